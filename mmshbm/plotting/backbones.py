"""Backbone curves: amplitude, energy and peak contact force against frequency."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

from .common import (
    _POINT_COLORS,
    _as_list,
    _figure,
    _finish,
    _gap,
    _model,
    _overlay_measured,
    _reference_lines,
    branch_label,
    log,
)


def plot_backbone(branches, labels: Sequence[str] | None = None, *, measured=None, model=None,
                  marks=None, reference_lines: bool = True, modes: Sequence[int] = (2, 3),
                  max_order: int = 10,
                  ax=None, path=None, title: str | None = None, styles: Sequence[dict] | None = None,
                  legend_loc: str = "upper left") -> Figure:
    """Backbone curves: tip amplitude against frequency.

    Parameters
    ----------
    branches : Branch or sequence of Branch
    labels : sequence of str, optional
        Legend entries (default :func:`branch_label`).
    measured : MeasuredBackbone or path, optional
        A measured backbone to overlay (``mmshbm.analysis.measured.load_measured`` reads CSV).
    model : Model, optional
        For the reference lines (default the first branch's model).
    marks : sequence of (branch index, point index), optional
        Points to mark and number 1, 2, ... (e.g. those of :func:`plot_time_signals`).
    reference_lines : bool
        Mark the linear frequency f_1, the zero-gap limit and f_k/n for ``modes`` k and
        orders n = 2..``max_order`` that fall inside the plotted frequency range.
    ax : matplotlib Axes, optional
        Draw there instead of a new figure.
    path : str or Path, optional
        Write the figure there.
    styles : sequence of dict, optional
        Line keyword arguments per branch.
    legend_loc : str
        Legend position (matplotlib ``loc``).

    Returns
    -------
    matplotlib.figure.Figure

    Notes
    -----
    The amplitude axis is in multiples of the gap when the first branch's gap is
    positive, otherwise in mm.
    """
    branches = _as_list(branches)
    if not branches:
        raise ValueError("no branches to plot")
    fig, ax = _figure(ax, (6.4, 4.6))
    gap = _gap(branches[0])
    scale, ylabel = (gap, "tip amplitude / gap") if gap > 0 else (1e-3, "tip amplitude (mm)")
    labels = list(labels) if labels is not None else [branch_label(b) for b in branches]
    if len(labels) != len(branches):
        raise ValueError(f"{len(labels)} labels for {len(branches)} branches")
    for i, (b, label) in enumerate(zip(branches, labels, strict=True)):
        style = dict(styles[i]) if styles is not None else {}
        ax.plot(b.frequency, b.amplitude / scale, label=label, **({"lw": 1.4} | style))
    if measured is not None:
        if not hasattr(measured, "frequency"):
            from ..analysis.measured import load_measured

            measured = load_measured(measured)
        _overlay_measured(ax, measured, scale)
    for n, (bi, pi) in enumerate(marks or (), start=1):
        b = branches[bi]
        ax.plot(b.frequency[pi], b.amplitude[pi] / scale, "o", color=_POINT_COLORS[(n - 1) % 6], ms=7,
                mec="w", zorder=5)
        ax.annotate(str(n), (b.frequency[pi], b.amplitude[pi] / scale), xytext=(-9, 4),
                    textcoords="offset points", fontsize=10, fontweight="bold", zorder=6)
    if reference_lines:
        model = model if model is not None else _model(branches[0])
        if model is not None:
            f_all = np.concatenate([b.frequency for b in branches if len(b)])
            lo, hi = float(np.nanmin(f_all)), float(np.nanmax(f_all))
            pad = 0.03 * (hi - lo if hi > lo else hi)
            _reference_lines(ax, model, lo - pad, hi + pad, modes, max_order)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel(ylabel)
    ax.set_ylim(bottom=0)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc=legend_loc)
    if title:
        ax.set_title(title)
    return _finish(fig, path)


def plot_frequency_energy(branches, labels: Sequence[str] | None = None, *, ax=None, path=None,
                          title: str | None = None, styles: Sequence[dict] | None = None) -> Figure:
    """Frequency–energy plot: log10 of the mechanical energy (J) against frequency (Hz);
    ``styles`` are line keyword arguments per branch."""
    branches = _as_list(branches)
    if not branches:
        raise ValueError("no branches to plot")
    fig, ax = _figure(ax, (6.4, 4.6))
    labels = list(labels) if labels is not None else [branch_label(b) for b in branches]
    for i, (b, label) in enumerate(zip(branches, labels, strict=True)):
        style = {"lw": 1.4} | (dict(styles[i]) if styles is not None else {})
        with np.errstate(divide="ignore", invalid="ignore"):
            ax.plot(b.frequency, np.log10(b.energy), label=label, **style)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("log$_{10}$(energy / J)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    if title:
        ax.set_title(title)
    return _finish(fig, path)


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

