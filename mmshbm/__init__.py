"""mmshbm: nonlinear modes of finite-element structures with impact.

The Massless Mixed Shooting-Harmonic Balance Method (Schreyer, Peter & Leine) computes
backbone curves of structures whose massless contact node meets a rigid stop: the linear
structure is condensed per harmonic onto the few contact DOFs, the Signorini law is
written with a proximal point function, and Newton iterates only in the contact DOFs'
Fourier coefficients and the frequency.

Public API (imported lazily so that ``import mmshbm`` stays cheap)::

    beam = mmshbm.default_beam()
    model = beam.model(21)
    branch = mmshbm.backbone(model, harmonics=5)
"""

from __future__ import annotations

import importlib

from . import _entry_points

# the results call functions of the methods layer above them (to rebuild a solver, redo a
# run), which the methods package registers when imported: import it when one is missing
_entry_points.add_loader(lambda: importlib.import_module("mmshbm.methods"))

__version__ = "0.2.0"

# public name -> module that defines it
_LAZY = {
    "Model": "mmshbm.model.model",
    "TimoshenkoBeam": "mmshbm.fe.beam",
    "default_beam": "mmshbm.fe.beam",
    "one_dof_oscillator": "mmshbm.fe.oscillator",
    "OneDofOscillator": "mmshbm.fe.oscillator",
    "ClearanceOscillator": "mmshbm.fe.oscillator",
    "backbone": "mmshbm.methods.backbone",
    "frequency_response": "mmshbm.methods.frequency_response",
    "FrequencyResponse": "mmshbm.results.response",
    "harmonic_force": "mmshbm.methods.mms.forced",
    "base_excitation": "mmshbm.methods.mms.forced",
    "ContinuationOptions": "mmshbm.core.continuation",
    "Branch": "mmshbm.results.branch",
    "fit_material": "mmshbm.analysis.identification",
    "fit_contact_stiffness": "mmshbm.analysis.contact_fit",
    "solid_beam_model": "mmshbm.fe.solid",
    "tip_damper_model": "mmshbm.fe.damper",
    "tip_damper_force": "mmshbm.fe.damper",
    "solid_tip_friction_model": "mmshbm.fe.damper",
    "lap_joint": "mmshbm.fe.lap_joint",
    "LapJoint": "mmshbm.fe.lap_joint",
    "normal_load_study": "mmshbm.analysis.friction_study",
    "branch_stability": "mmshbm.methods.mms.stability",
    "phase_resonance_backbone": "mmshbm.analysis.phase_resonance",
    "load": "mmshbm.io",
    "read_fe": "mmshbm.model.readers",
    "FEMatrices": "mmshbm.model.readers",
    "MmshbmWarning": "mmshbm._warnings",
    "BranchWarning": "mmshbm._warnings",
    "ModelWarning": "mmshbm._warnings",
}
# submodule attribute -> module (the layered packages, and the exact reference)
_SUBMODULES = {
    "model": "mmshbm.model", "fe": "mmshbm.fe", "core": "mmshbm.core", "results": "mmshbm.results",
    "methods": "mmshbm.methods", "analysis": "mmshbm.analysis", "io": "mmshbm.io",
    "plotting": "mmshbm.plotting", "cli": "mmshbm.cli", "elements": "mmshbm.elements",
    "exact": "mmshbm.exact",
}

__all__ = sorted(_LAZY) + ["__version__", "elements"]


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    if name in _SUBMODULES:
        return importlib.import_module(_SUBMODULES[name])
    raise AttributeError(f"module 'mmshbm' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY) | set(_SUBMODULES))
