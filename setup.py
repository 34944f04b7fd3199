"""The build step: the wheel carries the main job's Numba kernels compiled for this machine.

The package's metadata is in ``pyproject.toml``; this file adds one step to ``build_py``:
after the package is copied to the build folder, ``python -m mmshbm._precompile`` runs on
that copy (its Numba in-tree cache is written next to the kernel files and goes into the
wheel), so that the first ``mmshbm backbone`` after ``pip install .`` loads its kernels
rather than compiling them. The step is best effort: where it fails (no Numba in the build
environment, a read-only build folder, a time-out) the build goes on without the cache and
the kernels compile at first use. ``MMSHBM_PRECOMPILE=0`` skips it.
"""

from __future__ import annotations

import os
import subprocess
import sys

from setuptools import setup
from setuptools.command.build_py import build_py

#: seconds the main job may take to compile in the build
TIMEOUT_S = 900


class BuildPyPrecompiled(build_py):
    """``build_py``, then the main job's kernels compiled into the built copy's cache."""

    def run(self):
        super().run()
        # an editable install runs the sources in place: their cache fills at first use
        skip = os.environ.get("MMSHBM_PRECOMPILE", "1").strip().lower() in ("0", "no", "false")
        if skip or self.dry_run or getattr(self, "editable_mode", False):
            return
        build_lib = os.path.abspath(self.build_lib)
        env = dict(os.environ)
        env.pop("NUMBA_CACHE_DIR", None)  # the in-tree cache, in the built copy
        env["NUMBA_DISABLE_JIT"] = "0"
        env["PYTHONPATH"] = os.pathsep.join(p for p in (build_lib, env.get("PYTHONPATH")) if p)
        env.setdefault("OPENBLAS_NUM_THREADS", "1")
        try:
            subprocess.run([sys.executable, "-m", "mmshbm._precompile"], cwd=build_lib, env=env, check=True,
                           timeout=TIMEOUT_S)
        except (OSError, subprocess.SubprocessError) as err:
            print(f"mmshbm build: kernels not compiled ahead ({err}); they compile at first use",
                  file=sys.stderr)


setup(cmdclass={"build_py": BuildPyPrecompiled})
