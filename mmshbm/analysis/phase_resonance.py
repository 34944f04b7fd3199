"""The phase-resonance backbone, as the phase-locked-loop experiment measures it, next to
the damped (EPMC) and conservative nonlinear modes.

:func:`phase_resonance_backbone` continues the forced responses whose fundamental lags
the force by 90° (:mod:`mmshbm.methods.mms.phase_resonance`) as the force level grows, and
returns a :class:`~mmshbm.results.branch.Branch` (method ``"phase_resonance"``) whose
``records`` hold the force amplitude (N) and phase along it. :func:`compare_backbones`
computes the three curves on one model for a plot (:func:`mmshbm.plotting.response.
plot_phase_resonance`) and tabulates their frequencies at common amplitudes.
"""

from __future__ import annotations

import numpy as np

from ..methods.backbone import backbone
from ..methods.mms.forced import Excitation, harmonic_force
from ..model.model import Model

__all__ = ["phase_resonance_backbone", "compare_backbones"]


def phase_resonance_backbone(model: Model, force, harmonics: int = 5, max_amplitude: float | None = None,
                             **options):
    """The phase-resonance backbone of ``model`` driven by the force pattern ``force``.

    Parameters
    ----------
    model : Model
        Damped, with a massless amplitude DOF (the beam's tip).
    force : array_like (n_dof,) or Excitation
        The force pattern; its level is continued (``records["force"]``, N).
    harmonics : int
    max_amplitude : float, optional
        Stop at this amplitude (m, the backbone convention); default 10 gaps.
    **options
        Continuation options and MMS-HBM options (``n_samples``, ``projection``, ...),
        as for :func:`mmshbm.backbone`.

    Returns
    -------
    Branch
        ``method == "phase_resonance"``; ``records["force"]`` (N), ``records["phase"]``.
    """
    if model.damping is None:
        raise ValueError("phase resonance needs a damped model (model.with_damping(...)): without "
                         "damping the force that holds the phase is zero")
    exc = force if isinstance(force, Excitation) else harmonic_force(model, force)
    return backbone(model, harmonics=harmonics, method="phase_resonance", max_amplitude=max_amplitude,
                    force=exc.to_json(), **options)


def compare_backbones(model: Model, force, harmonics: int = 5, max_amplitude: float | None = None,
                      amplitudes=None, **options) -> dict:
    """The conservative backbone (damping removed), the damped nonlinear mode (EPMC) and the
    phase-resonance backbone of ``model``, and their frequencies (Hz) at ``amplitudes`` (m,
    default 1.5, 3 and 6 gaps).

    Returns
    -------
    dict
        ``{"conservative": Branch, "epmc": Branch, "phase_resonance": Branch,
        "table": {name: frequencies (n_amplitudes,)}, "amplitudes": ndarray}``.
    """
    from dataclasses import replace

    undamped = replace(model, damping=None)
    branches = {
        "conservative": backbone(undamped, harmonics=harmonics, max_amplitude=max_amplitude, **options),
        "epmc": backbone(model, harmonics=harmonics, max_amplitude=max_amplitude, **options),
        "phase_resonance": phase_resonance_backbone(model, force, harmonics, max_amplitude, **options),
    }
    if amplitudes is None:
        amplitudes = np.array([1.5, 3.0, 6.0]) * model.gap
    amps = np.asarray(amplitudes, dtype=float)
    table = {name: np.array([b.frequency_at(a) for a in amps]) for name, b in branches.items()}
    return {**branches, "table": table, "amplitudes": amps}
