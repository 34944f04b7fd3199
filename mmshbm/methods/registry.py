"""The continuation problems of the methods, by name.

``METHODS`` maps a method name to the ``module:class`` of its continuation problem and
``METHOD_INFO`` to its capabilities (:class:`MethodInfo`; the table lives in the
dependency-free :mod:`mmshbm._method_info`, so that the CLI and the results read it
without importing the methods); :func:`make_problem` builds a problem (importing only that
method's module), validating the option names against the class's constructor.
"""

from __future__ import annotations

import importlib
import inspect

from .._method_info import (
    METHOD_INFO,
    MethodInfo,
    backbone_methods,
    forced_methods,
    is_harmonic_balance,
    method_info,
)
from ..model.model import Model
from .runner import CONTINUATION_FIELDS, check_option_names

__all__ = ["METHODS", "METHOD_INFO", "MethodInfo", "make_problem", "method_options", "method_info",
           "is_harmonic_balance", "backbone_methods", "forced_methods"]

#: method name -> "module:class" of its continuation problem
METHODS = {
    "mmshbm": "mmshbm.methods.mms.conservative:MMSHBMProblem",
    "penalty": "mmshbm.methods.penalty.hbm:PenaltyHBMProblem",
    "penalty-reduced": "mmshbm.methods.penalty.reduced:ReducedPenaltyHBMProblem",
    "shooting": "mmshbm.methods.shooting.conservative:ShootingProblem",
    # damped nonlinear modes: mmshbm.backbone(damped_model) dispatches here
    "epmc": "mmshbm.methods.mms.epmc:EPMCProblem",
    "phase_resonance": "mmshbm.methods.mms.phase_resonance:PhaseResonanceProblem",
}

_CONTINUATION_FIELDS = CONTINUATION_FIELDS


def make_problem(model: Model, method: str = "mmshbm", **options):
    """Build the continuation problem of ``method`` on ``model`` (``options`` go to its
    constructor).

    Raises
    ------
    ValueError
        For an unknown method name.
    TypeError
        For an option the method's constructor does not take (named, with the nearest
        valid name).
    """
    if not isinstance(method, str) or method not in METHODS:
        raise ValueError(f"unknown method {method!r}; choose one of {sorted(METHODS)}")
    module, cls = METHODS[method].split(":")
    if getattr(model, "friction", ()):
        if method != "epmc":
            raise NotImplementedError(f"method {method!r} does not yet take friction contacts: use 'mmshbm'")
        module, cls = "mmshbm.methods.mms.friction_epmc", "FrictionEPMCProblem"
    try:
        problem_class = getattr(importlib.import_module(module), cls)
    except ImportError as err:  # pragma: no cover - a baseline not installed
        raise ValueError(f"method {method!r} is not available: {err}") from None
    _check_option_names(method, problem_class, options)
    return problem_class(model, **options)


def method_options(method: str) -> list[str]:
    """Names of the options the constructor of ``method``'s problem takes (besides the model)."""
    module, cls = METHODS[method].split(":")
    problem_class = getattr(importlib.import_module(module), cls)
    params = list(inspect.signature(problem_class).parameters.values())[1:]
    return [p.name for p in params if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]


def _check_option_names(method: str, problem_class, options: dict) -> None:
    check_option_names(problem_class, options, what=f"method {method!r}", extra_names=_BACKBONE_ARGUMENTS)


_BACKBONE_ARGUMENTS = ("harmonics", "method", "max_amplitude", "start_amplitude", "bounds", "verbose",
                       "callback", "checkpoint", "resume")

