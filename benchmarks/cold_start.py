"""The first ``mmshbm backbone`` after ``pip install .``, and the second, for two source
trees measured alternately in one script.

Each tree is built into a wheel once (``pip wheel --no-deps``, in pip's isolated build
environment as ``pip install .`` builds it), installed with ``pip install --no-deps
--target`` into a folder; every round copies that installation afresh (as installed: no
kernel cache beyond what the wheel carries) and times, in that copy, ``python -m mmshbm
backbone`` twice: the first run (a fresh install: kernels loaded from the wheel's cache or
compiled) and the second (warm). ``NUMBA_CACHE_DIR`` is unset for both (Numba's in-tree
cache, in the installation), the dependencies are this interpreter's.

    python benchmarks/cold_start.py --before /path/to/old/tree --after . --rounds 3

Also, with ``--empty-cache``, a first run with ``NUMBA_CACHE_DIR`` an empty folder (every
kernel compiles whatever the wheel carries).
"""

from __future__ import annotations

import argparse
import glob
import os
import shutil
import subprocess
import sys
import tempfile
import time


def _install(tree: str, where: str) -> str:
    wheels = os.path.join(where, "wheel")
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", wheels, tree], check=True)
    target = os.path.join(where, "installed")
    wheel = glob.glob(os.path.join(wheels, "*.whl"))[0]
    subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--target", target, wheel],
                   check=True)
    return target


def _run(root: str, out: str, cache: str | None = None) -> float:
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "PYTHONPATH")}
    env.update(PYTHONPATH=root, MPLBACKEND="Agg")
    env.setdefault("OPENBLAS_NUM_THREADS", "1")
    if cache is not None:
        env["NUMBA_CACHE_DIR"] = cache
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "mmshbm", "backbone", "--out", out], env=env, check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=out)
    return time.perf_counter() - t0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--before", required=True)
    p.add_argument("--after", required=True)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--empty-cache", action="store_true",
                   help="also a first run with an empty NUMBA_CACHE_DIR")
    ns = p.parse_args(argv)
    trees = {"before": os.path.abspath(ns.before), "after": os.path.abspath(ns.after)}
    times = {(t, k): [] for t in trees for k in ("first", "second", "empty cache")}
    with tempfile.TemporaryDirectory() as tmp:
        installed = {}
        for name, tree in trees.items():
            t0 = time.perf_counter()
            installed[name] = _install(tree, os.path.join(tmp, name))
            print(f"{name}: wheel built and installed in {time.perf_counter() - t0:.1f} s", flush=True)
        for r in range(ns.rounds):
            for name in trees:
                root = os.path.join(tmp, f"{name}-{r}")
                shutil.copytree(installed[name], root)
                out = os.path.join(tmp, f"out-{name}-{r}")
                os.makedirs(out)
                times[name, "first"].append(_run(root, out))
                times[name, "second"].append(_run(root, out))
                if ns.empty_cache:
                    times[name, "empty cache"].append(_run(root, out, os.path.join(tmp, f"numba-{name}-{r}")))
                shutil.rmtree(root)
            last = ", ".join(f"{t} {k} {v[-1]:.2f} s" for (t, k), v in times.items() if v)
            print(f"round {r + 1}: {last}", flush=True)
    print(f"\n{'mmshbm backbone (s, fastest / slowest)':40s} {'before':>14s} {'after':>14s}")
    for kind in ("first", "second", "empty cache"):
        if times["before", kind]:
            cols = " ".join(f"{min(times[t, kind]):6.2f} / {max(times[t, kind]):5.2f}" for t in trees)
            print(f"{kind + (' (fresh install)' if kind == 'first' else ''):40s} {cols}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
