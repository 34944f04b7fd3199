"""Plots of studies: styles per run and the Figure 2 layout of the paper."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

from .backbones import plot_backbone
from .common import _H_COLORS, _finish, _gap, branch_label, line_styles
from .data import resonances_met
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
        parts = []
        for k in axes:
            v = r.get(k)
            if k == "harmonics":
                parts.append(f"H{v}")
            elif k == "elements":
                parts.append(f"{v} el.")
            elif k == "method":
                parts.append(str(v))
            else:
                parts.append(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}")
        out.append(", ".join(parts) or "run")
    return out


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
    if len(axes) > 3 or len(values[first]) > 10 or any(len(values[k]) > 4 for k in axes[1:]):
        return line_styles(len(runs))
    styles = []
    for r in runs:
        i = values[first].index(repr(r.get(first)))
        if first == "harmonics" and all(h in _H_COLORS for h in (x.get(first) for x in runs)):
            color = _H_COLORS[r.get(first)]
        else:
            color = f"C{i}"
        style = {"color": color, "ls": "-", "lw": 1.5}
        if len(axes) > 1:
            # the finest mesh / last value solid, others dashed, dotted, dash-dotted
            vals = values[axes[1]]
            j = len(vals) - 1 - vals.index(repr(r.get(axes[1])))
            style["ls"] = ("-", "--", ":", "-.")[j]
        if len(axes) > 2:
            k = values[axes[2]].index(repr(r.get(axes[2])))
            if k:
                style.update(marker=("o", "s", "^")[k - 1], ms=3.5, markevery=0.1)
        styles.append(style)
    return styles


def plot_study(study, *, measured=None, path=None, title: str | None = None, ax=None, **kwargs) -> Figure:
    """Backbone curves of every run of a study over any coordinates: each branch in units
    of its own gap, labels naming every coordinate that varies (:func:`study_labels`),
    distinct styles (:func:`study_styles`), reference lines per distinct model, special
    points and the ends of runs that stopped short. ``kwargs`` go to :func:`plot_backbone`."""
    runs = list(study.runs)
    if not runs:
        raise ValueError("the study is empty")
    return plot_backbone(study.branches, study_labels(runs), measured=measured, styles=study_styles(runs),
                         path=path, title=title, ax=ax, **kwargs)


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
    if marked is None:
        best = max(range(len(runs)), key=lambda i: (runs[i].get("harmonics", 0), runs[i].get("elements", 0)))
        marked = {k: runs[best][k] for k in ("method", "harmonics", "elements") if k in runs[best]}
    mb = study.branch(**marked)
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
    points = mb.solve_at(np.asarray(marks, dtype=float) * gap) if gap > 0 and len(marks) else None
    pts = list(range(len(points))) if points is not None else []
    plot_backbone(branches, labels, measured=measured, marks=points, ax=left, styles=styles,
                  legend_loc="lower right")
    left.set_title("backbone curves (first nonlinear mode)", fontsize=11)
    dofs = [int(d) for d in model.c]
    dofs = [model.contact_dof] + [d for d in dofs if d != model.contact_dof][:1]
    plot_time_signals(points if points is not None else mb, pts, dofs=dofs, axes=right[:len(dofs)])
    note = right[0].get_title(loc="left")
    right[0].set_title("", loc="left")
    head = f"marked points ({branch_label(mb)}): tip motion and contact force"
    right[0].set_title(f"{head}\n{note}", fontsize=9)
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



#: colours of H beyond the paper's (H 1, 3, 5 as in Figure 2)
_MORE_H_COLORS = ("C7", "C8", "C9", "C4", "C5")


def _h_colors(values) -> dict:
    out, extra = {}, iter(_MORE_H_COLORS)
    used = set()
    for h in sorted(values):
        color = _H_COLORS.get(h)
        if color is None or color in used:
            color = next(extra, None) or f"C{len(out) % 10}"
        used.add(color)
        out[h] = color
    return out


def _front_line(branch) -> tuple[np.ndarray, np.ndarray]:
    """Frequency and amplitude of the family front with NaN breaks at skipped intervals."""
    from ..analysis.skips import skips

    front = branch.family_front()
    breaks = {s.index_hi for s in skips(branch)}
    f, a = [], []
    for i in front:
        if int(i) in breaks:
            f.append(np.nan)
            a.append(np.nan)
        f.append(branch.frequency[i])
        a.append(branch.amplitude[i])
    return np.array(f), np.array(a)


def _path_line(branch, gap: float) -> tuple[np.ndarray, np.ndarray]:
    """The whole continuation path, broken before every jump (no line across a restart)."""
    f = np.asarray(branch.frequency, dtype=float)
    a = np.asarray(branch.amplitude, dtype=float) / gap
    cuts = sorted(int(s[1]) for s in branch.special_points if s[0] == "jump" and 0 < int(s[1]) < len(f))
    return np.insert(f, cuts, np.nan), np.insert(a, cuts, np.nan)


def plot_family_grid(study, *, amplitudes: Sequence[float] = (2.0, 5.0, 10.0), path=None,
                     title: str | None = None) -> Figure:
    """The first-mode family of every run of an H × elements study, one panel per element
    count, colour by H.

    Each panel draws the family front (:meth:`Branch.family_front`: the backbone of the
    starting mode) solid, the whole path of the continuation including its excursions
    into internal-resonance tongues thin and grey, every skipped interval (a jump or a
    passage) as a dotted segment, the internal resonances named on the branch (diamonds,
    "k:j" = harmonic k meets mode j, labelled once per run) and the table amplitudes as
    dashed horizontal lines. Amplitudes in units of each run's gap.

    Parameters
    ----------
    study : Study
        With coordinates ``harmonics`` and ``elements``.
    amplitudes : sequence of float
        Table amplitudes (gaps) to draw as guides.
    path : str or Path, optional
    """
    from matplotlib.lines import Line2D

    from ..analysis.skips import WIDE, skips

    runs = list(study.runs)
    if not runs or not all("harmonics" in r and "elements" in r for r in runs):
        raise ValueError("plot_family_grid needs a study over harmonics and elements")
    elements = sorted({r["elements"] for r in runs})
    colors = _h_colors({r["harmonics"] for r in runs})
    ncol = min(len(elements), 3)
    nrow = -(-len(elements) // ncol)
    fig = Figure(figsize=(4.6 * ncol, 4.0 * nrow + 0.6), layout="constrained")
    axes = fig.subplots(nrow, ncol, sharex=True, sharey=True, squeeze=False).ravel()
    for ax in axes[len(elements):]:
        ax.set_visible(False)
    for ax, n in zip(axes, elements, strict=False):
        for a in amplitudes:
            ax.axhline(a, color="0.6", ls="--", lw=0.6, zorder=0)
        panel = sorted(((r, b) for r, b in study if r["elements"] == n), key=lambda rb: rb[0]["harmonics"])
        for r, b in panel:
            gap = _gap(b) or 1.0
            color = colors[r["harmonics"]]
            ax.plot(*_path_line(b, gap), color="0.65", lw=0.5, zorder=1)
            f, a = _front_line(b)
            ax.plot(f, a / gap, color=color, lw=1.5, zorder=3, label=f"H{r['harmonics']}")
            for s in skips(b):
                if s.width > WIDE * s.hi or s.discontinuous:
                    ax.plot([s.f_lo, s.f_hi], [s.lo / gap, s.hi / gap], ls=":", color=color, lw=1.2, zorder=2)
            named = set()
            for sp in resonances_met(b):
                i = int(sp[1])
                ax.plot(b.frequency[i], b.amplitude[i] / gap, "D", color=color, mfc="w", ms=3.5, mew=0.9,
                        zorder=4)
                key = (sp.data.get("k"), sp.data.get("j"))
                if key not in named:
                    named.add(key)
                    ax.annotate(f"{key[0]}:{key[1]}", (b.frequency[i], b.amplitude[i] / gap), xytext=(3, -7),
                                textcoords="offset points", fontsize=6, color=color)
        ax.set_title(f"{n} elements", fontsize=10)
        ax.grid(True, alpha=0.25)
    for i, ax in enumerate(axes[:len(elements)]):
        if i + ncol >= len(elements):  # no panel below
            ax.set_xlabel("frequency (Hz)")
            ax.tick_params(labelbottom=True)
        if i % ncol == 0:
            ax.set_ylabel("tip amplitude / gap")
    handles, labels = axes[0].get_legend_handles_labels()
    handles += [Line2D([], [], color="0.65", lw=0.5), Line2D([], [], color="k", ls=":", lw=1.2),
                Line2D([], [], ls="", marker="D", color="k", mfc="w", ms=4)]
    labels += ["continuation off the family (tongues)", "skipped interval (jump or passage)",
               "internal resonance k:j (kΩ ≈ ω_j)"]
    fig.legend(handles, labels, loc="outside lower center", ncol=min(len(labels), 6), fontsize=8)
    fig.suptitle(title or "first-mode family (solid) of every run; f at the dashed amplitudes in the table")
    return _finish(fig, path)


def plot_convergence(study, *, amplitudes: Sequence[float] = (2.0, 5.0, 10.0), table=None, path=None,
                     title: str | None = None) -> Figure:
    """Frequency at each table amplitude against H (top row, one line per element count)
    and against the number of elements (bottom row, log axis, one line per H). Empty
    cells (a skipped tongue, see the table's notes) break the lines; values next to a
    jump of the family are ringed in red.

    Parameters
    ----------
    study : Study
        Over ``harmonics`` and ``elements``.
    amplitudes : sequence of float
        Gaps.
    table : FrequencyTable, optional
        ``study.table(amplitudes)`` if already computed.
    path : str or Path, optional
    """
    table = study.table(amplitudes, unit="gap") if table is None else table
    amps = list(table.amplitudes)
    fig = Figure(figsize=(4.2 * len(amps), 7.0), layout="constrained")
    axes = fig.subplots(2, len(amps), squeeze=False)
    hs = sorted({r["harmonics"] for r in study.runs})
    colors = _h_colors(hs)
    for j, a in enumerate(amps):
        rows, cols, f = table.pivot(j, "elements", "harmonics")
        _, _, cells = table._cells("elements", "harmonics")
        noted = np.zeros(f.shape, dtype=bool)
        for (ri, ci), k in cells.items():
            noted[ri, ci] = bool(table.notes[k][j]) and np.isfinite(table.frequency[k, j])
        top, bottom = axes[0, j], axes[1, j]
        for ri, n in enumerate(rows):
            top.plot(cols, f[ri], "o-", ms=3.5, lw=1.0, color=f"C{ri}", label=f"{n} el.")
            top.plot(np.asarray(cols)[noted[ri]], f[ri][noted[ri]], "o", ms=9, mfc="none", mec="r", mew=1.2)
        for ci, h in enumerate(cols):
            bottom.plot(rows, f[:, ci], "s-", ms=3.5, lw=1.0, color=colors[h], label=f"H{h}")
            bottom.plot(np.asarray(rows)[noted[:, ci]], f[noted[:, ci], ci], "o", ms=9, mfc="none", mec="r",
                        mew=1.2)
        top.set_xticks(cols)
        bottom.set_xscale("log")
        bottom.set_xticks(rows, [str(n) for n in rows])
        bottom.minorticks_off()
        top.set_title(f"A = {a:g} gaps", fontsize=10)
        top.set_xlabel("H")
        bottom.set_xlabel("elements")
        for ax in (top, bottom):
            ax.grid(True, alpha=0.3)
        if j == 0:
            top.set_ylabel("frequency (Hz)")
            bottom.set_ylabel("frequency (Hz)")
    axes[0, -1].legend(fontsize=7)
    axes[1, -1].legend(fontsize=7, ncol=2)
    fig.suptitle(title or "convergence in H (top) and elements (bottom); gaps in a line = no value "
                 "(skipped tongue), red ring = next to a jump of the family", fontsize=10)
    return _finish(fig, path)
