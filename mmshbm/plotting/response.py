"""Plots of forced responses and damped nonlinear modes.

- :func:`plot_frequency_response`: amplitude (and phase) against the excitation frequency,
  stable parts solid and unstable parts dashed, folds and bifurcations marked, an
  optional backbone overlaid.
- :func:`plot_phase_resonance`: the phase-resonance backbone (what the phase-locked-loop
  test measures), the damped nonlinear mode (EPMC) and the conservative backbone, with a
  measured backbone overlaid; beside it the modal damping ratio of the EPMC and the force
  level of the phase resonance against amplitude.
- :func:`plot_damping_ratio`: the modal damping ratio ξ/(2Ω) of damped modes against
  amplitude.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

from .common import _figure, _finish, _overlay_measured
from .data import amplitude_name

__all__ = ["plot_frequency_response", "plot_phase_resonance", "plot_damping_ratio", "stability_runs",
           "response_dof"]

_MARKERS = {"fold": ("o", "fold"), "branch_point": ("s", "branch point"),
            "period_doubling": ("D", "period doubling"), "neimark_sacker": ("^", "Neimark–Sacker"),
            "grazing": ("v", "grazing")}


def stability_runs(stable: np.ndarray) -> list[tuple[int, int, bool]]:
    """(start, stop, stable) index runs covering 0..n-1 (stop exclusive); consecutive runs
    share their boundary point so that the drawn curve has no gaps."""
    stable = np.asarray(stable, dtype=bool)
    n = len(stable)
    if n == 0:
        return []
    cuts = np.flatnonzero(stable[1:] != stable[:-1]) + 1
    starts = np.r_[0, cuts]
    stops = np.r_[cuts + 1, n]
    stops[-1] = n
    return [(int(a), int(min(b, n)), bool(stable[a])) for a, b in zip(starts, stops, strict=True)]


def _scale(obj) -> tuple[float, str]:
    gap = obj.gap if getattr(obj, "gap", None) else 0.0
    return (gap, "amplitude / gap") if gap and gap > 0 else (1e-3, "amplitude (mm)")


def response_dof(response) -> str:
    """The DOF whose amplitude a result reports, in words: "DOF 40 (tip deflection w)",
    "DOF 7 (rotation θ at node 4)", "DOF 2 (contact DOF)" or "DOF 5"; "the amplitude DOF"
    when the result does not say which."""
    meta = response.metadata
    dof = meta.get("amplitude_dof")
    model = None
    try:
        model = response.get_model()
    except (ValueError, RuntimeError, AttributeError):
        pass
    if dof is None and model is not None:
        dof = model.amplitude_dof
    if dof is None:
        return "the amplitude DOF"
    dof = int(dof)
    description = dict(meta.get("model") or {})
    if description.get("kind") == "TimoshenkoBeam":
        node = dof // 2 + 1
        where = "tip" if node == int(description["n_elements"]) else f"node {node}"
        words = f"{where} deflection w" if dof % 2 == 0 else f"rotation θ at {where}"
    elif model is not None and model.n_contacts and all(c.dof == dof for c in model.contacts):
        words = "contact DOF"
    else:
        return f"DOF {dof}"
    return f"DOF {dof} ({words})"


def _draw(ax, f, a, stable, color, label, lw=1.4):
    first = True
    for i, j, ok in stability_runs(stable):
        ax.plot(f[i:j], a[i:j], ls="-" if ok else "--", color=color, lw=lw, label=label if first else None)
        first = False


def plot_frequency_response(responses, labels: Sequence[str] | None = None, *, phase: bool = True,
                            backbone=None, measured=None, marks=("fold", "grazing"), path=None, axes=None,
                            title: str | None = None) -> Figure:
    """Amplitude (and phase) against frequency; unstable parts dashed.

    Parameters
    ----------
    responses : FrequencyResponse or sequence of them
    labels : sequence of str, optional
    phase : bool
        Add a second panel with the phase lag (degrees).
    backbone : Branch or sequence of Branch, optional
        Backbones (e.g. the EPMC's) to overlay, dotted.
    measured : MeasuredBackbone or path, optional
        A measured curve (CSV) to overlay.
    marks : sequence of str or "all"
        Kinds of special points to mark (default folds and grazing; "all" adds branch
        points, period doublings and Neimark–Sacker points).
    path : str or Path, optional
    axes : (ax_amplitude, ax_phase), optional
    title : str, optional
        Default: "forced response at DOF d (...)" (:func:`response_dof`); the amplitude
        axis says the measure (the largest |q| of that DOF over a period).
    """
    from ..results.response import FrequencyResponse

    responses = [responses] if isinstance(responses, FrequencyResponse) else list(responses)
    if not responses:
        raise ValueError("no frequency responses to plot")
    if axes is None:
        fig = Figure(figsize=(6.4, 6.4 if phase else 4.6), layout="constrained")
        if phase:
            ax, axp = fig.subplots(2, 1, sharex=True, height_ratios=(2.2, 1))
        else:
            ax, axp = fig.add_subplot(), None
    else:
        ax, axp = axes
        fig = ax.figure
    scale, ylabel = _scale(responses[0])
    if labels is None:
        labels = [f"{r.method}" + (f", H{r.harmonics}" if r.harmonics else "") for r in responses]
    labels = list(labels)
    if len(labels) != len(responses):
        raise ValueError(f"{len(labels)} labels for {len(responses)} responses")
    marked = set()
    for k, (r, label) in enumerate(zip(responses, labels, strict=True)):
        color = f"C{k}"
        _draw(ax, r.frequency, r.amplitude / scale, r.stable, color, label)
        if axp is not None:
            _draw(axp, r.frequency, np.degrees(r.phase), r.stable, color, None)
        kinds = set(_MARKERS) if marks == "all" else set(marks or ())
        if kinds:
            for p in r.special_points:
                if p.kind in kinds and 0 <= p.index < len(r):
                    m, name = _MARKERS[p.kind]
                    ax.plot(r.frequency[p.index], r.amplitude[p.index] / scale, m, color=color, mfc="w", ms=6,
                            label=None if p.kind in marked else name, zorder=5)
                    marked.add(p.kind)
    if backbone is not None:
        from ..results.branch import Branch

        for b in [backbone] if isinstance(backbone, Branch) else list(backbone):
            ax.plot(b.frequency, b.amplitude / scale, ":", color="k", lw=1.2, label=f"backbone ({b.method})")
    if measured is not None:
        if not hasattr(measured, "frequency"):
            from ..analysis.measured import load_measured

            measured = load_measured(measured)
        _overlay_measured(ax, measured, scale)
    ax.plot([], [], "--", color="0.4", label="unstable")
    name = amplitude_name(responses[0])
    ax.set_ylabel(ylabel.replace("amplitude", f"{name}: max |q| over a period", 1))
    ax.set_ylim(bottom=0)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    dofs = {response_dof(r) for r in responses}
    ax.set_title((f"forced response at {dofs.pop()}" if len(dofs) == 1 else "forced responses")
                 if title is None else title, fontsize=10)
    if axp is not None:
        axp.axhline(90, color="0.5", lw=0.8, ls=":")
        axp.set_ylabel("phase lag (°)")
        axp.set_xlabel("excitation frequency (Hz)")
        axp.grid(True, alpha=0.3)
    else:
        ax.set_xlabel("excitation frequency (Hz)")
    return _finish(fig, path)


def plot_damping_ratio(branches, labels: Sequence[str] | None = None, *, ax=None, path=None) -> Figure:
    """Modal damping ratio ξ/(2Ω) (%) of damped nonlinear modes against amplitude."""
    from ..results.branch import Branch

    branches = [branches] if isinstance(branches, Branch) else list(branches)
    fig, ax = _figure(ax, (6.4, 4.0))
    scale, xlabel = _scale(branches[0])
    labels = list(labels) if labels is not None else [f"EPMC H{b.harmonics}" for b in branches]
    for b, label in zip(branches, labels, strict=True):
        ax.plot(b.amplitude / scale, 100 * b.damping_ratio, label=label)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("modal damping ratio (%)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return _finish(fig, path)


def plot_phase_resonance(phase_resonance, epmc=None, conservative=None, *, measured=None, path=None,
                         title: str | None = None) -> Figure:
    """The phase-resonance backbone with the EPMC and conservative backbones and a measured
    curve; right: the EPMC's damping ratio and the phase resonance's force against amplitude.

    Parameters
    ----------
    phase_resonance : Branch
        From :func:`mmshbm.analysis.phase_resonance.phase_resonance_backbone`.
    epmc, conservative : Branch, optional
    measured : MeasuredBackbone or path, optional
    """
    fig = Figure(figsize=(10.5, 4.4), layout="constrained")
    ax, ax2 = fig.subplots(1, 2, width_ratios=(1.4, 1))
    scale, ylabel = _scale(phase_resonance)
    curves = [(conservative, "conservative backbone", "k", ":"), (epmc, "damped mode (EPMC)", "C0", "-"),
              (phase_resonance, "phase resonance (90° lag)", "C3", "--")]
    for b, label, color, ls in curves:
        if b is not None and len(b):
            ax.plot(b.frequency, b.amplitude / scale, ls=ls, color=color, lw=1.5, label=label)
    if measured is not None:
        if not hasattr(measured, "frequency"):
            from ..analysis.measured import load_measured

            measured = load_measured(measured)
        _overlay_measured(ax, measured, scale)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel(ylabel)
    ax.set_ylim(bottom=0)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    if title:
        ax.set_title(title)
    if epmc is not None and len(epmc):
        ax2.plot(epmc.amplitude / scale, 100 * epmc.damping_ratio, color="C0", label="EPMC damping ratio (%)")
    ax2.set_xlabel(ylabel.replace("amplitude", "amplitude"))
    ax2.set_ylabel("modal damping ratio (%)", color="C0")
    ax2.grid(True, alpha=0.3)
    force = phase_resonance.records.get("force")
    if force is not None and len(force):
        ax3 = ax2.twinx()
        ax3.plot(phase_resonance.amplitude / scale, force, color="C3", ls="--", label="phase-resonance force")
        ax3.set_ylabel("force amplitude (N)", color="C3")
    return _finish(fig, path)
