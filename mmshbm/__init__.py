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

__version__ = "0.1.0"

# public name -> module that defines it
_LAZY = {
    "Model": "mmshbm.model",
    "TimoshenkoBeam": "mmshbm.fe.beam",
    "default_beam": "mmshbm.fe.beam",
    "one_dof_oscillator": "mmshbm.examples",
    "OneDofOscillator": "mmshbm.examples",
    "backbone": "mmshbm.api",
    "ContinuationOptions": "mmshbm.continuation",
    "Branch": "mmshbm.results",
    "fit_material": "mmshbm.identification",
}
_SUBMODULES = {"exact", "studies", "plotting", "harmonics", "kernels", "condense", "continuation",
               "baselines", "fe", "examples", "results", "measured", "identification",
               "cli", "benchmarking", "checkpoint", "api", "model", "mms_hbm"}

__all__ = sorted(_LAZY) + ["__version__"]


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    if name in _SUBMODULES:
        return importlib.import_module(f"mmshbm.{name}")
    raise AttributeError(f"module 'mmshbm' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY) | _SUBMODULES)
