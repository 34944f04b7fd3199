"""Plots of grid studies (H × elements): the first-mode family per element count and the
convergence of the tabulated frequencies."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

from .common import _H_COLORS, _finish, _gap
from .data import marked_run, resonances_met

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
                     title: str | None = None, marks: Sequence[float] = (),
                     marked: dict | None = None) -> Figure:
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
    marks : sequence of float
        Amplitudes (gaps) of numbered points solved on the family front of the ``marked``
        run (:meth:`~mmshbm.Branch.solve_at`), drawn in its panel, each with a legend
        entry "n: f Hz, A gaps".
    marked : dict, optional
        Coordinates of the run carrying the points (default the largest H with the most
        elements).
    """
    from matplotlib.lines import Line2D

    from ..analysis.skips import WIDE, skips
    from .common import _POINT_COLORS, _point_label, branch_label

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
    if len(marks):
        marked = marked or marked_run(runs)
        mb = study.branch(**marked)
        gap = _gap(mb) or 1.0
        points = mb.solve_at(np.asarray(marks, dtype=float) * gap, stand_in=True)
        ax = axes[elements.index(marked.get("elements", mb.metadata.get("model", {}).get("n_elements")))]
        for n in range(len(points)):
            x, y = points.frequency[n], points.amplitude[n] / gap
            (dot,) = ax.plot(x, y, "o", color=_POINT_COLORS[n % 6], ms=6, mec="w", zorder=6)
            ax.annotate(str(n + 1), (x, y), xytext=(-9, 4), textcoords="offset points", fontsize=9,
                        fontweight="bold", zorder=7)
            handles.append(dot)
            labels.append(f"marked point {_point_label(points, n + 1, n)} ({branch_label(mb)})")
    handles += [Line2D([], [], color="0.65", lw=0.5), Line2D([], [], color="k", ls=":", lw=1.2),
                Line2D([], [], ls="", marker="D", color="k", mfc="w", ms=4)]
    labels += ["continuation off the family (tongues)", "skipped interval (jump or passage)",
               "internal resonance k:j (kΩ ≈ ω_j)"]
    fig.legend(handles, labels, loc="outside lower center", ncol=min(len(labels), 6), fontsize=8)
    guides = "; f at the dashed amplitudes in the table" if len(amplitudes) else ""
    fig.suptitle(title or f"first-mode family (solid) of every run{guides}")
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
