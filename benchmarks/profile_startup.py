"""Where the time of ``mmshbm backbone`` goes, as a whole process (not an asv suite: asv
tracks the totals in ``bench_goals.py``; this script breaks them down).

    python benchmarks/profile_startup.py            # warm: Numba's on-disk cache in place
    python benchmarks/profile_startup.py --cold     # a fresh NUMBA_CACHE_DIR: every kernel compiles
                                                    # (not seeded: MMSHBM_KERNEL_SEED=0)
    python benchmarks/profile_startup.py --repeat 5 --args -H 3 --elements 8

It prints

* the wall time of the whole ``mmshbm backbone`` process (fastest and median of
  ``--repeat`` runs, in a temporary output folder);
* the phases of one instrumented run in a child process: imports, model, Numba (its
  first dispatch initialises the CPU target: ~0.2 s even from the cache), each kernel's
  compilation or cache load (exclusive of the kernels it calls; a kernel that appears
  twice was compiled for two signatures), the continuation itself, the branch checks,
  the files and the figures (drawn in this child, as ``MMSHBM_PLOT_WORKER=0`` does).

Run it with ``OPENBLAS_NUM_THREADS=1`` on a shared machine. Timings are wall clock.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time


def whole_process(args: list[str], repeat: int, cold: bool, env: dict | None = None,
                  seed: bool = False) -> list[float]:
    """Wall times (s) of ``repeat`` runs of ``mmshbm backbone ARGS`` (each with a fresh
    NUMBA_CACHE_DIR when ``cold``: every kernel compiles, or with ``seed`` it is seeded
    from the kernels the package's folders hold compiled, as after an installation)."""
    times = []
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(repeat):
            run_env = dict(os.environ if env is None else env)
            if cold:
                run_env["NUMBA_CACHE_DIR"] = os.path.join(tmp, f"numba{i}")
                if not seed:  # not from the kernels the package's folders hold compiled
                    run_env["MMSHBM_KERNEL_SEED"] = "0"
            t0 = time.perf_counter()
            command = [sys.executable, "-m", "mmshbm", "backbone", "--out", os.path.join(tmp, "out"), *args]
            subprocess.run(command, env=run_env, check=False, stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL)
            times.append(time.perf_counter() - t0)
    return times


#: the LLVM phases of a Numba kernel's library: optimising its own functions; optimising the
#: module once its callees are linked in (callees are optimised again, inlined, in every
#: caller); emitting machine code for that linked module
_LLVM_PHASES = ("_optimize_functions", "_optimize_final_module", "_finalize_final_module")


def _time_llvm() -> dict:
    """Time the LLVM phases of every kernel compiled from now on: {kernel name: {phase: s}}
    (empty where this Numba's code library lacks those methods)."""
    import collections

    from numba.core import codegen

    library = getattr(codegen, "CPUCodeLibrary", None)
    times = collections.defaultdict(dict)
    if library is None or not all(hasattr(library, m) for m in _LLVM_PHASES):
        return times

    def timer(phase):
        orig = getattr(library, phase)

        def timed(self, *a, **k):
            t0 = time.perf_counter()
            try:
                return orig(self, *a, **k)
            finally:
                # a library is named after its function (Numba's own helpers: 'nrt', ...)
                name = self.name.split("$")[0].split("[")[0].rsplit(".", 1)[-1]
                times[name][phase] = times[name].get(phase, 0.0) + time.perf_counter() - t0

        return timed

    for phase in _LLVM_PHASES:
        setattr(library, phase, timer(phase))
    return times


def _child(args: list[str], out: str) -> None:
    """One instrumented ``mmshbm backbone`` (the steps of cli/backbone.py), phases printed."""
    t_start = time.perf_counter()
    marks = []

    def mark(name):
        marks.append((name, time.perf_counter()))

    import mmshbm.cli as cli
    from mmshbm.cli import common

    mark("import mmshbm.cli (argparse, numpy)")
    parsed = cli.build_parser().parse_args(["backbone", "--out", out, *args])
    from mmshbm.methods.backbone import backbone

    mark("import mmshbm.methods.backbone (scipy)")
    model = common.model(parsed)
    mark("model")
    import numba  # noqa: F401
    from numba.core.dispatcher import Dispatcher

    mark("import numba")
    from numba.core.registry import cpu_target

    cpu_target.typing_context.refresh()  # what the first dispatch (even from the cache) does
    cpu_target.target_context.refresh()
    mark("Numba CPU target initialisation (typing and lowering registries)")
    kernels, stack = [], []
    compile_ = Dispatcher.compile

    def timed(self, sig):
        stack.append(0.0)
        t0 = time.perf_counter()
        try:
            return compile_(self, sig)
        finally:
            inclusive = time.perf_counter() - t0
            inner = stack.pop()
            if stack:
                stack[-1] += inclusive
            name = f"{self.py_func.__module__}.{self.py_func.__name__}"
            kernels.append((name, inclusive - inner, inclusive))

    Dispatcher.compile = timed
    llvm = _time_llvm()
    from mmshbm.results import diagnostics

    check_time = []
    check = diagnostics.check_branch

    def timed_check(*a, **k):
        t0 = time.perf_counter()
        try:
            return check(*a, **k)
        finally:
            check_time.append(time.perf_counter() - t0)

    diagnostics.check_branch = timed_check
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = time.perf_counter()
        branch = backbone(model, harmonics=parsed.harmonics, method=parsed.method)
        t_backbone = time.perf_counter() - t0
    mark("backbone (below: its parts)")
    from pathlib import Path

    path = Path(out)
    path.mkdir(parents=True, exist_ok=True)
    branch.to_csv(path / "backbone.csv")
    branch.save(path / "backbone.npz")
    mark("files (csv, npz)")
    from mmshbm.plotting import backbones as plots

    mark("import matplotlib and the plots")
    plots.plot_backbone(branch, model=model, path=path / "backbone.png")
    mark("figure: backbone.png")
    plots.plot_frequency_energy(branch, path=path / "frequency_energy.png")
    mark("figure: frequency_energy.png")

    print(f"{'phase':66s} {'ms':>8s}")
    last = t_start
    for name, t in marks:
        print(f"{name:66s} {1e3 * (t - last):8.1f}")
        last = t
    print(f"{'total in process':66s} {1e3 * (last - t_start):8.1f}")
    compile_total = sum(k[1] for k in kernels)
    continuation = branch.metadata.get("elapsed_s", float("nan"))
    print(f"\nbackbone {1e3 * t_backbone:.1f} ms = kernels compiled or loaded {1e3 * compile_total:.1f} ms"
          f" + checks {1e3 * sum(check_time):.1f} ms + the rest (problem set-up, continuation: "
          f"{1e3 * (t_backbone - compile_total - sum(check_time)):.1f} ms); metadata elapsed_s "
          f"{1e3 * continuation:.1f} ms (continuation incl. its kernel loads)")
    print(f"branch: {len(branch)} points, status {branch.status}")
    print(f"\n{'kernel (exclusive of the kernels it calls)':56s} {'ms':>8s} {'incl.':>8s} "
          f"{'LLVM opt':>9s} {'linked':>7s} {'emit':>7s}")
    for name, excl, incl in sorted(kernels, key=lambda k: -k[1]):
        if excl >= 0.5e-3:
            parts = llvm.get(name.rsplit(".", 1)[-1], {})
            widths = zip(_LLVM_PHASES, (9, 7, 7), strict=True)
            cols = " ".join(f"{1e3 * parts.get(m, 0.0):{w}.1f}" for m, w in widths)
            print(f"{name:56s} {1e3 * excl:8.1f} {1e3 * incl:8.1f} {cols}")
    if llvm:
        total = {m: sum(p.get(m, 0.0) for p in llvm.values()) for m in _LLVM_PHASES}
        print(f"LLVM (part of the exclusive times): its own functions {1e3 * total[_LLVM_PHASES[0]]:.0f} ms, "
              f"the module linked with its callees (which it optimises again) "
              f"{1e3 * total[_LLVM_PHASES[1]]:.0f} ms, machine code {1e3 * total[_LLVM_PHASES[2]]:.0f} ms; "
              "the rest is Numba's typing and lowering")
    small = [k for k in kernels if k[1] < 0.5e-3]
    if small:
        print(f"({len(small)} dispatches below 0.5 ms: type resolution of kernels already loaded)")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cold", action="store_true", help="fresh NUMBA_CACHE_DIR (every kernel compiles)")
    p.add_argument("--repeat", type=int, default=3, help="whole-process runs (default 3)")
    p.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--out", default=None, help=argparse.SUPPRESS)
    p.add_argument("--args", nargs=argparse.REMAINDER, default=[], help="further mmshbm backbone options")
    ns = p.parse_args(argv)
    if ns.child:
        _child(ns.args, ns.out)
        return 0
    env = dict(os.environ)
    env.setdefault("OPENBLAS_NUM_THREADS", "1")
    times = whole_process(ns.args, ns.repeat, ns.cold, env)
    kind = "cold (fresh Numba cache)" if ns.cold else "warm (Numba cache in place)"
    print(f"mmshbm backbone {' '.join(ns.args)} whole process, {kind}: fastest {min(times):.2f} s, "
          f"median {statistics.median(times):.2f} s over {len(times)} runs\n")
    with tempfile.TemporaryDirectory() as tmp:
        child_env = dict(env)
        if ns.cold:
            child_env["NUMBA_CACHE_DIR"] = os.path.join(tmp, "numba")
            child_env["MMSHBM_KERNEL_SEED"] = "0"
        command = [sys.executable, __file__, "--child", "--out", os.path.join(tmp, "out"), "--args", *ns.args]
        subprocess.run(command, env=child_env, check=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
