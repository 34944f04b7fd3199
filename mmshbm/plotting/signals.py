"""The motion at points of a branch: time signals, contact force, harmonic content."""

from __future__ import annotations

import textwrap
from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

from .common import _POINT_COLORS, _figure, _finish, _gap, _model, _point_label, _points, dof_label


def _kind(branch) -> str:
    """What the method's own signals are: 'series' for harmonic balance, 'orbit' else."""
    return "series" if branch.harmonics else "orbit"


def plot_time_signals(branch, points, dofs: Sequence[int] | None = None, *, n_samples: int = 256, axes=None,
                      path=None, numbers: Sequence[int] | None = None, signals: str = "both") -> Figure:
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
    signals : {"both", "admissible", "series"}
        For harmonic balance: "admissible" draws the massless DOFs from the exact static
        contact problem driven by the Fourier motion of the DOFs with mass (never through
        the stop; ``branch.time_signals(i, admissible=True)``), "series" the truncated
        Fourier series, "both" (default) the admissible signals solid and the series
        thin dashed. The legend says which is which. Shooting's orbit is drawn as it is.
    """
    if signals not in ("both", "admissible", "series"):
        raise ValueError(f"signals must be 'both', 'admissible' or 'series', got {signals!r}")
    pts = _points(branch, points)
    if dofs is None:
        dofs = [int(d) for d in branch.get_model().c]
    dofs = [int(d) for d in np.atleast_1d(dofs)]
    if axes is None:
        fig = Figure(figsize=(6.4, 2.3 * len(dofs) + 0.6), layout="constrained")
        axes = fig.subplots(len(dofs), 1, sharex=True, squeeze=False)[:, 0]
    else:
        fig = axes[0].figure
    model = _model(branch)
    series_only = _kind(branch) != "series" or signals == "series"
    numbers = list(numbers) if numbers is not None else list(range(1, len(pts) + 1))
    for j, (n, i) in enumerate(zip(numbers, pts, strict=True)):
        T = 1.0 / branch.frequency[i]
        color = _POINT_COLORS[j % 6]
        if series_only:
            drawn = [("series", {})]
        elif signals == "admissible":
            drawn = [("admissible", {})]
        else:
            drawn = [("admissible", {}), ("series", {"ls": "--", "lw": 0.8})]
        for what, style in drawn:
            t, q = branch.time_signals(i, dofs=dofs, n_samples=n_samples, admissible=what == "admissible")
            tt = np.append(t, T) / T  # close the period
            for ax, d, qd in zip(axes, dofs, q, strict=True):
                _, factor = dof_label(branch, d)
                ax.plot(tt, np.append(qd, qd[0]) * factor, color=color, **({"lw": 1.3} | style),
                        label=_point_label(branch, n, i) if what == drawn[0][0] else None)
    for ax, d in zip(axes, dofs, strict=True):
        ax.set_ylabel(dof_label(branch, d)[0])
        ax.grid(True, alpha=0.3)
        ax.axhline(0, color="0.7", lw=0.6)
    gap = _gap(branch)
    if gap > 0 and model is not None:
        for contact in model.contacts:
            if contact.dof in dofs:
                axes[dofs.index(contact.dof)].axhline(contact.side * contact.gap * 1e3, color="0.3", ls="--",
                                                      lw=0.9, label="stop")
    axes[-1].set_xlabel("t / T")
    axes[-1].set_xlim(0, 1)
    axes[0].legend(fontsize=8, loc="best")
    axes[0].set_title(textwrap.fill(_signals_note(branch, signals), 90), fontsize=8, loc="left")
    return _finish(fig, path)


def _signals_note(branch, signals: str) -> str:
    if _kind(branch) != "series":
        return f"{branch.method}: the time-domain orbit (massless DOFs from the exact static contact problem)"
    H = branch.harmonics
    return {"both": f"solid: admissible (exact static contact, driven by the H = {H} Fourier motion of the "
                    f"DOFs with mass); dashed: truncated Fourier series (H = {H})",
            "admissible": f"admissible: exact static contact driven by the H = {H} Fourier motion of "
                          "the DOFs with mass",
            "series": f"truncated Fourier series (H = {H}): may pass the stop"}[signals]


def plot_contact_force(branch, points, *, n_samples: int = 512, ax=None, path=None,
                       numbers: Sequence[int] | None = None, admissible: bool = False) -> Figure:
    """Contact force λ (N) over one period (t/T) at branch ``points``.

    ``admissible=False`` (default) draws the method's own force — for harmonic balance
    its truncated Fourier series, which may become negative (a truncation effect; the
    title says so when it does); True draws the exact static contact force driven by the
    Fourier motion of the DOFs with mass (λ >= 0, exactly 0 while the contact is open;
    its peaks are the contact stiffness times the series' overshoot, far above the
    series' on a stiff contact element).
    """
    pts = _points(branch, points)
    fig, ax = _figure(ax, (6.4, 3.2))
    numbers = list(numbers) if numbers is not None else list(range(1, len(pts) + 1))
    lowest = 0.0
    for j, (n, i) in enumerate(zip(numbers, pts, strict=True)):
        t, lam = branch.contact_force(i, n_samples=n_samples, admissible=admissible)
        lam = np.atleast_2d(lam)
        T = 1.0 / branch.frequency[i]
        for row in lam:
            ax.plot(np.append(t, T) / T, np.append(row, row[0]), color=_POINT_COLORS[j % 6], lw=1.3,
                    label=_point_label(branch, n, i))
        lowest = min(lowest, float(lam.min()))
    ax.set_xlabel("t / T")
    ax.set_ylabel("contact force λ (N)")
    ax.set_xlim(0, 1)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    if _kind(branch) == "series":
        what = ("admissible: exact static contact force driven by the Fourier motion of the DOFs with mass"
                if admissible else f"truncated Fourier series of λ (H = {branch.harmonics})")
        if lowest < 0:
            what += f"; λ < 0 (down to {lowest:.3g} N) is a truncation effect"
    else:
        what = f"{branch.method}: exact static contact force along the orbit"
    ax.set_title(textwrap.fill(what, 90), fontsize=8, loc="left")
    return _finish(fig, path)


def plot_harmonic_content(branch, point: int, dof: int | None = None, *, log_scale: bool = True, ax=None,
                          path=None, number: int | None = None) -> Figure:
    """Bar chart of the harmonic amplitudes |Q_k|, k = 0..H, of ``dof`` (default the
    contact DOF) at ``point``; ``number`` names it in the title as a marked point (default:
    its index)."""
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
    title = f"point {i}" if number is None else f"marked point {_point_label(branch, number, i)}"
    ax.set_title(title if number is not None else f"{title}: {branch.frequency[i]:.2f} Hz", fontsize=10)
    ax.grid(True, axis="y", alpha=0.3)
    return _finish(fig, path)

