"""``mmshbm.frequency_response``: forced responses by MMS-HBM or a baseline.

The response is continued in the excitation frequency from the low end of the range
(started on the linear response there) by the pseudo-arclength driver of
:mod:`mmshbm.core.continuation`, through the folds of the resonance peak, until the
frequency leaves the range. Floquet multipliers at every point give the stability
(:mod:`mmshbm.methods.mms.stability`), and the bifurcations along the response are named.
"""

from __future__ import annotations

import dataclasses
import difflib
import importlib
import inspect
import logging
import platform
import time

import numpy as np

from .. import _validate as check
from .._threads import blas_limit
from ..core.continuation import ContinuationOptions, continue_branch
from ..core.special_points import SpecialPoint
from ..model.damping import model_has_damping
from ..model.model import Model
from ..results.response import FrequencyResponse
from .mms.forced import Excitation, harmonic_force

__all__ = ["frequency_response", "FORCED_METHODS", "make_forced_problem"]

log = logging.getLogger(__name__)

#: method name -> "module:class" of its forced-response problem
FORCED_METHODS = {
    "mmshbm": "mmshbm.methods.mms.forced:ForcedResponseProblem",
    "penalty": "mmshbm.methods.penalty.forced:PenaltyForcedProblem",
    "shooting": "mmshbm.methods.shooting.forced:ShootingForcedProblem",
}

_CONTINUATION_FIELDS = {f.name for f in dataclasses.fields(ContinuationOptions)}
#: continuation defaults of a frequency response (scaled units: coefficients in gaps, Ω in ω_1)
_DEFAULTS = {"ds": 0.02, "ds_max": 0.3, "max_steps": 3000, "max_newton": 12}


def make_forced_problem(model: Model, force, method: str = "mmshbm", harmonics: int = 5,
                        options: dict | None = None):
    """The forced-response problem of ``method`` on ``model`` (``force``: a vector, an
    :class:`~mmshbm.methods.mms.forced.Excitation` or its JSON form).

    Raises
    ------
    ValueError
        An unknown method; TypeError: an option the method does not take (named).
    """
    if not isinstance(method, str) or method not in FORCED_METHODS:
        raise ValueError(f"unknown method {method!r}; choose one of {sorted(FORCED_METHODS)}")
    if isinstance(force, dict):
        force = Excitation.from_json(force)
    module, cls = FORCED_METHODS[method].split(":")
    if getattr(model, "friction", ()):
        module, cls = {"mmshbm": ("mmshbm.methods.mms.friction_forced", "FrictionForcedProblem"),
                       "penalty": ("mmshbm.methods.penalty.jenkins", "JenkinsForcedProblem"),
                       "shooting": ("mmshbm.methods.shooting.friction", "FrictionShootingProblem")}[method]
    problem_class = getattr(importlib.import_module(module), cls)
    options = dict(options or {})
    params = list(inspect.signature(problem_class).parameters.values())[2:]
    valid = [p.name for p in params]
    unknown = [k for k in options if k not in valid]
    if unknown:
        everything = sorted(set(valid) | _CONTINUATION_FIELDS)
        hints = []
        for name in unknown:
            close = difflib.get_close_matches(name, everything, n=1)
            hints.append(f"{name!r}" + (f" (did you mean {close[0]!r}?)" if close else ""))
        raise TypeError(f"unknown option{'s' if len(unknown) > 1 else ''} {', '.join(hints)} for the forced "
                        f"method {method!r}; method options: {valid}; continuation options: "
                        f"{sorted(_CONTINUATION_FIELDS)}")
    if "harmonics" in valid:
        options["harmonics"] = harmonics
    return problem_class(model, force, **options)


def frequency_response(model: Model, force, frequency_range, harmonics: int = 5, method: str = "mmshbm", *,
                       verbose: bool = False, callback=None, **options) -> FrequencyResponse:
    """Forced response of ``model`` over ``frequency_range``.

    Parameters
    ----------
    model : Model
        The structure, usually damped (``model.with_damping(...)``), massless contact DOFs.
    force : array_like (n_dof,) or Excitation
        Complex amplitude F̂ of the harmonic force Re(F̂ e^{iΩt}) (N) on DOFs with mass, or
        an :class:`~mmshbm.methods.mms.forced.Excitation` (e.g.
        :func:`~mmshbm.methods.mms.forced.base_excitation`).
    frequency_range : (float, float)
        (f_start, f_end) in Hz, 0 < f_start < f_end; the response starts on the linear
        response at f_start and ends where the frequency leaves the range.
    harmonics : int
        H of the harmonic-balance methods.
    method : {"mmshbm", "penalty", "shooting"}
        MMS-HBM, or a baseline on the same forced problem.
    verbose : bool
        Progress bar.
    callback : callable(u, record), optional
        Called with every converged point.
    **options
        Continuation options (``ds``, ``ds_max``, ``max_steps``, ...; defaults
        ``ds=0.02, ds_max=0.3, max_steps=3000, max_newton=12``) and method options
        (MMS-HBM: ``n_samples``, ``r``, ``backend``, ``stability``; penalty:
        ``penalty_stiffness``, ``n_samples``; shooting: ``steps_per_period``).

    Returns
    -------
    FrequencyResponse
        Every converged point with its stability; ``status`` says why it stopped.

    Raises
    ------
    ValueError, TypeError
        Naming the offending input: a model without damping
        (:func:`~mmshbm.model.damping.model_has_damping`), an empty or inverted frequency
        range, a force of the wrong length or on a massless DOF, an unknown method or option.
    """
    if not isinstance(model, Model):
        raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
    f0, f1 = _frequency_range(frequency_range)
    if not model_has_damping(model):
        raise ValueError("the model has no damping: its forced response grows along the backbone without "
                         "bound (no resonance peak to continue around); give it damping with "
                         "model.with_damping(modal_ratio=...) or (rayleigh=(alpha, beta)), or compute the "
                         "conservative backbone, mmshbm.backbone(model)")
    if method not in FORCED_METHODS:
        raise ValueError(f"unknown method {method!r}; choose one of {sorted(FORCED_METHODS)}")
    if method != "shooting":
        check.integer("harmonics", harmonics, minimum=1)
    excitation = force if isinstance(force, Excitation) else harmonic_force(model, force)
    if callback is not None and not callable(callback):
        raise TypeError(f"callback must be callable, got {callback!r}")
    cont = {**_DEFAULTS, **{k: options.pop(k) for k in list(options) if k in _CONTINUATION_FIELDS}}
    # the start sits on f0 up to round-off: the bound below it leaves room for that
    cont["bounds"] = {"frequency": (f0 * (1 - 1e-9), f1), **dict(cont.get("bounds", {}))}
    copts = ContinuationOptions(**cont)
    problem = make_forced_problem(model, excitation, method, harmonics, options)
    progress = None
    if verbose:
        from tqdm.auto import tqdm

        progress = tqdm(desc=f"{method} frequency response", unit="pt", leave=False, disable=None)
    t0 = time.perf_counter()
    try:
        with blas_limit():  # small dense solves: one BLAS thread unless the user chose (mmshbm._threads)
            start = problem.start_point(f0)
            res = continue_branch(problem, start, problem.initial_tangent(), copts,
                                  callback=callback, progress=progress)
    finally:
        if progress is not None:
            progress.close()
    elapsed = time.perf_counter() - t0
    log.info("%s frequency response: %d points, status %s, %.3f s", method, len(res.u), res.status, elapsed)
    return _assemble(model, excitation, problem, res, method, (f0, f1), options, copts, elapsed)


def _frequency_range(frequency_range) -> tuple[float, float]:
    try:
        f0, f1 = frequency_range
    except (TypeError, ValueError):
        raise ValueError(f"frequency_range must be a pair (f_start, f_end) in Hz, got {frequency_range!r}") \
            from None
    f0 = check.positive("frequency_range start", f0)
    f1 = check.positive("frequency_range end", f1)
    if not f0 < f1:
        raise ValueError(f"frequency_range must satisfy f_start < f_end (an empty or inverted range), "
                         f"got {frequency_range!r}")
    return f0, f1


def _assemble(model, excitation, problem, res, method, frange, options, copts, elapsed) -> FrequencyResponse:
    from .mms.stability import classify

    rec = res.records
    n = len(res.u)

    def column(name, fill=np.nan):
        return np.asarray(rec[name], dtype=float) if name in rec else np.full(n, fill)

    special = list(res.special_points)
    amp, force_max = column("amplitude"), column("contact_force_max", 0.0)
    touching = np.flatnonzero(force_max > 0)
    if len(touching) and touching[0] > 0:
        special.insert(1, SpecialPoint("grazing", int(touching[0])))
    stable = np.ones(n, dtype=bool)
    extra = {k: v for k, v in rec.items() if k not in (
        "frequency", "amplitude", "phase", "energy", "contact_force_max", "stable", "floquet_max")}
    if "floquet" in rec and n:
        folds = [p.index for p in special if p.kind == "fold"]
        stable, bifurcations = classify(np.asarray(rec["floquet"]), trivial=0, folds=folds)
        special = special[:-1] + bifurcations + special[-1:]
        special.sort(key=lambda p: (p.index, p.kind == "endpoint"))
    meta = {"model": model.description, "model_gap": float(model.gap), "excitation": excitation.to_json(),
            "frequency_range": list(frange), "method": method, "harmonics": int(problem.H),
            "n_samples": int(problem.N), "method_options": _jsonable(options),
            "continuation": _jsonable(dataclasses.asdict(copts)), "amplitude_dof": int(model.amplitude_dof),
            "elapsed_s": elapsed, "python": platform.python_version(), "numpy": np.__version__}
    return FrequencyResponse(
        frequency=column("frequency"), amplitude=amp, phase=column("phase"), energy=column("energy"),
        contact_force_max=force_max, stable=stable, floquet_max=column("floquet_max"),
        newton_iterations=res.newton_iterations, step_size=res.step_size, states=res.u, status=res.status,
        method=method, harmonics=int(problem.H), special_points=special, metadata=meta,
        solver=problem, residual_histories=res.residual_histories, model=model, records=extra)


def _jsonable(d: dict) -> dict:
    out = {}
    for k, v in d.items():
        if isinstance(v, dict):
            out[k] = _jsonable(v)
        elif isinstance(v, tuple | list):
            out[k] = [x.item() if isinstance(x, np.generic) else x for x in v]
        elif isinstance(v, np.generic):
            out[k] = v.item()
        else:
            out[k] = v
    return out
