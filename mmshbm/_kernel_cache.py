"""The on-disk cache policy of the package's Numba kernels: a cached kernel is stale when
any kernel source of the package changes, not only its own file.

Numba checks a cached kernel against the file that defines it alone, so a kernel that calls
a kernel of another file would run stale machine code after that callee is edited. Instead
of copying callees into every file that calls them, the package registers cache locators
(Numba's own in-tree and ``NUMBA_CACHE_DIR`` locators, for files of this package only) whose
source stamp is the file's own stamp together with one fingerprint of every module of the
package that compiles kernels (the modules whose text has ``njit``). Kernels may then call
kernels of other files; editing any kernel file recompiles all of them at the next run.
Installed copies never change, so the fingerprint is computed once per process (a few ms,
only when a kernel is first taken from the cache).

The hook uses ``numba.core.caching.CacheImpl._locator_classes``, the extension point that
Numba's own locators are registered in; where a Numba version lacks it, :func:`install`
returns False and kernels cache by their own file, as Numba does by default.
"""

from __future__ import annotations

import functools
import hashlib
from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parent


@functools.lru_cache(maxsize=1)
def kernel_fingerprint() -> bytes:
    """SHA-256 over the sources of every package module that compiles kernels (whose text
    has ``njit``), in sorted path order."""
    digest = hashlib.sha256()
    for path in sorted(PACKAGE_DIR.rglob("*.py")):
        text = path.read_bytes()
        if b"njit" in text:
            digest.update(str(path.relative_to(PACKAGE_DIR)).encode())
            digest.update(text)
    return digest.digest()


def _in_package(py_file: str) -> bool:
    try:
        return Path(py_file).resolve().is_relative_to(PACKAGE_DIR)
    except (OSError, ValueError):
        return False


def _locator(base):
    class PackageLocator(base):
        """``base`` for this package's files, stamped with the kernel fingerprint too."""

        def get_source_stamp(self):
            return (super().get_source_stamp(), kernel_fingerprint())

        @classmethod
        def from_function(cls, py_func, py_file):
            if not _in_package(py_file):
                return None
            return super().from_function(py_func, py_file)

    PackageLocator.__name__ = PackageLocator.__qualname__ = f"Package{base.__name__}"
    return PackageLocator


def install() -> bool:
    """Register the package's locators ahead of Numba's (idempotent). False where this Numba
    has no locator registry (kernels then cache by their own file only)."""
    try:
        from numba.core import caching
    except ImportError:  # pragma: no cover - numba is a dependency
        return False
    registry = getattr(getattr(caching, "CacheImpl", None), "_locator_classes", None)
    bases = [getattr(caching, name, None) for name in ("UserProvidedCacheLocator", "InTreeCacheLocator")]
    if not isinstance(registry, list) or None in bases:
        return False
    if any(getattr(c, "__module__", None) == __name__ for c in registry):
        return True
    registry[:0] = [_locator(base) for base in bases]
    return True


__all__ = ["install", "kernel_fingerprint"]
