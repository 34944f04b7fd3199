"""Backbone curves: amplitude, energy and peak contact force against frequency."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

from ..core.status import Status
from .common import (
    _POINT_COLORS,
    _as_list,
    _figure,
    _finish,
    _gap,
    _overlay_measured,
    _point_label,
    _reference_lines,
    branch_label,
    distinct_models,
    line_styles,
    log,
)
from .data import (
    amplitude_name,
    odd_harmonics,
    reference_frequencies,
    resonance_label,
    resonance_orders,
    resonances_met,
)


def plot_backbone(branches, labels: Sequence[str] | None = None, *, measured=None, model=None,
                  marks=None, reference_lines: bool = True, modes: Sequence[int] = (2, 3),
                  max_order: int = 10,
                  ax=None, path=None, title: str | None = None, styles: Sequence[dict] | None = None,
                  legend_loc: str = "best", special: bool = True, coexisting: bool = True) -> Figure:
    """Backbone curves: amplitude (a beam's tip, a model's amplitude DOF) against frequency.

    Parameters
    ----------
    branches : Branch or sequence of Branch
    labels : sequence of str, optional
        Legend entries (default :func:`branch_label`).
    measured : MeasuredBackbone or path, optional
        A measured backbone to overlay (``mmshbm.analysis.measured.load_measured`` reads CSV).
    model : Model or (f_lin, f_zero[, exact]), optional
        For the reference lines (default: every distinct model of the branches); or the
        tuple :func:`~mmshbm.plotting.data.reference_frequencies` gives.
    marks : Branch or sequence of (branch index, point index), optional
        Points to mark and number 1, 2, ..., each with a legend entry "marked point n:
        f Hz, A gaps": the points of a Branch (those :meth:`~mmshbm.Branch.solve_at`
        solves on the family front, as :func:`plot_time_signals` draws them), or points of
        the plotted branches.
    reference_lines : bool
        Mark the linear frequency f_1, the zero-gap limit and f_k/n for ``modes`` k and
        orders n = 2..``max_order`` that fall inside the plotted frequency range and that
        the branches carry (n <= H; odd n only for a symmetric clearance), once
        per distinct model (in that model's colour when there are several).
    ax : matplotlib Axes, optional
        Draw there instead of a new figure.
    path : str or Path, optional
        Write the figure there.
    styles : sequence of dict, optional
        Line keyword arguments per branch (default :func:`line_styles`).
    legend_loc : str
        Legend position (matplotlib ``loc``).
    special : bool
        Mark the special points: folds (▲), branch points (■), internal resonances (◆,
        labelled kΩ≈f_j), jumps (dotted from the family's last point before the jump,
        with the skipped amplitudes), and the end of every branch that stopped short of
        its bounds (✕, with the reason). The starting mode's backbone (the family front,
        :meth:`~mmshbm.Branch.family_front`) is the branch's line; points off the family
        (internal-resonance tongues) are drawn thin.
    coexisting : bool
        Mark the branch's computed points that are other orbits of the same amplitude as
        the backbone (:func:`mmshbm.results.coexisting.coexisting_intervals`: points off
        the family front on amplitudes the front covers) with hollow circles, legend entry
        "coexisting orbit (same amplitude)". No solve; :meth:`~mmshbm.Branch.orbits_at`
        lists the family's orbits at one amplitude, solved.

    Returns
    -------
    matplotlib.figure.Figure

    Notes
    -----
    The amplitude axis is in multiples of each branch's own gap when every gap is
    positive (branches with different gaps are comparable), otherwise in mm.
    """
    branches = _as_list(branches)
    if not branches:
        raise ValueError("no branches to plot")
    fig, ax = _figure(ax, (6.4, 4.6))
    gaps = [_gap(b) for b in branches]
    per_gap = all(g > 0 for g in gaps)
    scales = gaps if per_gap else [1e-3] * len(branches)
    names = {amplitude_name(b) for b in branches}
    name = names.pop() if len(names) == 1 else "amplitude"
    if per_gap:
        ylabel = f"{name} / gap" if len(set(gaps)) == 1 else f"{name} / its gap"
    else:
        ylabel = f"{name} (mm)"
    labels = list(labels) if labels is not None else [branch_label(b) for b in branches]
    if len(labels) != len(branches):
        raise ValueError(f"{len(labels)} labels for {len(branches)} branches")
    if styles is None:
        styles = line_styles(len(branches))
    colors = []
    notes: list = []  # labels of special points, placed once the axes' limits are known
    excursion_labelled = coexisting_labelled = False
    for i, (b, label) in enumerate(zip(branches, labels, strict=True)):
        style = {"lw": 1.4} | dict(styles[i])
        y = np.asarray(b.amplitude) / scales[i]
        line, drawn = _draw_family(ax, b, y, label, style, not excursion_labelled)
        excursion_labelled |= drawn
        colors.append(line.get_color())
        if coexisting:
            coexisting_labelled |= _coexisting_points(ax, b, y, line.get_color(), not coexisting_labelled)
        if special:
            _special_points(ax, b, scales[i], line.get_color(), notes)
    if measured is not None:
        if not hasattr(measured, "frequency"):
            from ..analysis.measured import load_measured

            measured = load_measured(measured)
        _overlay_measured(ax, measured, scales[0])
    for n, (b, pi, scale) in enumerate(_marked(marks, branches, scales), start=1):
        x, y = b.frequency[pi], b.amplitude[pi] / scale
        ax.plot(x, y, "o", color=_POINT_COLORS[(n - 1) % 6], ms=7, mec="w", zorder=5,
                label=f"marked point {_point_label(b, n, pi)}")
        ax.annotate(str(n), (x, y), xytext=(-9, 4), textcoords="offset points", fontsize=10,
                    fontweight="bold", zorder=6)
    if reference_lines:
        f_all = np.concatenate([b.frequency for b in branches if len(b)] or [np.array([np.nan])])
        if np.any(np.isfinite(f_all)):
            lo, hi = float(np.nanmin(f_all)), float(np.nanmax(f_all))
            pad = 0.03 * (hi - lo if hi > lo else hi)
            groups = [(model, list(range(len(branches))))] if model is not None else distinct_models(branches)
            lines = _merge_reference(groups, modes)
            for m, (values, members) in enumerate(lines):
                tag = "" if len(lines) == 1 else _model_tag([branches[i] for i in members], branches)
                shade = _MODEL_COLORS[m % len(_MODEL_COLORS)]
                color = {} if len(lines) == 1 else dict(color_open=shade, color_zero=shade, color_ir=shade)
                _reference_lines(ax, values, lo - pad, hi + pad, modes, max_order, tag=tag,
                                 orders=_orders([branches[i] for i in members], max_order), **color)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel(ylabel)
    ax.set_ylim(bottom=0)
    ax.grid(True, alpha=0.3)
    _place_notes(ax, notes)
    _legend(ax, fontsize=8, loc=legend_loc)
    if title:
        ax.set_title(title)
    return _finish(fig, path)


def _orders(branches, max_order: int) -> list[int]:
    """The orders n of the lines f_j/n that ``branches`` can meet: up to the largest H
    among them (every order for a method without truncation), odd ones only when every
    branch's motion carries odd harmonics only."""
    H = [int(b.harmonics) for b in branches]
    top = max_order if not H or min(H) <= 0 else max(H)
    return resonance_orders(top, max_order, odd=bool(branches) and all(odd_harmonics(b) for b in branches))


def _marked(marks, branches, scales) -> list[tuple[object, int, float]]:
    """(branch, point index, amplitude scale) of every marked point."""
    if marks is None:
        return []
    if hasattr(marks, "frequency"):  # a branch of marked points
        gap = _gap(marks)
        scale = gap if all(s == g for s, g in zip(scales, [_gap(b) for b in branches], strict=True)) \
            and gap > 0 else 1e-3
        return [(marks, i, scale) for i in range(len(marks))]
    return [(branches[bi], int(pi), scales[bi]) for bi, pi in marks]


#: colours of the reference lines when several models are drawn
_MODEL_COLORS = ("k", "0.5", "tab:brown", "tab:olive", "tab:pink", "tab:cyan")


def _merge_reference(groups, modes) -> list[tuple[tuple, list[int]]]:
    """Reference frequencies per distinct model, models with equal ones (to 1e-9, e.g.
    differing only in the gap) merged: [((f_lin, f_zero, exact), branch indices), ...]."""
    out: list[tuple[tuple, list[int]]] = []
    for model, members in groups:
        values = reference_frequencies(model, modes)
        if values is None:
            continue
        for known, idx in out:
            same_modes = np.shape(known[0]) == np.shape(values[0])  # models with fewer modes differ
            if same_modes and np.allclose(known[0], values[0], rtol=1e-9, atol=0) and (
                    (known[1] is None) == (values[1] is None)
                    and (known[1] is None or np.isclose(known[1], values[1], rtol=1e-9, atol=0))):
                idx.extend(members)
                break
        else:
            out.append((values, list(members)))
    return out


def _model_tag(members, branches) -> str:
    """What distinguishes the models of ``members`` from the other branches': elements,
    else gap, else the first member's label."""
    elements = {b.metadata.get("model", {}).get("n_elements") for b in members}
    if len(elements) == 1 and None not in elements and \
            len({b.metadata.get("model", {}).get("n_elements") for b in branches}) > 1:
        return f"{elements.pop()} el."
    gaps = {_gap(b) for b in members}
    if len(gaps) == 1 and len({_gap(b) for b in branches}) > 1:
        return f"gap {gaps.pop() * 1e3:g} mm"
    return branch_label(members[0])


#: markers of the special points drawn by :func:`plot_backbone`
SPECIAL_MARKERS = {"fold": "^", "branch_point": "s", "internal_resonance": "D"}


def _front(branch) -> np.ndarray | None:
    """The family front's indices (:func:`mmshbm.results.family_points.family_front`), or
    None when the branch records no family (every point is drawn)."""
    records = getattr(branch, "records", None) or {}
    if "on_family" not in records and "mode_share" not in records:
        return None
    from ..results.family_points import family_front

    return family_front(branch)


def _family_curve(branch, y=None) -> tuple[np.ndarray, np.ndarray]:
    """(frequency, ``y``) of the starting mode's backbone in ``branch`` (``y`` per point,
    default the amplitude): its family front, and the branch's first stretch on the family
    from its start (a backbone can turn back in the measured amplitude after grazing
    without leaving the family: those points are not on the front, which is single-valued
    in amplitude, yet they are the family's), broken (NaN) where the points skip (a tongue
    or a jump); the whole branch when it records no family or never leaves it."""
    y = np.asarray(branch.amplitude if y is None else y, dtype=float)
    front = _front(branch)
    if front is None or len(front) == len(branch):
        return np.asarray(branch.frequency), y
    jumps = {int(sp[1]) for sp in branch.special_points if sp[0] == "jump"}
    on = np.asarray((getattr(branch, "records", None) or {}).get("on_family", np.zeros(0)), dtype=float)
    first = []
    for i in range(min(len(on), len(branch))):
        if on[i] <= 0.5 or (i and i in jumps):
            break
        first.append(i)
    front = sorted(set(front.tolist()) | set(first))
    f, a = [], []
    for n, i in enumerate(front):
        if n and (i != front[n - 1] + 1 or i in jumps):
            f.append(np.nan)
            a.append(np.nan)
        f.append(branch.frequency[i])
        a.append(y[i])
    return np.array(f), np.array(a)


def _broken_at_jumps(branch, y=None) -> tuple[np.ndarray, np.ndarray]:
    """(frequency, ``y``) of every point of ``branch`` (``y`` default the amplitude),
    NaN-broken before each jump (the path is not continuous there)."""
    n = len(branch)
    cuts = sorted({int(sp[1]) for sp in branch.special_points if sp[0] == "jump" and 0 < int(sp[1]) < n})
    f = np.insert(np.asarray(branch.frequency, dtype=float), cuts, np.nan)
    a = np.insert(np.asarray(branch.amplitude if y is None else y, dtype=float), cuts, np.nan)
    return f, a


def _draw_family(ax, branch, y, label, style, first_excursion: bool):
    """The branch's family front as its line (``style``) and its excursions off the family
    thin in the same colour; returns (line, whether an excursion was drawn)."""
    f, v = _family_curve(branch, y)
    (line,) = ax.plot(f, v, label=label, **style)
    if len(f) - np.count_nonzero(np.isnan(f)) == len(branch):
        return line, False
    fp, vp = _broken_at_jumps(branch, y)
    ax.plot(fp, vp, color=line.get_color(), lw=0.6, alpha=0.35, zorder=1,
            label="off the family (internal resonance)" if first_excursion else None)
    return line, True


def _coexisting_points(ax, branch, y, color, label_it: bool) -> bool:
    """Hollow circles at the points of ``branch`` that coexist with its backbone at the
    same amplitude (``y`` per point); returns whether any was drawn."""
    if "on_family" not in (getattr(branch, "records", None) or {}):
        return False
    from ..results.coexisting import coexisting_intervals

    front = set(_front(branch).tolist())
    points = sorted({i for c in coexisting_intervals(branch) for i in c.points if i not in front})
    if not points:
        return False
    ax.plot(np.asarray(branch.frequency)[points], np.asarray(y)[points], "o", ms=3.5, mfc="none", mec=color,
            mew=0.9, ls="none", zorder=3, label="coexisting orbit (same amplitude)" if label_it else None)
    return True


#: two labels of special points closer than this (fractions of the axes' width, height)
#: would overlap: the later one (lower priority) is left out; its marker stays
_NOTE_SPACING = (0.12, 0.035)


def _place_notes(ax, notes: list) -> None:
    """Annotate the special points' labels (priority, text, (x, y) data, offset in points,
    colour), by priority (the end of a branch, then skipped intervals, then resonances),
    leaving out a label whose anchor lies too close to one already placed."""
    to_axes = ax.transData + ax.transAxes.inverted()
    placed: list = []
    for _, text, xy, offset, color in sorted(notes, key=lambda note: note[0]):
        px, py = to_axes.transform(xy)
        if any(abs(px - qx) < _NOTE_SPACING[0] and abs(py - qy) < _NOTE_SPACING[1] for qx, qy in placed):
            continue
        placed.append((px, py))
        right = px > 0.8  # near the right edge the label goes to the left of its point
        ax.annotate(text, xy, xytext=(-offset[0], offset[1]) if right else offset, textcoords="offset points",
                    fontsize=7, color=color, ha="right" if right else "left")


def _special_points(ax, branch, scale: float, color, notes: list) -> None:
    """Markers of the branch's special points; their labels go to ``notes``."""
    n = len(branch)
    f, a = branch.frequency, branch.amplitude / scale
    seen, named = set(), set()
    front = _front(branch)
    met = {id(sp) for sp in resonances_met(branch)}
    for sp in branch.special_points:
        kind, i = sp[0], int(sp[1])
        if not 0 <= i < n or kind == "internal_resonance" and id(sp) not in met:
            continue
        data = getattr(sp, "data", {}) or {}
        if kind in SPECIAL_MARKERS:
            label = None if kind in seen else kind.replace("_", " ")
            seen.add(kind)
            ax.plot(f[i], a[i], SPECIAL_MARKERS[kind], color=color, mfc="w", ms=5.5, mew=1.2, zorder=4,
                    label=label)
            if kind == "internal_resonance":
                k, j = data.get("k", data.get("harmonic")), data.get("j", data.get("mode"))
                if k is not None and j is not None and (k, j) not in named:
                    named.add((k, j))
                    notes.append((2, resonance_label(k, j), (f[i], a[i]), (4, -9), color))
        elif kind == "jump" and i > 0:
            label = None if "jump" in seen else "jump (family not sampled)"
            seen.add("jump")
            before = front[front < i] if front is not None else np.array([i - 1])
            i0 = int(before[-1]) if len(before) else i - 1
            ax.plot([f[i0], f[i]], [a[i0], a[i]], ls=":", color=color, lw=1.0, zorder=3, label=label)
            lo, hi = data.get("amplitude_frontier"), data.get("amplitude_to")
            if lo is not None and hi is not None and hi > lo * 1.01:
                notes.append((1, f"skipped {lo / scale:.3g}–{hi / scale:.3g}", (f[i], a[i]), (4, 4), color))
    status = Status.parse(branch.status)
    if n and status.kind != Status.BOUND:
        ax.plot(f[-1], a[-1], "x", color=color, ms=8, mew=2, zorder=6,
                label=None if "_stopped" in seen else "stopped short of its bounds")
        notes.append((0, status.kind.split(" (")[0], (f[-1], a[-1]), (5, 2), color))


def _legend(ax, **kwargs) -> None:
    """A legend without repeated entries (same label drawn for several lines)."""
    handles, labels = ax.get_legend_handles_labels()
    seen, keep = set(), []
    for h, lab in zip(handles, labels, strict=True):
        if lab and not lab.startswith("_") and lab not in seen:
            seen.add(lab)
            keep.append((h, lab))
    if keep:
        ax.legend(*zip(*keep, strict=True), **kwargs)


def plot_frequency_energy(branches, labels: Sequence[str] | None = None, *, ax=None, path=None,
                          title: str | None = None, styles: Sequence[dict] | None = None) -> Figure:
    """Frequency–energy plot: log10 of the mechanical energy (J) against frequency (Hz),
    drawn as :func:`plot_backbone` draws the backbone (the family front as the line,
    excursions into internal-resonance tongues thin); ``styles`` are line keyword
    arguments per branch. ``title`` defaults to "frequency–energy plot of nonlinear mode
    m" with the branch's label when there is one branch."""
    branches = _as_list(branches)
    if not branches:
        raise ValueError("no branches to plot")
    fig, ax = _figure(ax, (6.4, 4.6))
    labels = list(labels) if labels is not None else [branch_label(b) for b in branches]
    excursion_labelled = False
    for i, (b, label) in enumerate(zip(branches, labels, strict=True)):
        style = {"lw": 1.4} | (dict(styles[i]) if styles is not None else {})
        with np.errstate(divide="ignore", invalid="ignore"):
            energy = np.log10(np.asarray(b.energy, dtype=float))
        _, drawn = _draw_family(ax, b, energy, label, style, not excursion_labelled)
        excursion_labelled |= drawn
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("log₁₀(energy / J)")
    ax.grid(True, alpha=0.3)
    _legend(ax, fontsize=8)
    ax.set_title(_frequency_energy_title(branches, labels) if title is None else title)
    return _finish(fig, path)


def _frequency_energy_title(branches, labels) -> str:
    modes = {int(dict(b.metadata.get("solver") or {}).get("mode", 1)) for b in branches}
    what = f"nonlinear mode {modes.pop()}" if len(modes) == 1 else "nonlinear modes"
    return f"frequency–energy plot of {what}" + (f" ({labels[0]})" if len(branches) == 1 else "")


def plot_peak_contact_force(branches, labels: Sequence[str] | None = None, *, measured=None, ax=None,
                            path=None, styles: Sequence[dict] | None = None) -> Figure:
    """Largest contact force per period (N) against frequency (Hz), with the measured
    peak forces overlaid when the measured backbone has them."""
    branches = _as_list(branches)
    if not branches:
        raise ValueError("no branches to plot")
    fig, ax = _figure(ax, (6.4, 4.6))
    labels = list(labels) if labels is not None else [branch_label(b) for b in branches]
    for i, (b, label) in enumerate(zip(branches, labels, strict=True)):
        style = {"lw": 1.4} | (dict(styles[i]) if styles is not None else {})
        ax.plot(b.frequency, b.contact_force_max, label=label, **style)
    if measured is not None:
        if not hasattr(measured, "frequency"):
            from ..analysis.measured import load_measured

            measured = load_measured(measured)
        if measured.contact_force is None:
            log.info("the measured backbone has no contact force column")
        else:
            ax.plot(measured.frequency, measured.contact_force, "o", mfc="none", mec="k", ms=5,
                    label=f"measured{f' ({measured.source})' if measured.source else ''}")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("peak contact force (N)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return _finish(fig, path)

