"""Helpers shared by the plots: figures, labels, points, reference lines."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from .._method_info import DEFAULT_METHOD
from .data import _gap, reference_frequencies

log = logging.getLogger(__name__)

_DPI = 150
_H_COLORS = {1: "C0", 2: "C4", 3: "C1", 4: "C5", 5: "C2", 7: "C3", 9: "C6"}
_POINT_COLORS = ("k", "C3", "C9", "C6", "C8", "C7")
_SUBSCRIPTS = str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉")


def subscript(n: int) -> str:
    """``n`` in Unicode subscript digits (labels without mathtext, whose parser costs
    ~50 ms on the first figure of a process)."""
    return str(n).translate(_SUBSCRIPTS)


#: margins (inches) of the single-axes figures: room for tick labels of up to ~7
#: characters and the axis labels; the title adds ``_TITLE_IN`` on top
_MARGINS_IN = {"left": 0.8, "right": 0.15, "bottom": 0.55, "top": 0.15}
_TITLE_IN = 0.3


def _figure(ax, figsize):
    """A new single-axes figure (or ``ax``'s). Fixed margins instead of a layout engine:
    constrained layout measures every text twice per draw (~50 ms of a ~100 ms figure)."""
    if ax is None:
        fig = Figure(figsize=figsize)
        fig._mmshbm_fixed_margins = True
        _set_margins(fig, title=False)
        return fig, fig.add_subplot()
    return ax.figure, ax


def _set_margins(fig: Figure, title: bool) -> None:
    w, h = fig.get_size_inches()
    m = _MARGINS_IN
    fig.subplots_adjust(left=m["left"] / w, right=1 - m["right"] / w, bottom=m["bottom"] / h,
                        top=1 - (m["top"] + (_TITLE_IN if title else 0.0)) / h)


def _finish(fig: Figure, path) -> Figure:
    if getattr(fig, "_mmshbm_fixed_margins", False):
        _set_margins(fig, title=any(a.get_title() for a in fig.axes))
    declutter(fig)
    if path is not None:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=_DPI)
        log.info("wrote %s", path)
    return fig


def declutter(fig: Figure) -> int:
    """Move the annotations of every axes (labels of special points, resonances, skipped
    intervals, reference lines) apart: each in turn keeps its place when it overlaps no
    annotation already placed, else is shifted up or down by whole text heights, else
    hidden (the legend and the command line still say what it said). Bold texts (the
    numbers of marked points) are placed first. Returns the number hidden."""
    from matplotlib.text import Annotation

    axes = [ax for ax in fig.axes
            if ax.get_visible() and sum(isinstance(t, Annotation) for t in ax.texts) > 1]
    if not axes:
        return 0
    if fig.get_layout_engine() is not None:
        fig.draw_without_rendering()  # place the axes first
    renderer = fig._get_renderer()
    hidden = 0
    for ax in axes:
        frame = ax.get_window_extent(renderer)
        texts = [t for t in ax.texts if isinstance(t, Annotation) and t.get_visible() and t.get_text()]
        texts.sort(key=lambda t: t.get_fontweight() not in ("bold", 700))
        placed = []
        for t in texts:
            x0, y0 = t.xyann
            step = 1.15 * t.get_fontsize()
            movable = t.anncoords == "offset points"  # shifts are in points
            for k in (0, -1, 1, -2, 2, -3, 3) if movable else (0,):
                t.xyann = (x0, y0 + k * step)
                box = t.get_window_extent(renderer)
                if not any(box.overlaps(p) for p in placed) and (k == 0 or frame.contains(box.x0, box.y0)
                                                                and frame.contains(box.x1, box.y1)):
                    placed.append(box)
                    break
            else:
                t.xyann = (x0, y0)
                t.set_visible(False)
                hidden += 1
    return hidden


def _as_list(branches) -> list:
    """One branch (anything with a ``frequency`` array: a Branch or a :class:`BranchData`)
    or a sequence of them -> list."""
    return [branches] if hasattr(branches, "frequency") else list(branches)


def _model(branch):
    try:
        return branch.get_model()
    except ValueError as err:
        log.info("no model for the reference lines: %s", err)
        return None


def branch_label(branch) -> str:
    """A short legend label: method, H and elements, e.g. "H5, 21 el."."""
    meta = branch.metadata.get("model", {})
    parts = []
    if branch.method != DEFAULT_METHOD:
        parts.append(branch.method)
    if branch.harmonics:
        parts.append(f"H{branch.harmonics}")
    if "n_elements" in meta:
        parts.append(f"{meta['n_elements']} el.")
    return ", ".join(parts) or branch.method


#: line styles beyond the colours: a new dash pattern every 10 lines, then markers
_DASHES = ("-", "--", "-.", ":")
_MARKERS = (None, "o", "s", "^", "v", "D")


def line_styles(n: int) -> list[dict]:
    """``n`` distinguishable line styles: the 10 colours of the default cycle, then each
    again with another dash pattern, then with markers (every combination distinct up to
    240 lines)."""
    out = []
    for i in range(n):
        style = {"color": f"C{i % 10}", "ls": _DASHES[(i // 10) % 4]}
        marker = _MARKERS[(i // 40) % len(_MARKERS)]
        if marker:
            style.update(marker=marker, ms=3.5, markevery=0.1)
        out.append(style)
    return out


def dof_label(branch, dof: int) -> tuple[str, float]:
    """(axis label with unit, factor from SI) for ``dof`` of the branch's model: beam DOFs
    become "tip deflection w (mm)" / "rotation θ at node 3 (mrad)"; others "q[dof] (m or rad)"."""
    meta = branch.metadata.get("model", {})
    if meta.get("kind") == "TimoshenkoBeam":
        n_el = int(meta["n_elements"])
        node = dof // 2 + 1
        where = "tip" if node == n_el else f"node {node}"
        if dof % 2 == 0:
            return f"{where} deflection w (mm)", 1e3
        return f"{where} rotation θ (mrad)", 1e3
    model = _model(branch)
    if model is not None and dof == model.contact_dof:
        return "contact DOF q (mm)", 1e3
    return f"q[{dof}] (SI units)", 1.0


def points_at(branch, amplitudes) -> list[int]:
    """Indices of the first branch points whose amplitude reaches each of ``amplitudes``
    (m); the last point when the branch never does."""
    out = []
    for a in np.atleast_1d(np.asarray(amplitudes, dtype=float)):
        hit = np.flatnonzero(branch.amplitude >= a)
        out.append(int(hit[0]) if len(hit) else len(branch) - 1)
    return out


def _reference_lines(ax, model, fmin, fmax, modes, max_order, *, color_open="0.55", color_zero="0.3",
                     color_ir="C3", tag: str = "", orders=None) -> None:
    """Vertical lines: linear f1, zero-gap limit, f_k/n of higher modes inside [fmin, fmax]
    for the ``orders`` n (default 2..``max_order``; sparse eigen-solves: about 0.2 s on 1000
    elements). ``tag`` names the model in the legend when several models are drawn."""
    values = reference_frequencies(model, modes) if not isinstance(model, tuple) else model
    if values is None:
        return
    f_lin, f_zero, *exact = values
    suffix = f" ({tag})" if tag else ""
    ax.axvline(f_lin[0], color=color_open, ls=":", lw=1.2, label=f"linear f₁ = {f_lin[0]:.2f} Hz{suffix}")
    if f_zero is not None:
        what = "zero-gap limit (one-DOF estimate)" if exact and not exact[0] else "zero-gap limit"
        ax.axvline(f_zero, color=color_zero, ls="--", lw=1.0, label=f"{what} {f_zero:.2f} Hz{suffix}")
    labelled = False
    for k in modes:
        if k - 1 >= len(f_lin):
            continue
        for order in (range(2, max_order + 1) if orders is None else orders):
            f = f_lin[k - 1] / order
            if fmin <= f <= fmax:
                ax.axvline(f, color=color_ir, ls="-.", lw=0.8, alpha=0.7,
                           label=None if labelled else f"internal resonance fₖ/n{suffix}")
                labelled = True
                ax.annotate(f"f{subscript(k)}/{order}", xy=(f, 0.0), xycoords=("data", "axes fraction"),
                            xytext=(2, 3), textcoords="offset points", ha="left", va="bottom", fontsize=8,
                            color=color_ir)


def distinct_models(branches) -> list[tuple[object, list[int]]]:
    """The distinct models of ``branches`` (by :meth:`Model.fingerprint`), each with the
    indices of its branches, in order of first appearance; branches whose model cannot
    be had are left out."""
    groups: dict[str, tuple[object, list[int]]] = {}
    for i, b in enumerate(branches):
        model = _model(b)
        if model is None:
            continue
        key = model.fingerprint()
        if key in groups:
            groups[key][1].append(i)
        else:
            groups[key] = (model, [i])
    return list(groups.values())


def _overlay_measured(ax, measured, scale: float) -> None:
    ax.plot(measured.frequency, measured.amplitude / scale, "o", mfc="none", mec="k", ms=5, mew=1.0,
            label=f"measured{f' ({measured.source})' if measured.source else ''}")


def _point_label(branch, n: int, i: int) -> str:
    gap = _gap(branch)
    amp = f"{branch.amplitude[i] / gap:.2g} gaps" if gap > 0 else f"{1e3 * branch.amplitude[i]:.3g} mm"
    return f"{n}: {branch.frequency[i]:.2f} Hz, {amp}"


def _points(branch, points) -> list[int]:
    pts = [int(p) for p in np.atleast_1d(points)]
    n = len(branch)
    for p in pts:
        if not -n <= p < n:
            raise IndexError(f"point {p} out of range for a branch of {n} points")
    return [p % n for p in pts]

