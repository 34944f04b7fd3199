"""Before/after figures of two source trees, measured alternately in one script.

Each figure runs in a fresh subprocess per tree (``PYTHONPATH=<tree>``), the trees
alternating, ``--rounds`` times; the table shows the fastest wall-clock and CPU time of
each (the CPU time of the process is less sensitive to other load on a shared machine).
Numba kernels are compiled (or loaded from each tree's cache) before any timed call.

    python benchmarks/before_after.py --before /path/to/old/tree --after . --rounds 2
    python benchmarks/before_after.py ... --only forced     # one group

Groups: ``forced`` (damped beam: 0.5 % on mode 1, 5 % on the modes above, or on modes
2..N+1 only with ``--damped-modes N``; 5 N, 40–62 Hz, H = 5..40), ``epmc`` (H = 20, default
budget), ``scale`` (whole backbone after the reduction, 21/1000/10 000 elements, 1.9 and 2
gaps), ``main`` (the default backbone to 10 gaps, warm), ``process`` (the whole
``python -m mmshbm backbone`` process, warm: wall and CPU time of the process and its
children, the plot worker included).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

PRELUDE = """
import json, time, warnings
import numpy as np
import mmshbm
warnings.simplefilter("ignore")

def clock(f, repeat):
    best = (float("inf"), float("inf"))
    out = None
    for _ in range(repeat):
        t, c = time.perf_counter(), time.process_time()
        out = f()
        best = (min(best[0], time.perf_counter() - t), min(best[1], time.process_time() - c))
    return best, out

def damped_beam():
    m = mmshbm.default_beam().model(21)
    return m.with_damping(modal_ratio=[0.005] + [0.05] * ({higher} if {higher} else len(m.l) - 1))
"""

JOBS = {
    "forced": """
m = damped_beam()
F = np.zeros(m.n_dof); F[38] = 5.0
mmshbm.frequency_response(m, F, (40.0, 41.0), harmonics=3)
(w, c), r = clock(lambda: mmshbm.frequency_response(m, F, (40.0, 62.0), harmonics={H}), {repeat})
print(json.dumps({{"wall": w, "cpu": c, "points": len(r), "end_hz": float(r.frequency[-1]),
                  "peak_gaps": float(r.amplitude.max() / m.gap)}}))
""",
    "epmc": """
m = damped_beam()
mmshbm.backbone(m, harmonics=3, max_amplitude=1.5e-3)
(w, c), b = clock(lambda: mmshbm.backbone(m, harmonics=20), 1)
print(json.dumps({{"wall": w, "cpu": c, "points": len(b), "status": b.status,
                  "max_gaps": float(b.amplitude.max() / m.gap)}}))
""",
    "scale": """
m = mmshbm.default_beam().model({elements})
mmshbm.backbone(m, harmonics=5, max_amplitude={gaps} * m.gap)
(w, c), b = clock(lambda: mmshbm.backbone(m, harmonics=5, max_amplitude={gaps} * m.gap), 15)
print(json.dumps({{"wall": w, "cpu": c, "points": len(b), "status": b.status}}))
""",
    "process": """
import os, resource, subprocess, sys, tempfile
out = tempfile.mkdtemp()
cmd = [sys.executable, "-m", "mmshbm", "backbone", "--out", out]
subprocess.run(cmd, check=True, capture_output=True)
walls, cpus = [], []
for _ in range({repeat}):
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True)
    walls.append(time.perf_counter() - t)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpus.append(r1.ru_utime + r1.ru_stime - r0.ru_utime - r0.ru_stime)
print(json.dumps({{"wall": min(walls), "cpu": min(cpus), "median_wall": sorted(walls)[len(walls) // 2]}}))
""",
    "main": """
m = mmshbm.default_beam().model(21)
mmshbm.backbone(m, harmonics=5, max_amplitude=10 * m.gap)
(w, c), b = clock(lambda: mmshbm.backbone(m, harmonics=5, max_amplitude=10 * m.gap), 30)
print(json.dumps({{"wall": w, "cpu": c, "points": len(b), "status": b.status}}))
""",
}


#: forced responses: harmonics; damped beam: modes above the first with 5 % (0: all)
FORCED_H = (5, 10, 20, 30, 40)
HIGHER = 0


def cases(only, harmonics=FORCED_H):
    out = []
    if only in (None, "main"):
        out.append(("main", "default backbone to 10 gaps", {}))
    if only in (None, "process"):
        out.append(("process", "whole mmshbm backbone process, warm", {"repeat": 5}))
    if only in (None, "scale"):
        for gaps in (1.9, 2.0):
            for elements in (21, 1000, 10000):
                out.append(("scale", f"backbone {elements} el. to {gaps} gaps",
                            {"elements": elements, "gaps": gaps}))
    if only in (None, "epmc"):
        out.append(("epmc", "EPMC H = 20, default budget", {}))
    if only in (None, "forced"):
        for H in harmonics:
            out.append(("forced", f"forced response H = {H}", {"H": H, "repeat": 2 if H < 40 else 1}))
    return out


def run(tree: str, job: str, params: dict, timeout: float) -> dict:
    env = dict(os.environ, PYTHONPATH=os.path.abspath(tree))
    code = PRELUDE.format(higher=HIGHER) + JOBS[job].format(**params)
    try:
        p = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                           timeout=timeout, cwd="/tmp")
    except subprocess.TimeoutExpired:
        return {"error": f"timeout {timeout:.0f} s"}
    if p.returncode:
        return {"error": p.stderr.strip().splitlines()[-1] if p.stderr.strip() else f"rc {p.returncode}"}
    return json.loads(p.stdout.strip().splitlines()[-1])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", required=True)
    ap.add_argument("--after", required=True)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--only", choices=sorted(JOBS))
    ap.add_argument("--timeout", type=float, default=600.0)
    ap.add_argument("--damped-modes", type=int, default=0,
                    help="damped beam: 5 %% on modes 2..N+1 only (0: on every mode above the first)")
    ap.add_argument("--harmonics", type=int, nargs="+", default=list(FORCED_H))
    args = ap.parse_args(argv)
    global HIGHER
    HIGHER = args.damped_modes
    for job, label, params in cases(args.only, args.harmonics):
        best = {}
        for _ in range(args.rounds):
            for name, tree in (("before", args.before), ("after", args.after)):
                res = run(tree, job, params, args.timeout)
                prev = best.get(name)
                if prev is None or "error" in prev or ("wall" in res and res["wall"] < prev["wall"]):
                    if prev is not None and "wall" in res and "cpu" in prev:
                        res["cpu"] = min(res["cpu"], prev["cpu"])
                    best[name] = res
        b, a = best["before"], best["after"]
        extra = {k: (b.get(k), a.get(k)) for k in a if k not in ("wall", "cpu")}
        if "wall" in b and "wall" in a:
            print(f"{label}: wall {b['wall']:.4g} -> {a['wall']:.4g} s ({b['wall'] / a['wall']:.2f}x), "
                  f"cpu {b['cpu']:.4g} -> {a['cpu']:.4g} s ({b['cpu'] / a['cpu']:.2f}x); {extra}", flush=True)
        else:
            print(f"{label}: before {b}, after {a}", flush=True)


if __name__ == "__main__":
    main()
