"""The lap joint's friction damping against a march in time, at one frequency and several
preloads: the harmonic balance at H = 5 and 9 (its truncation error estimated by their
difference) beside the march of :mod:`mmshbm.methods.shooting.pair_march` at N and 2N steps
per period (its time-step error), with processor times. The table of docs/interfaces.md:

    OPENBLAS_NUM_THREADS=1 python -m benchmarks.lap_joint_march 8 500 1000 2000 8000
    OPENBLAS_NUM_THREADS=1 python -m benchmarks.lap_joint_march 100 2000
    OPENBLAS_NUM_THREADS=1 python -m benchmarks.lap_joint_march 8 1000 --harmonics 9 64 129 --steps 1024 4096

(pairs, then the bolt's preloads in N, optionally the harmonics and the steps per period;
0.98 f_1, tip load 1 N, 1 % modal damping. Above 8 harmonics the start point is found from
the solution at half as many, :meth:`FrictionForcedProblem.start_point
<mmshbm.methods.mms.friction_forced.FrictionForcedProblem.start_point>`.)
"""

from __future__ import annotations

import sys
import time


def check(pairs: int, preload: float, harmonics=(5, 9), steps=(512, 1024), frequency_ratio: float = 0.98,
          modal_damping: float = 0.01) -> list[tuple]:
    """Rows (method, H or steps, tip amplitude (m), friction work per period (J), processor
    time (s), converged) at one preload."""
    import mmshbm
    from mmshbm.methods.mms.friction_forced import FrictionForcedProblem
    from mmshbm.methods.shooting.pair_march import march_pairs_to_steady

    joint = mmshbm.lap_joint(pairs, modal_damping=modal_damping, preload=preload)
    f = frequency_ratio * joint.bending_frequency
    rows = []
    for H in harmonics:
        t = time.process_time()
        problem = FrictionForcedProblem(joint.model, joint.force, harmonics=H)
        u = problem.start_point(f)
        rec = problem.monitor(u)
        rows.append(("HBM", H, rec["amplitude"], rec["friction_dissipation"], time.process_time() - t, True))
    for n in steps:
        t = time.process_time()
        orbit = march_pairs_to_steady(joint.model, joint.force, f, n)
        rows.append(("march", n, orbit.amplitude(0), orbit.work_friction, time.process_time() - t,
                     orbit.converged))
    return rows


def _split(argv: list[str]) -> dict[str, list[str]]:
    """Positional arguments under "", each ``--name`` option's values under its name."""
    out, key = {"": []}, ""
    for a in argv:
        if a.startswith("--"):
            key = a[2:]
            out[key] = []
        else:
            out[key].append(a)
    return out


def main(argv: list[str]) -> None:
    args = _split(argv)
    pos = args[""]
    pairs = int(pos[0]) if pos else 8
    preloads = [float(a) for a in pos[1:]] or [500.0, 2000.0, 8000.0]
    harmonics = tuple(int(a) for a in args.get("harmonics", ["5", "9"]))
    steps = tuple(int(a) for a in args.get("steps", ["512", "1024"]))
    print("| pairs | preload (N) | method | H / steps | tip amplitude (mm) | friction work (mJ) | time (s) |")
    print("|---:|---:|---|---:|---:|---:|---:|")
    for pre in preloads:
        for m, k, a, w, t, ok in check(pairs, pre, harmonics, steps):
            print(f"| {pairs} | {pre:g} | {m}{'' if ok else ' (not converged)'} | {k} | {1e3 * a:.5f} "
                  f"| {1e3 * w:.5f} | {t:.1f} |", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
