"""Compile the kernels of the main job (``mmshbm backbone``: the default beam, 21 elements,
H = 5, and the truncation estimate it prints) into Numba's cache, by running that job once.

The package's build step (``setup.py``) runs ``python -m mmshbm._precompile`` on the built
copy of the package, so that the wheel carries these kernels compiled (Numba's in-tree
cache, ``__pycache__/*.nbi, *.nbc`` next to the kernel files) and the first
``mmshbm backbone`` after ``pip install .`` loads them instead of compiling them.

Numba uses a cached kernel only where it was made by the same Numba version, for the same
CPU (name and features), from the same source text (:mod:`mmshbm._kernel_cache`); a wheel
installed elsewhere, or with another Numba than its build environment had, compiles its
kernels at first use as without this step. Numba looks for its cache in ``NUMBA_CACHE_DIR``
when that is set, and in the package's folder only when it is writable: there too the
kernels compile at first use.

``python -m mmshbm._precompile`` can also be run after an installation, to compile the
main job's kernels ahead of the first run into whatever cache Numba uses.
"""

from __future__ import annotations

import sys
import time
import warnings


def main() -> int:
    """Run the main job's backbone (results discarded); prints what it took."""
    t0 = time.perf_counter()
    from .fe.beam import default_beam
    from .methods.backbone import backbone

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        branch = backbone(default_beam().model(21), harmonics=5)
        branch.truncation_error(float(branch.amplitude[branch.family_front()].max()))  # printed by the CLI
    print(f"mmshbm: main job's kernels compiled into Numba's cache ({len(branch)} points, "
          f"{time.perf_counter() - t0:.1f} s)")
    return 0


if __name__ == "__main__":  # pragma: no cover - run by the build step
    sys.exit(main())
