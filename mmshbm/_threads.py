"""BLAS threads for the package's linear algebra: one thread unless the user says otherwise.

The continuation solves small dense systems (the bordered Newton system, condensed
stiffness blocks, modal projections) thousands of times; multithreaded BLAS starts and
synchronises its threads for each of them and, on a shared machine, competes with the
other processes. Measured on the project's 2-core machine (OpenBLAS, 2 threads by
default), whole backbones with the continuation on one BLAS thread against the default:
default beam (21 elements) MMS-HBM to 10 gaps 1.9× faster, penalty-HBM 1.2×, shooting
1.35×; 1000 elements MMS-HBM 1.65×, penalty-HBM (H = 5, sparse) 4.3×.

:func:`blas_limit` is the context manager that ``mmshbm.backbone`` runs the continuation
in. It does nothing when the user chose the BLAS threads (``OPENBLAS_NUM_THREADS``,
``MKL_NUM_THREADS``, ``OMP_NUM_THREADS``, ``BLIS_NUM_THREADS`` or ``MMSHBM_BLAS_THREADS``
set; the last one sets the package's limit, e.g. ``MMSHBM_BLAS_THREADS=2``) or when
threadpoolctl is not installed. The ``mmshbm`` program sets ``OPENBLAS_NUM_THREADS`` (and
the others) to 1 before numpy loads, unless they are set (:func:`single_thread_env`).
"""

from __future__ import annotations

import contextlib
import os

__all__ = ["blas_limit", "user_chose", "single_thread_env", "BLAS_ENV"]

#: environment variables that set the threads of the BLAS libraries numpy/scipy load
BLAS_ENV = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS", "BLIS_NUM_THREADS")

#: the BLAS libraries' threadpoolctl controllers (None until the first blas_limit)
_controller = None


def user_chose() -> bool:
    """True when the environment sets the BLAS threads (the package then leaves them)."""
    return any(os.environ.get(name, "").strip() for name in BLAS_ENV)


def _limit() -> int | None:
    value = os.environ.get("MMSHBM_BLAS_THREADS", "").strip()
    if value:
        try:
            n = int(value)
        except ValueError:
            raise ValueError(f"MMSHBM_BLAS_THREADS must be a positive integer, got {value!r}") from None
        if n < 1:
            raise ValueError(f"MMSHBM_BLAS_THREADS must be a positive integer, got {value!r}")
        return n
    return None if user_chose() else 1


def blas_limit():
    """A context manager that runs its block with the package's BLAS thread limit (one
    thread by default, see the module docstring); a no-op when the user chose the threads
    or threadpoolctl is missing. Entering and leaving costs a few µs."""
    global _controller
    n = _limit()
    if n is None:
        return contextlib.nullcontext()
    if _controller is None:
        try:
            import scipy.linalg  # noqa: F401  (its BLAS library loaded before the controller looks)
            from threadpoolctl import ThreadpoolController
        except ImportError:  # pragma: no cover - threadpoolctl is a dependency
            return contextlib.nullcontext()
        # the BLAS libraries' own controllers: set and restored directly (threadpoolctl's
        # limit() selects and describes them on every call)
        _controller = [lc for lc in ThreadpoolController().lib_controllers if lc.user_api == "blas"]
    return _Limit(_controller, n)


class _Limit:
    """Sets each BLAS library's threads to ``n`` on entering (where they differ) and
    restores them on leaving."""

    __slots__ = ("libs", "n", "before")

    def __init__(self, libs, n: int):
        self.libs, self.n, self.before = libs, n, []

    def __enter__(self):
        self.before = [(lc, lc.get_num_threads()) for lc in self.libs]
        for lc, threads in self.before:
            if threads != self.n:
                lc.set_num_threads(self.n)
        return self

    def __exit__(self, *exc):
        for lc, threads in self.before:
            if threads != self.n:
                lc.set_num_threads(threads)
        return False


def single_thread_env() -> None:
    """Set the BLAS thread variables to 1 unless the user set one (the ``mmshbm``
    program, before numpy is imported: then no BLAS thread pool is ever started)."""
    if not user_chose() and not os.environ.get("MMSHBM_BLAS_THREADS", "").strip():
        for name in BLAS_ENV:
            os.environ[name] = "1"
