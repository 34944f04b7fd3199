"""``mmshbm backbone``."""

from __future__ import annotations

import contextlib
import math
import sys
import warnings
from pathlib import Path

from .._method_info import backbone_methods, method_info
from . import common


def register(sub) -> None:
    """Add the subcommand to the subparsers ``sub``."""
    p = sub.add_parser("backbone", help="first nonlinear mode: backbone.csv/.npz/.png")
    common.beam_options(p)
    p.add_argument("-H", "--harmonics", type=common.positive_int, default=None,
                   help="harmonics H (default 5); not with --tol")
    p.add_argument("--tol", type=common.positive_float, default=None,
                   help="relative tolerance on the frequency of every point: H chosen per point from an "
                        "error estimate (docs/accuracy.md) instead of a fixed -H")
    p.add_argument("--max-harmonics", type=common.positive_int, default=None,
                   help="with --tol: the largest H of any solve (default 64)")
    p.add_argument("--method", default="mmshbm", choices=backbone_methods(),
                   help="MMS-HBM, or a baseline: penalty harmonic balance (full or reduced) or time-domain "
                        "shooting (exit code 1 when a baseline's branch turns into another family)")
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

    with PlotWorker() as worker, _branch_warnings() as caught:  # matplotlib loads in a child meanwhile
        return _run(args, worker, caught)


def _run(args, worker, caught: list) -> int:
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
        if not method_info(args.method).proximal_parameter:
            raise ValueError(f"--proximal {args.proximal} applies to --method mmshbm, not {args.method}")
        extra["r"] = args.proximal
    if args.tol is not None:
        if args.harmonics is not None:
            raise ValueError(f"pass either -H {args.harmonics} (a fixed H) or --tol {args.tol:g} (H chosen "
                             "to meet it), not both")
        extra["tol"] = args.tol
        if args.max_harmonics is not None:
            extra["max_harmonics"] = args.max_harmonics
    elif args.max_harmonics is not None:
        raise ValueError("--max-harmonics bounds H with --tol: pass --tol too, or a fixed -H")
    else:
        extra["harmonics"] = 5 if args.harmonics is None else args.harmonics
    branch = backbone(model, method=args.method, max_amplitude=max_amp, verbose=common.progress(args),
                      **extra)
    out = common.out_dir(args)
    files = [branch.to_csv(out / "backbone.csv"), branch.save(out / "backbone.npz")]
    if len(branch):
        files += [out / "backbone.png", out / "frequency_energy.png"]
        data = BranchData.of(branch)
        worker.draw([("plot_backbone", (data,), {"measured": measured, "model": reference_frequencies(model),
                                                 "path": files[-2]}),
                     ("plot_frequency_energy", (data,), {"path": files[-1]})])
    return _report(args, branch, model.gap, files, caught)


@contextlib.contextmanager
def _branch_warnings():
    """Collect the messages of the branch's :class:`~mmshbm.BranchWarning` (its checks'
    findings) instead of printing them; every other warning is shown as before."""
    from .._warnings import BranchWarning

    caught: list[BranchWarning] = []
    with warnings.catch_warnings():
        warnings.simplefilter("always", BranchWarning)
        shown = warnings.showwarning

        def show(message, category, filename, lineno, file=None, line=None):
            if issubclass(category, BranchWarning):
                caught.append(message)
            else:
                shown(message, category, filename, lineno, file, line)

        warnings.showwarning = show
        yield caught


def _report(args, branch, gap: float, files: list, caught: list) -> int:
    """Print what the run gave: one summary line; warnings only for a result that is not
    the backbone asked for (cut short, another family beyond the backbone, a message the
    summary does not cover); every finding, the resonances and the jumps with ``-v``.
    Returns the exit code."""
    findings = branch.findings
    short = _another_family(branch, gap, quiet=True)
    print(_summary(branch, gap, findings, short))
    verbose = args.verbose > 0
    for message in caught:
        kind = getattr(message, "kind", None)
        if (verbose or kind in (None, "incomplete", "tolerance_not_met")
                or (short and kind == "left_family")):
            print(f"mmshbm backbone: warning: {message}", file=sys.stderr)
    if short:
        _another_family(branch, gap)
    if verbose:
        for line in _special_lines(branch, gap):
            print(line)
    common.wrote(*files)
    code = common.exit_code([branch])
    if method_info(args.method).baseline and short:
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


def _amp(a: float, gap: float) -> str:
    return f"{a / gap:.3g} gaps" if gap > 0 else f"{a:.3g} m"


def _summary(branch, gap: float, findings: list, short: bool) -> str:
    """One line: what the branch is (complete or not, how far the backbone of linear mode 1
    reaches, its frequency range) and how far to trust its frequency (the truncation
    estimate at the top of the backbone, and whether the truncated series passes the stop)."""
    head = f"mmshbm backbone: {method_info(branch.method).display_name}"
    import numpy as np

    hs = np.asarray(branch.records.get("harmonics", [branch.harmonics]))
    hs = f"{int(hs.min())}–{int(hs.max())}" if len(hs) and hs.min() != hs.max() else str(branch.harmonics)
    head += f", H = {hs}: " if branch.harmonics else ": "
    state = "complete" if branch.completed else f"incomplete ({branch.status})"
    front = branch.family_front() if len(branch) else []
    if not len(front):
        return f"{head}{state}, no point computed"
    top = float(branch.amplitude[front].max())
    f = branch.frequency[front]
    parts = [f"{state}: the backbone of linear mode 1 to {_amp(top, gap)}"
             + (" (another family beyond)" if short else "") + f", {f.min():.4g}–{f.max():.4g} Hz"]
    parts.append(_trust(branch, top, gap))
    pen = [x for x in findings if x.kind == "penetration"]
    if pen:
        parts.append(f"the truncated series passes the stop by up to {pen[0].value:.2g} gaps")
    more = "; details: -v" if findings or branch.special_points else ""
    return head + "; ".join(parts) + more


def _trust(branch, top: float, gap: float) -> str:
    """The frequency's truncation error estimate at the amplitude ``top`` (m), in words."""
    if not branch.harmonics:
        return "no truncation in H (time integration)"
    from ..results.tolerance_checks import tolerance_summary

    asked = tolerance_summary(branch)
    if asked is not None:  # a run with --tol: every point carries its estimate
        return asked
    if not method_info(branch.method).cheap_truncation_estimate:  # re-solves at 2H, 4H: minutes
        return "truncation estimate on request (branch.truncation_error(A))"
    try:
        est = branch.truncation_error(top)
    except (ValueError, RuntimeError, ArithmeticError) as err:
        return f"no truncation estimate ({str(err).splitlines()[0]})"
    if not math.isfinite(est.error):
        return f"no truncation estimate ({est.note or 'the re-solves failed'})"
    at_h = ", ".join(str(h) for h in est.harmonics)
    return (f"frequency error from truncation ≈ {est.error:.1e} at {_amp(top, gap)} (estimate from "
            f"H = {at_h}{'' if est.asymptotic else ', not asymptotic'})")


def _another_family(branch, gap: float, quiet: bool = False) -> bool:
    """Whether a branch ends on another family than its starting mode's (its family front
    stops short of the branch's reach); says so on stderr unless ``quiet``."""
    if not len(branch):
        return False
    front = branch.family_front()
    top = float(branch.amplitude.max())
    if len(front) and float(branch.amplitude[front].max()) >= top * (1 - 1e-9):
        return False
    if quiet:
        return True
    end = int(front[-1]) if len(front) else 0
    code = " (exit code 1)" if method_info(branch.method).baseline else ""
    print(f"mmshbm backbone: warning: {branch.method} branch: the backbone of linear mode 1 ends at "
          f"{_amp(branch.amplitude[end], gap)} ({branch.frequency[end]:.4g} Hz); up to {_amp(top, gap)} the "
          f"branch is another family of motions, not that mode's backbone{code}", file=sys.stderr)
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
