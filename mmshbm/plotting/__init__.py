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
- :func:`plot_figure2`: the paper's Figure 2 layout from a study over H and elements.
- :func:`plot_study`: the backbones of a study over any coordinates (each branch in
  units of its own gap, every varying coordinate in the labels).
- :func:`plot_family_grid`, :func:`plot_convergence`: a study over H and elements, its
  first-mode family per element count and the convergence of its table.
- :func:`plot_error_band`: a backbone with the band of its per-point error estimate.
- :func:`plot_frequency_response`, :func:`plot_phase_resonance`, :func:`plot_damping_ratio`:
  forced responses (unstable parts dashed), phase resonance, damped modes."""

from __future__ import annotations

import importlib

#: public name -> submodule (imported on first use: matplotlib costs ~0.3 s to import,
#: and ``mmshbm.plotting.data`` is needed without it)
_LAZY = {
    "plot_backbone": "backbones", "plot_frequency_energy": "backbones",
    "plot_peak_contact_force": "backbones",
    "BranchData": "data", "reference_frequencies": "data",
    "_gap": "data", "branch_label": "common", "dof_label": "common", "points_at": "common",
    "plot_damping_ratio": "response", "plot_frequency_response": "response",
    "plot_phase_resonance": "response",
    "plot_contact_force": "signals", "plot_harmonic_content": "signals", "plot_time_signals": "signals",
    "plot_figure2": "studies", "plot_study": "studies", "study_labels": "studies", "study_styles": "studies",
    "varying_axes": "studies", "plot_family_grid": "grids", "plot_convergence": "grids",
    "plot_error_band": "accuracy",
}

__all__ = ["plot_backbone", "plot_frequency_energy", "plot_time_signals", "plot_contact_force",
           "plot_harmonic_content", "plot_figure2", "plot_peak_contact_force", "study_styles", "points_at",
           "plot_study", "study_labels", "varying_axes", "branch_label", "dof_label", "_gap",
           "plot_frequency_response", "plot_phase_resonance", "plot_damping_ratio", "BranchData",
           "reference_frequencies", "plot_family_grid", "plot_convergence", "plot_error_band"]


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
