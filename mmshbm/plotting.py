"""Plots of backbone curves and of the motion along them.

Headless-safe: everything is drawn with matplotlib's object API on a
:class:`matplotlib.figure.Figure` (no pyplot, no GUI, no ``matplotlib.use``); pass
``path`` to write the figure (the format follows the suffix) or ``ax`` to draw into your
own axes. Every function returns the figure.

- :func:`plot_backbone`: tip amplitude (in gaps) against frequency for one or several
  branches, with the linear frequency, the zero-gap (bilinear) limit and internal
  resonance frequencies f_k/n marked, and an optional measured backbone overlaid.
- :func:`plot_frequency_energy`: log10 of the energy against frequency.
- :func:`plot_time_signals`: displacements/rotations (default: tip deflection and tip
  rotation) over one period at chosen points.
- :func:`plot_contact_force`: λ(t) over one period at chosen points.
- :func:`plot_harmonic_content`: bar chart of |Q_k| at one point.
- :func:`plot_peak_contact_force`: largest contact force against frequency, with the
  measured peak forces.
- :func:`plot_figure2`: the seed paper's Figure 2 layout from a study.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

__all__ = ["plot_backbone", "plot_frequency_energy", "plot_time_signals", "plot_contact_force",
           "plot_harmonic_content", "plot_figure2", "plot_peak_contact_force", "study_styles", "points_at",
           "branch_label", "dof_label"]

log = logging.getLogger(__name__)

_DPI = 150
_H_COLORS = {1: "C0", 2: "C4", 3: "C1", 4: "C5", 5: "C2", 7: "C3", 9: "C6"}
_POINT_COLORS = ("k", "C3", "C9", "C6", "C8", "C7")


# ---------------------------------------------------------------------- helpers
def _figure(ax, figsize):
    if ax is None:
        fig = Figure(figsize=figsize, layout="constrained")
        return fig, fig.add_subplot()
    return ax.figure, ax


def _finish(fig: Figure, path) -> Figure:
    if path is not None:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=_DPI)
        log.info("wrote %s", path)
    return fig


def _as_list(branches) -> list:
    from .results.branch import Branch

    return [branches] if isinstance(branches, Branch) else list(branches)


def _gap(branch) -> float:
    gap = branch.gap
    if gap is None:
        try:
            gap = branch.get_model().gap
        except ValueError:
            gap = 0.0
    return float(gap)


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
    if branch.method != "mmshbm":
        parts.append(branch.method)
    if branch.harmonics:
        parts.append(f"H{branch.harmonics}")
    if "n_elements" in meta:
        parts.append(f"{meta['n_elements']} el.")
    return ", ".join(parts) or branch.method


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


def _reference_lines(ax, model, fmin, fmax, modes, max_order) -> None:
    """Vertical lines: linear f1, zero-gap limit, f_k/n of higher modes inside [fmin, fmax]."""
    n = max(max(modes, default=1), 1)
    try:
        f_lin = model.linear_frequencies(n)
        f_zero = model.zero_gap_frequency() if model.gap > 0 else None
    except (ValueError, np.linalg.LinAlgError) as err:
        log.info("no reference lines: %s", err)
        return
    ax.axvline(f_lin[0], color="0.55", ls=":", lw=1.2, label=f"linear $f_1$ = {f_lin[0]:.2f} Hz")
    if f_zero is not None:
        ax.axvline(f_zero, color="0.3", ls="--", lw=1.0, label=f"zero-gap limit {f_zero:.2f} Hz")
    labelled = False
    for k in modes:
        if k - 1 >= len(f_lin):
            continue
        for order in range(2, max_order + 1):
            f = f_lin[k - 1] / order
            if fmin <= f <= fmax:
                ax.axvline(f, color="C3", ls="-.", lw=0.8, alpha=0.7,
                           label=None if labelled else "internal resonance $f_k/n$")
                labelled = True
                ax.annotate(f"$f_{k}/{order}$", xy=(f, 0.0), xycoords=("data", "axes fraction"),
                            xytext=(2, 3), textcoords="offset points", ha="left", va="bottom", fontsize=8,
                            color="C3")


def _overlay_measured(ax, measured, scale: float) -> None:
    ax.plot(measured.frequency, measured.amplitude / scale, "o", mfc="none", mec="k", ms=5, mew=1.0,
            label=f"measured{f' ({measured.source})' if measured.source else ''}")


# ---------------------------------------------------------------------- backbone
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
            from .analysis.measured import load_measured

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
            from .analysis.measured import load_measured

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


# ---------------------------------------------------------------------- along the branch
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


def plot_time_signals(branch, points, dofs: Sequence[int] | None = None, *, n_samples: int = 256, axes=None,
                      path=None, numbers: Sequence[int] | None = None) -> Figure:
    """Displacements / rotations over one period (t/T) at branch ``points``.

    Parameters
    ----------
    branch : Branch
    points : int or sequence of int
        Branch point indices.
    dofs : sequence of int, optional
        Model DOFs, one panel each (default the massless contact DOFs: for the beam
        tip deflection w and tip rotation θ).
    n_samples : int
        Samples per period.
    axes : sequence of Axes, optional
        One per DOF.
    numbers : sequence of int, optional
        Point numbers for the legend (default 1, 2, ...).
    """
    pts = _points(branch, points)
    if dofs is None:
        dofs = [int(d) for d in branch.get_model().c]
    dofs = [int(d) for d in np.atleast_1d(dofs)]
    if axes is None:
        fig = Figure(figsize=(6.4, 2.3 * len(dofs) + 0.6), layout="constrained")
        axes = fig.subplots(len(dofs), 1, sharex=True, squeeze=False)[:, 0]
    else:
        fig = axes[0].figure
    numbers = list(numbers) if numbers is not None else list(range(1, len(pts) + 1))
    for j, (n, i) in enumerate(zip(numbers, pts, strict=True)):
        t, q = branch.time_signals(i, dofs=dofs, n_samples=n_samples)
        T = 1.0 / branch.frequency[i]
        tt = np.append(t, T) / T  # close the period
        for ax, d, qd in zip(axes, dofs, q, strict=True):
            _, factor = dof_label(branch, d)
            ax.plot(tt, np.append(qd, qd[0]) * factor, color=_POINT_COLORS[j % 6], lw=1.3,
                    label=_point_label(branch, n, i))
    for ax, d in zip(axes, dofs, strict=True):
        ax.set_ylabel(dof_label(branch, d)[0])
        ax.grid(True, alpha=0.3)
        ax.axhline(0, color="0.7", lw=0.6)
    gap = _gap(branch)
    model = _model(branch)
    if gap > 0 and model is not None and model.contact_dof in dofs:
        ax = axes[dofs.index(model.contact_dof)]
        ax.axhline(model.stop_side * gap * 1e3, color="0.3", ls="--", lw=0.9, label="stop")
    axes[-1].set_xlabel("t / T")
    axes[-1].set_xlim(0, 1)
    axes[0].legend(fontsize=8, loc="best")
    return _finish(fig, path)


def plot_contact_force(branch, points, *, n_samples: int = 512, ax=None, path=None,
                       numbers: Sequence[int] | None = None) -> Figure:
    """Contact force λ (N) over one period (t/T) at branch ``points``."""
    pts = _points(branch, points)
    fig, ax = _figure(ax, (6.4, 3.2))
    numbers = list(numbers) if numbers is not None else list(range(1, len(pts) + 1))
    for j, (n, i) in enumerate(zip(numbers, pts, strict=True)):
        t, lam = branch.contact_force(i, n_samples=n_samples)
        T = 1.0 / branch.frequency[i]
        ax.plot(np.append(t, T) / T, np.append(lam, lam[0]), color=_POINT_COLORS[j % 6], lw=1.3,
                label=_point_label(branch, n, i))
    ax.set_xlabel("t / T")
    ax.set_ylabel("contact force λ (N)")
    ax.set_xlim(0, 1)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return _finish(fig, path)


def plot_harmonic_content(branch, point: int, dof: int | None = None, *, log_scale: bool = True, ax=None,
                          path=None) -> Figure:
    """Bar chart of the harmonic amplitudes |Q_k|, k = 0..H, of ``dof`` (default the
    contact DOF) at ``point``."""
    (i,) = _points(branch, [point])
    fig, ax = _figure(ax, (5.2, 3.4))
    amp = np.asarray(branch.harmonic_content(i, dof))
    d = branch.get_model().contact_dof if dof is None else int(dof)
    label, factor = dof_label(branch, d)
    k = np.arange(len(amp))
    ax.bar(k, amp * factor, color="C0", width=0.6)
    if log_scale and np.any(amp > 0):
        ax.set_yscale("log")
        ax.set_ylim(bottom=max(amp[amp > 0].min() * factor * 0.3, amp.max() * factor * 1e-8))
    ax.set_xticks(k)
    ax.set_xlabel("harmonic k")
    ax.set_ylabel(f"|Q_k| of {label}")
    ax.set_title(f"point {i}: {branch.frequency[i]:.2f} Hz", fontsize=10)
    ax.grid(True, axis="y", alpha=0.3)
    return _finish(fig, path)


# ---------------------------------------------------------------------- Figure 2
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
