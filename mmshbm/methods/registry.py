"""The continuation problems of the methods, by name.

``METHODS`` maps a method name to the ``module:class`` of its continuation problem,
``FORCED_METHODS`` (``FORCED_FRICTION_PROBLEMS`` with friction contacts) to that of its
forced-response problem, and ``METHOD_INFO`` to its capabilities (:class:`MethodInfo`; the table lives in the
dependency-free :mod:`mmshbm._method_info`, so that the CLI and the results read it
without importing the methods); :func:`make_problem` builds a problem (importing only that
method's module), validating the option names against the class's constructor.

Elements (:mod:`mmshbm.elements`): ``METHOD_ELEMENTS`` and ``FORCED_METHOD_ELEMENTS``
name the element kinds each method's backbone and forced response take, and
``ELEMENT_PROBLEMS`` / ``FORCED_ELEMENT_PROBLEMS`` the problem that runs a model with
elements; :func:`check_elements` refuses any other combination by name.
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

__all__ = ["ELEMENT_PROBLEMS", "FORCED_ELEMENT_PROBLEMS", "FORCED_FRICTION_PROBLEMS", "FORCED_METHODS",
           "FORCED_METHOD_ELEMENTS", "METHODS",
           "METHOD_ELEMENTS", "METHOD_INFO", "MethodInfo", "backbone_methods", "check_elements",
           "forced_methods", "is_harmonic_balance", "make_problem", "method_info", "method_options"]

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

#: forced method name -> "module:class" of its forced-response problem
FORCED_METHODS = {
    "mmshbm": "mmshbm.methods.mms.forced:ForcedResponseProblem",
    "penalty": "mmshbm.methods.penalty.forced:PenaltyForcedProblem",
    "shooting": "mmshbm.methods.shooting.forced:ShootingForcedProblem",
}
#: forced method name -> "module:class" of the forced problem of a model with friction contacts
FORCED_FRICTION_PROBLEMS = {
    "mmshbm": "mmshbm.methods.mms.friction_forced:FrictionForcedProblem",
    "penalty": "mmshbm.methods.penalty.jenkins:JenkinsForcedProblem",
    "shooting": "mmshbm.methods.shooting.friction:FrictionShootingProblem",
}

_CONTINUATION_FIELDS = CONTINUATION_FIELDS

#: the smooth and piecewise-linear elements (``Element.kind``) that MMS-HBM takes by AFT
_AFT_ELEMENTS = ("cubic_spring", "polynomial_spring", "compliant_stop")
#: method name -> the element kinds its backbone takes (a method not named takes none)
METHOD_ELEMENTS = {"mmshbm": _AFT_ELEMENTS, "penalty": _AFT_ELEMENTS, "penalty-reduced": (),
                   "shooting": _AFT_ELEMENTS, "epmc": _AFT_ELEMENTS, "phase_resonance": ()}
#: forced method name -> the element kinds its frequency response takes
FORCED_METHOD_ELEMENTS = {"mmshbm": _AFT_ELEMENTS, "penalty": (), "shooting": ()}
#: method name -> "module:class" of the backbone problem of a model with elements
ELEMENT_PROBLEMS = {"mmshbm": "mmshbm.methods.mms.smooth:ElementBackboneProblem",
                    "penalty": "mmshbm.methods.penalty.elements:ElementHBMProblem",
                    "shooting": "mmshbm.methods.shooting.elements:ElementShootingProblem",
                    "epmc": "mmshbm.methods.mms.smooth_epmc:ElementEPMCProblem"}
#: forced method name -> "module:class" of the forced problem of a model with elements
FORCED_ELEMENT_PROBLEMS = {"mmshbm": "mmshbm.methods.mms.smooth_forced:ElementForcedProblem"}


def check_elements(model: Model, method: str, forced: bool = False) -> None:
    """NotImplementedError naming the elements of ``model`` that ``method`` (its backbone,
    or with ``forced`` its frequency response) does not take, and the methods that do;
    also for elements beside friction contacts, which no method takes yet."""
    elements = getattr(model, "elements", ())
    if not elements:
        return
    table = FORCED_METHOD_ELEMENTS if forced else METHOD_ELEMENTS
    what = "frequency response" if forced else "backbone"
    if getattr(model, "friction", ()):
        raise NotImplementedError(f"no {what} method takes elements together with friction contacts yet")
    taken = table.get(method, ())
    refused = sorted({e.kind for e in elements if e.kind not in taken})
    if refused:
        able = sorted(m for m, kinds in table.items() if set(refused) <= set(kinds))
        hint = f": use method {' or '.join(repr(m) for m in able)}" if able else ""
        raise NotImplementedError(f"method {method!r} ({what}) does not take the element"
                                  f"{'s' if len(refused) > 1 else ''} {', '.join(refused)}{hint}")


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
    if getattr(model, "elements", ()):
        check_elements(model, method)
        module, cls = ELEMENT_PROBLEMS[method].split(":")
    elif getattr(model, "friction", ()):
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

