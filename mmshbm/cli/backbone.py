"""``mmshbm backbone``."""

from __future__ import annotations

from pathlib import Path

from . import common


def register(sub) -> None:
    """Add the subcommand to the subparsers ``sub``."""
    p = sub.add_parser("backbone", help="first nonlinear mode: backbone.csv/.npz/.png")
    common.beam_options(p)
    p.add_argument("-H", "--harmonics", type=common.positive_int, default=5, help="harmonics H (default 5)")
    p.add_argument("--method", default="mmshbm", choices=["mmshbm", "penalty", "shooting"],
                   help="MMS-HBM, or a baseline: penalty harmonic balance or time-domain shooting (exit "
                        "code 1 when a baseline's branch turns into another family)")
    p.add_argument("--max-amplitude", type=common.positive_float, default=None,
                   help="largest amplitude, in gaps (default 10)")
    p.add_argument("--max-steps", type=common.positive_int, default=None,
                   help="continuation step budget (default 1000); a run that uses it up exits 1")
    common.measured_option(p)
    p.add_argument("--checkpoint", default=None, metavar="FILE",
                   help="write converged points to FILE as they go")
    p.add_argument("--resume", default=None, metavar="FILE", help="continue from a checkpoint FILE")
    p.add_argument("--follow", default="family", choices=["family", "path"],
                   help="'family' (default): the first mode's backbone, jumping internal-resonance "
                        "tongues; 'path': plain path following (to study a tongue)")
    p.add_argument("--proximal", default="static", choices=["static", "residual"],
                   help="MMS-HBM's proximal parameter r: 'static' (default) the contact DOFs' static "
                        "stiffness; 'residual' the compliance of the modes above the truncation frequency, "
                        "smaller truncation errors with stiff stops (docs/exact.md)")
    p.set_defaults(func=run)


def run(args) -> int:
    from ._plot_worker import PlotWorker

    with PlotWorker() as worker:  # imports matplotlib in a child while this process computes
        return _run(args, worker)


def _run(args, worker) -> int:
    from ..methods.backbone import backbone
    from ..plotting.data import BranchData, reference_frequencies

    measured = common.measured(args)
    model = common.model(args)
    max_amp = gaps_in_m(10.0 if args.max_amplitude is None else args.max_amplitude, model)
    extra = {}
    if args.checkpoint:
        Path(args.checkpoint).parent.mkdir(parents=True, exist_ok=True)
        extra["checkpoint"] = args.checkpoint
    if args.resume:
        extra["resume"] = args.resume
    if args.max_steps is not None:
        extra["max_steps"] = args.max_steps
    if args.follow != "family":
        extra["follow"] = args.follow
    if args.proximal != "static":
        if args.method != "mmshbm":
            raise ValueError(f"--proximal {args.proximal} applies to --method mmshbm, not {args.method}")
        extra["r"] = args.proximal
    branch = backbone(model, harmonics=args.harmonics, method=args.method, max_amplitude=max_amp,
                      verbose=common.progress(args), **extra)
    out = common.out_dir(args)
    files = [branch.to_csv(out / "backbone.csv"), branch.save(out / "backbone.npz")]
    if len(branch):
        files += [out / "backbone.png", out / "frequency_energy.png"]
        data = BranchData.of(branch)
        worker.draw([("plot_backbone", (data,), {"measured": measured, "model": reference_frequencies(model),
                                                 "path": files[-2]}),
                     ("plot_frequency_energy", (data,), {"path": files[-1]})])
    print(repr(branch))
    for line in _special_lines(branch, model.gap):
        print(line)
    common.wrote(*files)
    code = common.exit_code([branch])
    if args.method != "mmshbm" and _another_family(branch, model.gap):
        code = 1
    return code


def gaps_in_m(gaps: float, model, option: str = "--max-amplitude") -> float:
    """``gaps`` (the value of ``option``, in gaps) in m; ValueError naming the option when
    the model has no positive gap to measure it in."""
    if not model.gap > 0:
        raise ValueError(f"{option} is in gaps, and this model has no stop with a positive gap to measure it "
                         "in: give the model a stop with gap > 0, or call mmshbm.backbone(model, "
                         "max_amplitude=...) in m from Python")
    return float(gaps) * model.gap


def _another_family(branch, gap: float) -> bool:
    """Whether a baseline's branch ends on another family than its starting mode's (its
    family front stops short of the branch's reach); says so on stderr."""
    import sys

    if not len(branch):
        return False
    front = branch.family_front()
    top = float(branch.amplitude.max())
    if len(front) and float(branch.amplitude[front].max()) >= top * (1 - 1e-9):
        return False
    end = int(front[-1]) if len(front) else 0

    def amp(a):
        return f"{a / gap:.3g} gaps" if gap > 0 else f"{a:.3g} m"

    print(f"mmshbm backbone: {branch.method} branch: the backbone of linear mode 1 ends at "
          f"{amp(branch.amplitude[end])} ({branch.frequency[end]:.4g} Hz); up to {amp(top)} the branch is "
          "another family of motions, not that mode's backbone (exit code 1)", file=sys.stderr)
    return True


def _special_lines(branch, gap: float) -> list[str]:
    """The internal resonances the branch met and the jumps it made, one line each kind."""
    from ..plotting.data import resonance_label, resonances_met

    def amp(a):
        return f"{a / gap:.3g} gaps" if gap > 0 else f"{a:.3g} m"

    res, jumps, seen = [], [], set()
    met = {id(sp) for sp in resonances_met(branch)}
    for sp in branch.special_points:
        d = getattr(sp, "data", {}) or {}
        if id(sp) in met and (d.get("k"), d.get("j")) not in seen:
            seen.add((d.get("k"), d.get("j")))
            i = int(sp[1])
            res.append(f"{resonance_label(d['k'], d['j'])} at {amp(branch.amplitude[i])} "
                       f"({branch.frequency[i]:.4g} Hz)")
        elif sp[0] == "jump" and "amplitude_frontier" in d:
            lo, hi = d["amplitude_frontier"], d["amplitude_to"]
            span = amp(lo) if hi <= lo * 1.001 else f"{amp(lo)}..{amp(hi)}"
            jumps.append(f"{span} ({d.get('frequency_to', float('nan')):.4g} Hz after)")
    out = []
    if res:
        out.append("internal resonances: " + ", ".join(res))
    if jumps:
        out.append("jumps over tongues: " + ", ".join(jumps))
    return out
