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

A package installed from a wheel built by the package's build step (``setup.py``) carries
its main job's kernels compiled, in Numba's in-tree cache (``__pycache__`` next to the
kernel files). Where ``NUMBA_CACHE_DIR`` sets another cache, the first kernel of a folder
that Numba looks up there copies that folder's carried kernels into it, each kernel whose
index is not there yet (an index already there, and its data, are left as they are); Numba
then loads them as any cached kernel, or compiles where they do not match its version, the
CPU or the sources. ``MMSHBM_KERNEL_SEED=0`` turns this off (to measure compilation with an
empty ``NUMBA_CACHE_DIR`` in a tree whose folders hold compiled kernels).

The hook uses ``numba.core.caching.CacheImpl._locator_classes``, the extension point that
Numba's own locators are registered in; where a Numba version lacks it, :func:`install`
returns False and kernels cache by their own file, as Numba does by default.
"""

from __future__ import annotations

import functools
import hashlib
import os
import shutil
import tempfile
from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parent

#: One place for the compilation flags of every kernel: cached, no GIL, fast math
#: without the flags that assume no NaN/inf (a NaN must propagate to Newton's checks).
#: A module that compiles kernels calls :func:`install` before its first ``njit``.
JIT_OPTIONS = dict(cache=True, nogil=True, fastmath={"nsz", "arcp", "contract", "afn"})


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


@functools.cache
def seed(source_dir: str, cache_dir: str) -> int:
    """Copy the kernels cached in ``source_dir/__pycache__`` (a wheel's, see the module's
    text) into ``cache_dir``, each whose index ``cache_dir`` lacks: its data files, then its
    index (each written under another name and renamed, so that a concurrent process sees
    it whole or not at all). Once per pair of folders and process; errors leave the rest to
    Numba. Returns the number of kernels copied."""
    if os.environ.get("MMSHBM_KERNEL_SEED", "").strip().lower() in ("0", "no", "false", "off"):
        return 0
    carried = Path(source_dir, "__pycache__")
    copied = 0
    try:
        indexes = sorted(carried.glob("*.nbi"))
        if not indexes or Path(cache_dir).resolve() == carried.resolve():
            return 0
        os.makedirs(cache_dir, exist_ok=True)
        for index in indexes:
            target = Path(cache_dir, index.name)
            if target.exists():
                continue
            for data in carried.glob(f"{index.stem}.*.nbc"):
                if not Path(cache_dir, data.name).exists():
                    _copy_whole(data, Path(cache_dir, data.name))
            _copy_whole(index, target)
            copied += 1
    except OSError:
        pass
    return copied


def _copy_whole(source: Path, target: Path) -> None:
    """Copy under another name, then rename: a reader sees the whole file or none."""
    fd, tmp = tempfile.mkstemp(dir=target.parent, suffix=".tmp")
    os.close(fd)
    try:
        shutil.copyfile(source, tmp)
        os.replace(tmp, target)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def _locator(base):
    class PackageLocator(base):
        """``base`` for this package's files, stamped with the kernel fingerprint too."""

        def get_source_stamp(self):
            return (super().get_source_stamp(), kernel_fingerprint())

        @classmethod
        def from_function(cls, py_func, py_file):
            if not _in_package(py_file):
                return None
            locator = super().from_function(py_func, py_file)
            if locator is not None and base.__name__ == "UserProvidedCacheLocator":
                seed(str(Path(py_file).resolve().parent), locator.get_cache_path())
            return locator

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


__all__ = ["JIT_OPTIONS", "install", "kernel_fingerprint", "seed"]
