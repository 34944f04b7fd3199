"""``mmshbm plot``."""

from __future__ import annotations

import sys
from pathlib import Path

from . import common

#: runs of the paper's Figure 2 (H 1 3 5 x 8 21 elements): larger grid studies are drawn one
#: panel per element count
FIGURE2_RUNS = 6


def register(sub) -> None:
    """Add the subcommand to the subparsers ``sub``."""
    p = sub.add_parser("plot", help="plots of a saved branch or study (.npz)")
    common.out_option(p)
    p.add_argument("file", help="a .npz written by Branch.save / Study.save (backbone, study)")
    p.add_argument("--kind", nargs="+", default=["all"],
                   choices=["all", "backbone", "energy", "peak_force", "signals", "force", "harmonics"],
                   help="which plots")
    p.add_argument("--points", type=common.positive_float, nargs="+", default=None,
                   help="amplitudes (gaps) of the marked points, solved on the backbone (the family "
                        "front); one line each, 'point N: F Hz, A gaps' (default 1.5 3 6)")
    common.measured_option(p)
    p.set_defaults(func=run)


def run(args) -> int:
    from .. import plotting
    from ..io import load
    from ..results.branch import Branch

    data = load(args.file)
    _show_findings(data)
    measured = common.measured(args)
    out = common.out_dir(args)
    stem = Path(args.file).stem
    kinds = set(args.kind)
    if "all" in kinds:
        kinds = {"backbone", "energy", "peak_force", "signals", "force", "harmonics"}
    marks = tuple(args.points) if args.points else common.DEFAULT_MARKS
    files = []
    if not isinstance(data, Branch):  # a study
        if "backbone" in kinds and common.has_grid(data):
            _print_points(data, marks)
        if "backbone" in kinds:
            path = out / f"{stem}_backbone.png"
            if common.has_grid(data) and len(data) > FIGURE2_RUNS:
                from ..plotting.grids import plot_family_grid

                plot_family_grid(data, amplitudes=(), marks=marks, path=path)
            elif common.has_grid(data):
                plotting.plot_figure2(data, marks=marks, measured=measured, path=path)
            else:
                plotting.plot_study(data, measured=measured, path=path)
            files.append(path)
        styles, labels = plotting.study_styles(data.runs), plotting.study_labels(data.runs)
        if "energy" in kinds:
            files.append(out / f"{stem}_energy.png")
            fig = plotting.plot_frequency_energy(data.branches, labels, styles=styles)
            _save_with_study_legend(fig, data.runs, styles, labels, files[-1])
        if "peak_force" in kinds:
            files.append(out / f"{stem}_peak_force.png")
            fig = plotting.plot_peak_contact_force(data.branches, labels, measured=measured, styles=styles)
            _save_with_study_legend(fig, data.runs, styles, labels, files[-1])
        common.wrote(*files)
        return 0
    branch = data
    if not len(branch):
        raise ValueError(f"{args.file}: the branch has no points")
    gap = plotting._gap(branch)
    if gap > 0:  # the marked points, solved on the family front
        points = branch.solve_at([m * gap for m in marks], stand_in=True)
    else:
        points = branch.solve_at([branch.amplitude[branch.family_front()[-1]]], stand_in=True)
    pts = list(range(len(points)))
    for n, i in enumerate(pts, start=1):
        print(f"point {n}: {_point_line(points, i, gap)}")
    if "backbone" in kinds:
        files.append(out / f"{stem}_backbone.png")
        plotting.plot_backbone(branch, measured=measured, marks=points, path=files[-1])
    if "energy" in kinds:
        files.append(out / f"{stem}_energy.png")
        plotting.plot_frequency_energy(branch, path=files[-1])
    if "peak_force" in kinds:
        files.append(out / f"{stem}_peak_force.png")
        plotting.plot_peak_contact_force(branch, measured=measured, path=files[-1])
    if points.solver is None and kinds & {"signals", "force", "harmonics"}:
        print(f"mmshbm plot: warning: {args.file}: no solver can be rebuilt for this branch (its model is "
              "not described in the file): the signal, contact-force and harmonic plots are left out and "
              "the marked points are the stored family points nearest in amplitude", file=sys.stderr)
        kinds = kinds - {"signals", "force", "harmonics"}
    if "signals" in kinds:
        files.append(out / f"{stem}_signals.png")
        plotting.plot_time_signals(points, pts, path=files[-1])
    if "force" in kinds:
        files.append(out / f"{stem}_contact_force.png")
        plotting.plot_contact_force(points, pts, path=files[-1])
    if "harmonics" in kinds:
        files.append(out / f"{stem}_harmonics.png")
        plotting.plot_harmonic_content(points, pts[-1], path=files[-1], number=len(pts))
    common.wrote(*files)
    return 0


def _save_with_study_legend(fig, runs, styles, labels, path) -> None:
    """Replace the per-run legend of a study's figure by one entry per coordinate value."""
    from ..plotting.common import _finish
    from ..plotting.studies import study_legend

    study_legend(fig.axes[0], runs, styles, labels, fontsize=7, ncol=2)
    _finish(fig, path)


def _print_points(study, marks) -> None:
    """One line per marked point of a grid study's figure (on its marked run)."""
    from ..plotting import branch_label
    from ..plotting.data import _gap, marked_run

    branch = study.branch(**marked_run(study.runs))
    gap = _gap(branch)
    if gap <= 0:
        return
    points = branch.solve_at([m * gap for m in marks], stand_in=True)
    for i in range(len(points)):
        print(f"point {i + 1}: {_point_line(points, i, gap)} ({branch_label(branch)})")


def _point_line(points, i: int, gap: float) -> str:
    """"F Hz, A gaps" of marked point i, saying when the family front had no point at the
    amplitude asked for and the nearest one stands in."""
    amp = f"{points.amplitude[i] / gap:.3g} gaps" if gap > 0 else f"{points.amplitude[i]:.3g} m"
    line = f"{points.frequency[i]:.2f} Hz, {amp}"
    if not points.records["solved"][i]:
        asked = points.records["requested_amplitude"][i]
        line += (f" (no family point at {asked / gap:.3g} gaps: the nearest)" if gap > 0
                 else " (the family's last point)")
    return line


def _show_findings(data) -> None:
    """Repeat what the checks found when the results were computed (a file from before
    the checks is checked now), as warnings: a plot must not look more certain than the run.
    A branch's findings one each; a study's as one line of counts (``Study.findings()``
    gives a row per run)."""
    import warnings

    from .._warnings import BranchWarning
    from ..results.branch import Branch

    branches = [data] if isinstance(data, Branch) else list(data.branches)
    for branch in branches:
        if "checks" not in branch.metadata:
            branch.check(warn=False)
    if isinstance(data, Branch):
        for finding in data.findings:
            warnings.warn(BranchWarning(finding.message, finding.kind), stacklevel=2)
    elif any(b.findings for b in branches):
        from ..analysis.tables import findings_count

        warnings.warn(f"{findings_count(data.runs, branches)} (a row per run: Study.findings(), or the "
                      "study's *_table.txt)", BranchWarning, stacklevel=2)
