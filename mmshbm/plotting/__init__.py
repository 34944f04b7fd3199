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
- :func:`plot_frequency_response`, :func:`plot_phase_resonance`, :func:`plot_damping_ratio`:
  forced responses (unstable parts dashed), phase resonance, damped modes."""

from .backbones import plot_backbone, plot_frequency_energy, plot_peak_contact_force
from .common import _gap, branch_label, dof_label, points_at
from .response import plot_damping_ratio, plot_frequency_response, plot_phase_resonance
from .signals import plot_contact_force, plot_harmonic_content, plot_time_signals
from .studies import plot_figure2, plot_study, study_labels, study_styles, varying_axes

__all__ = ["plot_backbone", "plot_frequency_energy", "plot_time_signals", "plot_contact_force",
           "plot_harmonic_content", "plot_figure2", "plot_peak_contact_force", "study_styles", "points_at",
           "plot_study", "study_labels", "varying_axes", "branch_label", "dof_label", "_gap",
           "plot_frequency_response", "plot_phase_resonance", "plot_damping_ratio"]
