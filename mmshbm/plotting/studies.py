"""Plots of studies: styles per run and the seed paper's Figure 2 layout."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

from .backbones import plot_backbone
from .common import _H_COLORS, _finish, _gap, branch_label, points_at
from .signals import plot_contact_force, plot_time_signals


def study_styles(runs: Sequence[dict]) -> list[dict]:
    """Line styles for the runs of a study: colour by H, solid for the most elements,
    dashed (or dotted, with three or more meshes) for fewer."""
    elements = sorted({r.get("elements") for r in runs if r.get("elements") is not None})
    styles = []
    for r in runs:
        finest = not elements or r.get("elements") == elements[-1]
        ls = "-" if finest else ("--" if len(elements) < 3 else ":")
        styles.append({"color": _H_COLORS.get(r.get("harmonics"), None), "ls": ls, "lw": 1.5})
    return styles


def plot_figure2(study, *, marks: Sequence[float] = (1.5, 3.0, 6.0), marked: dict | None = None,
                 measured=None, path=None, title: str | None = None) -> Figure:
    """The seed paper's Figure 2 layout from a study over H and elements.

    Left: backbone curves (tip amplitude in gaps against frequency) of every run, colour
    by H, solid for the most elements and dashed for fewer, with the linear frequency,
    zero-gap limit and f_k/n of the ``marked`` run's model, the measured backbone if
    given, and numbered points on the ``marked`` run. Right, over one period at the
    numbered points: tip deflection (top), tip rotation (middle; the second massless DOF)
    and contact force (bottom).

    Parameters
    ----------
    study : Study
        With coordinates ``harmonics`` and ``elements`` (e.g. :func:`mmshbm.analysis.studies.figure2_study`).
    marks : sequence of float
        Amplitudes (gaps) of the numbered points: the first branch point reaching each.
    marked : dict, optional
        Coordinates of the run carrying the points (default the largest H with the most
        elements).
    measured : MeasuredBackbone or path, optional
    path : str or Path, optional
    """
    runs = list(study.runs)
    if not runs:
        raise ValueError("the study is empty")
    if marked is None:
        best = max(range(len(runs)), key=lambda i: (runs[i].get("harmonics", 0), runs[i].get("elements", 0)))
        marked = {k: runs[best][k] for k in ("method", "harmonics", "elements") if k in runs[best]}
    mb = study.branch(**marked)
    styles = study_styles(runs)
    # order: the marked run last so that it is drawn on top
    order = sorted(range(len(runs)), key=lambda i: study.branches[i] is mb)
    branches = [study.branches[i] for i in order]
    labels = [branch_label(b) for b in branches]
    styles = [styles[i] for i in order]

    fig = Figure(figsize=(13.0, 7.0), layout="constrained")
    grid = fig.add_gridspec(3, 2, width_ratios=(1.15, 1.0))
    left = fig.add_subplot(grid[:, 0])
    right = [fig.add_subplot(grid[0, 1])]
    right += [fig.add_subplot(grid[i, 1], sharex=right[0]) for i in (1, 2)]
    gap = _gap(mb)
    pts = points_at(mb, np.asarray(marks, dtype=float) * gap) if gap > 0 else []
    model = mb.get_model()
    marked_points = [(len(branches) - 1, p) for p in pts]
    plot_backbone(branches, labels, measured=measured, model=model, marks=marked_points, ax=left,
                  styles=styles, legend_loc="lower right")
    left.set_title("backbone curves (first nonlinear mode)", fontsize=11)
    dofs = [int(d) for d in model.c]
    dofs = [model.contact_dof] + [d for d in dofs if d != model.contact_dof][:1]
    plot_time_signals(mb, pts, dofs=dofs, axes=right[:len(dofs)])
    right[0].set_title(f"marked points ({branch_label(mb)}): tip motion and contact force", fontsize=11)
    if len(dofs) < 2:
        right[1].set_visible(False)
    for ax in right[:2]:
        ax.tick_params(labelbottom=False)
        ax.set_xlabel("")
    plot_contact_force(mb, pts, ax=right[2])
    right[2].get_legend().remove()
    if title:
        fig.suptitle(title)
    return _finish(fig, path)

