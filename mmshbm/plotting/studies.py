"""Plots of studies: styles per run and the Figure 2 layout of the paper."""

from __future__ import annotations

import textwrap
from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

from .backbones import plot_backbone
from .common import _finish, _gap, branch_label, line_styles
from .data import marked_run
from .grids import _h_colors
from .signals import plot_contact_force, plot_time_signals


def varying_axes(runs: Sequence[dict]) -> list[str]:
    """The coordinates whose value differs between ``runs``: ``harmonics`` and ``elements``
    first (colour and dash pattern of the paper's Figure 2), then the others in order of
    first appearance."""
    names: list[str] = []
    for r in runs:
        names += [k for k in r if k not in names]
    varying = [k for k in names if len({repr(r.get(k)) for r in runs}) > 1]
    first = [k for k in ("harmonics", "elements") if k in varying]
    return first + [k for k in varying if k not in first]


def study_labels(runs: Sequence[dict]) -> list[str]:
    """Legend labels naming every coordinate that varies between ``runs``, e.g.
    "H5, 21 el., gap=0.002" (H and elements short, other parameters as name=value)."""
    axes = varying_axes(runs)
    out = []
    for r in runs:
        out.append(", ".join(_value_label(k, r.get(k)) for k in axes) or "run")
    return out


#: dash patterns of the second varying coordinate (its last value solid)
_DASH_ORDER = ("-", "--", ":", "-.", (0, (6, 2, 1, 2, 1, 2)), (0, (1, 4)))


def study_styles(runs: Sequence[dict]) -> list[dict]:
    """Distinct line styles for the runs of a study: colour by the first coordinate that
    varies (by H with the paper's colours when that is H), dash pattern by the second,
    markers by the third; when that does not make every run distinct (more values than
    colours, or further varying coordinates), :func:`line_styles` of the run count."""
    runs = list(runs)
    axes = varying_axes(runs)
    if not axes:
        return line_styles(len(runs))
    values = {k: list(dict.fromkeys(repr(r.get(k)) for r in runs)) for k in axes}
    first = axes[0]
    if len(axes) > 3 or len(values[first]) > 10 or any(len(values[k]) > len(_DASH_ORDER) for k in axes[1:2]) \
            or any(len(values[k]) > 4 for k in axes[2:]):
        return line_styles(len(runs))
    styles = []
    hs = {x.get(first) for x in runs}
    by_h = _h_colors(hs) if first == "harmonics" and all(isinstance(h, int) for h in hs) else None
    for r in runs:
        i = values[first].index(repr(r.get(first)))
        color = by_h[r.get(first)] if by_h is not None else f"C{i}"  # H: the paper's colours, as the grid
        style = {"color": color, "ls": "-", "lw": 1.5}
        if len(axes) > 1:
            # the finest mesh / last value solid, others dashed, dotted, dash-dotted
            vals = values[axes[1]]
            j = len(vals) - 1 - vals.index(repr(r.get(axes[1])))
            style["ls"] = _DASH_ORDER[j]
        if len(axes) > 2:
            k = values[axes[2]].index(repr(r.get(axes[2])))
            if k:
                style.update(marker=("o", "s", "^")[k - 1], ms=3.5, markevery=0.1)
        styles.append(style)
    return styles


def study_legend(ax, runs: Sequence[dict], styles: Sequence[dict], labels: Sequence[str], **kwargs) -> None:
    """A legend whose size does not grow with the number of runs: when the runs' styles
    encode their coordinates (:func:`study_styles`: colour by the first varying one, dash
    pattern by the second, marker by the third), one entry per value of each (e.g. "H5"
    in its colour, "21 el." in its dash pattern) instead of one per run; the other entries
    of ``ax`` (reference lines, special points, marked points) follow. ``kwargs`` go to
    ``ax.legend``."""
    from matplotlib.lines import Line2D

    runs, labels = list(runs), set(labels)
    axes = varying_axes(runs)
    handles, names = [], []
    coded = axes and len(axes) <= 3 and all("color" in st for st in styles) and \
        len({(st["color"], str(st.get("ls")), st.get("marker")) for st in styles}) == len(runs)
    if coded:
        for depth, key in enumerate(axes):
            seen = {}
            for r, st in zip(runs, styles, strict=True):
                seen.setdefault(repr(r.get(key)), (r.get(key), st))
            if depth and len(seen) == 1:
                continue
            for value, st in seen.values():
                look = {"color": st["color"]} if depth == 0 else {"color": "0.3"}
                if depth == 1:
                    look["ls"] = st.get("ls", "-")
                if depth == 2 and st.get("marker"):
                    look.update(marker=st["marker"], ms=4)
                handles.append(Line2D([], [], lw=1.5, **look))
                names.append(_value_label(key, value))
    seen_names = set(names)
    for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
        if lab.startswith("_") or lab in seen_names or (coded and lab in labels):
            continue
        seen_names.add(lab)
        handles.append(h)
        names.append(lab)
    if ax.get_legend() is not None:
        ax.get_legend().remove()
    if handles:
        ax.legend(handles, names, **kwargs)


def _value_label(key: str, value) -> str:
    if key == "harmonics":
        return f"H{value}"
    if key == "elements":
        return f"{value} el."
    if key == "method":
        return str(value)
    return f"{key}={value:g}" if isinstance(value, float) else f"{key}={value}"


def plot_study(study, *, measured=None, path=None, title: str | None = None, ax=None, **kwargs) -> Figure:
    """Backbone curves of every run of a study over any coordinates: each branch in units
    of its own gap, labels naming every coordinate that varies (:func:`study_labels`),
    distinct styles (:func:`study_styles`), reference lines per distinct model, special
    points and the ends of runs that stopped short; with more than six runs, a legend entry
    per value of each coordinate (:func:`study_legend`). ``kwargs`` go to
    :func:`plot_backbone`."""
    runs = list(study.runs)
    if not runs:
        raise ValueError("the study is empty")
    labels, styles = study_labels(runs), study_styles(runs)
    fig = plot_backbone(study.branches, labels, measured=measured, styles=styles, title=title, ax=ax,
                        **kwargs)
    if len(runs) > _LEGEND_RUNS:
        study_legend(ax or fig.axes[0], runs, styles, labels, fontsize=7, ncol=2)
    return _finish(fig, path)


#: studies with more runs get a legend by coordinate value (:func:`study_legend`)
_LEGEND_RUNS = 6


def plot_figure2(study, *, marks: Sequence[float] = (1.5, 3.0, 6.0), marked: dict | None = None,
                 measured=None, path=None, title: str | None = None) -> Figure:
    """The Figure 2 layout of Part I of the paper from a study over H and elements.

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
        Amplitudes (gaps) of the numbered points, solved on the family front of the
        ``marked`` run (:meth:`~mmshbm.Branch.solve_at`).
    marked : dict, optional
        Coordinates of the run carrying the points (default the largest H with the most
        elements).
    measured : MeasuredBackbone or path, optional
    path : str or Path, optional
    """
    runs = list(study.runs)
    if not runs:
        raise ValueError("the study is empty")
    mb = study.branch(**(marked or marked_run(runs)))
    styles = study_styles(runs)
    # order: the marked run last so that it is drawn on top
    order = sorted(range(len(runs)), key=lambda i: study.branches[i] is mb)
    branches = [study.branches[i] for i in order]
    all_labels = study_labels(runs)
    labels = [all_labels[i] for i in order]
    styles = [styles[i] for i in order]

    fig = Figure(figsize=(13.0, 7.0), layout="constrained")
    grid = fig.add_gridspec(3, 2, width_ratios=(1.15, 1.0))
    left = fig.add_subplot(grid[:, 0])
    right = [fig.add_subplot(grid[0, 1])]
    right += [fig.add_subplot(grid[i, 1], sharex=right[0]) for i in (1, 2)]
    gap = _gap(mb)
    model = mb.get_model()
    points = (mb.solve_at(np.asarray(marks, dtype=float) * gap, stand_in=True) if gap > 0 and len(marks)
              else None)
    pts = list(range(len(points))) if points is not None else []
    plot_backbone(branches, labels, measured=measured, marks=points, ax=left, styles=styles, model=model)
    study_legend(left, [runs[i] for i in order], styles, labels, fontsize=7, loc="upper left",
                 ncol=2 if len(runs) > 6 else 1)
    left.set_title("backbone curves (first nonlinear mode)", fontsize=11)
    dofs = [int(d) for d in model.c]
    dofs = [model.contact_dof] + [d for d in dofs if d != model.contact_dof][:1]
    plot_time_signals(points if points is not None else mb, pts, dofs=dofs, axes=right[:len(dofs)])
    note = right[0].get_title(loc="left")
    right[0].set_title("", loc="left")
    head = f"marked points ({branch_label(mb)}): tip motion and contact force"
    right[0].set_title(f"{head}\n{textwrap.fill(note.replace(chr(10), ' '), 80)}", fontsize=9)
    if len(dofs) < 2:
        right[1].set_visible(False)
    for ax in right[:2]:
        ax.tick_params(labelbottom=False)
        ax.set_xlabel("")
    plot_contact_force(points if points is not None else mb, pts, ax=right[2])
    right[2].get_legend().remove()
    if title:
        fig.suptitle(title)
    return _finish(fig, path)
