"""The kernels' cache policy: a cached kernel is recompiled when a kernel it calls in
another file changes (Numba alone checks only the caller's file)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import mmshbm._kernel_cache as kc
from mmshbm.contact import unilateral


def test_package_kernels_use_the_package_locator():
    assert kc.install()
    impl = unilateral._proximal_contact._cache._impl
    assert type(impl.locator).__module__ == "mmshbm._kernel_cache"
    stamp = impl.locator.get_source_stamp()
    assert stamp[1] == kc.kernel_fingerprint()


def _run(package_root: Path, cache_dir: Path) -> str:
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache_dir), PYTHONPATH=str(package_root))
    code = "from probe.caller import f; print(f())"
    return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                          check=True, timeout=300).stdout.strip()


def test_editing_a_callee_in_another_file_recompiles_its_caller(tmp_path):
    pkg = tmp_path / "probe"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    shutil.copy(kc.__file__, pkg / "_kernel_cache.py")
    (pkg / "caller.py").write_text(textwrap.dedent("""
        from numba import njit
        from ._kernel_cache import install
        install()
        from .callee import g

        @njit(cache=True)
        def f():
            return g()
        """))
    callee = pkg / "callee.py"
    callee.write_text("from numba import njit\n\n@njit(cache=True)\ndef g():\n    return 1\n")
    cache = tmp_path / "cache"
    assert _run(tmp_path, cache) == "1"
    assert _run(tmp_path, cache) == "1"  # from the cache
    callee.write_text("from numba import njit\n\n@njit(cache=True)\ndef g():\n    return 2\n")
    assert _run(tmp_path, cache) == "2"  # Numba's own locator would answer 1 here


def test_an_in_tree_cache_serves_a_copy_of_the_package(tmp_path):
    """The build step's premise (setup.py): the kernels compiled into the built copy's
    ``__pycache__`` load, not compile, in the installed copy (other paths and mtimes), also
    where NUMBA_CACHE_DIR names an empty cache."""
    built = tmp_path / "built"
    pkg = built / "probe"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    shutil.copy(kc.__file__, pkg / "_kernel_cache.py")
    (pkg / "caller.py").write_text(textwrap.dedent("""
        from numba import njit
        from ._kernel_cache import install
        install()
        from .callee import g

        @njit(cache=True)
        def f():
            return g()
        """))
    (pkg / "callee.py").write_text("from numba import njit\n\n@njit(cache=True)\ndef g():\n    return 3\n")
    code = ("from probe.caller import f; print(f(), sum(f.stats.cache_misses.values()), "
            "sum(f.stats.cache_hits.values()))")

    def run(root, cache=None, **extra):
        env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "MMSHBM_KERNEL_SEED")}
        env.update(extra, PYTHONPATH=str(root))
        if cache is not None:
            env["NUMBA_CACHE_DIR"] = str(cache)
        return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                              check=True, timeout=300).stdout.split()

    assert run(built) == ["3", "1", "0"]  # compiled into probe/__pycache__
    installed = tmp_path / "installed"
    shutil.copytree(built, installed, copy_function=shutil.copy)  # new mtimes
    assert run(installed) == ["3", "0", "1"]  # loaded
    # another cache (NUMBA_CACHE_DIR) is seeded from the installed copy's
    assert run(installed, tmp_path / "user_cache") == ["3", "0", "1"]
    assert run(installed, tmp_path / "user_cache") == ["3", "0", "1"]
    assert run(installed, tmp_path / "unseeded", MMSHBM_KERNEL_SEED="0") == ["3", "1", "0"]


def test_precompile_runs_the_main_job(capsys):
    from mmshbm import _precompile

    assert _precompile.main() == 0
    assert "main job's kernels compiled into Numba's cache" in capsys.readouterr().out
