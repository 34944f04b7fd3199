"""``mmshbm.frequency_response``: forced responses by MMS-HBM or a baseline.

The response is continued in the excitation frequency from the low end of the range
(started on the linear response there) by the pseudo-arclength driver of
:mod:`mmshbm.core.continuation`, through the folds of the resonance peak, until the
frequency leaves the range. Floquet multipliers at every point give the stability
(:mod:`mmshbm.methods.mms.stability`), and the bifurcations along the response are named.
"""

from __future__ import annotations

import importlib
import logging
import warnings

import numpy as np

from .. import _validate as check
from .._warnings import BranchWarning
from ..core.status import Status
from ..model.damping import model_has_damping
from ..model.model import Model
from ..results.response import FrequencyResponse
from . import runner
from .mms.forced import Excitation, harmonic_force
from .registry import FORCED_ELEMENT_PROBLEMS, FORCED_FRICTION_PROBLEMS, FORCED_METHODS, check_elements

__all__ = ["frequency_response", "FORCED_METHODS", "make_forced_problem"]

log = logging.getLogger(__name__)

#: continuation defaults of a frequency response (scaled units: coefficients in gaps, Ω in ω_1);
#: branch_point_ds: a change of orientation on a longer step is a jump across a fold (a
#: forced response's branch points are not generic), refined by halving the step
_DEFAULTS = {"ds": 0.02, "ds_max": 0.3, "max_steps": 3000, "max_newton": 12, "branch_point_ds": 1e-3}


def make_forced_problem(model: Model, force, method: str = "mmshbm", harmonics: int = 5,
                        options: dict | None = None):
    """The forced-response problem of ``method`` on ``model`` (``force``: a vector, an
    :class:`~mmshbm.methods.mms.forced.Excitation` or its JSON form).

    Raises
    ------
    ValueError
        An unknown method; TypeError: an option the method does not take (named).
    """
    runner.check_method(method, FORCED_METHODS)
    if isinstance(force, dict):
        force = Excitation.from_json(force)
    module, cls = FORCED_METHODS[method].split(":")
    if getattr(model, "elements", ()):
        check_elements(model, method, forced=True)
        module, cls = FORCED_ELEMENT_PROBLEMS[method].split(":")
    elif getattr(model, "friction", ()):
        module, cls = FORCED_FRICTION_PROBLEMS[method].split(":")
    problem_class = getattr(importlib.import_module(module), cls)
    options = dict(options or {})
    valid = runner.check_option_names(problem_class, options, what=f"the forced method {method!r}", skip=2)
    if "harmonics" in valid:
        options["harmonics"] = harmonics
    return problem_class(model, force, **options)


def frequency_response(model: Model, force, frequency_range, harmonics: int | None = None,
                       method: str = "mmshbm", *, tol: float | None = None, verbose: bool = False,
                       callback=None, checkpoint=None, resume=None, **options) -> FrequencyResponse:
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
    harmonics : int, optional
        H of the harmonic-balance methods; default 5. Not together with ``tol``.
    method : {"mmshbm", "penalty", "shooting"}
        MMS-HBM, or a baseline on the same forced problem.
    tol : float, optional
        Relative tolerance on every point: on its amplitude at its frequency, or, where
        the response is steeper than |d ln A / d ln f| = 10 (near its folds), on its
        frequency at its amplitude. H is chosen per point from an error
        estimate (:mod:`mmshbm.methods.adaptive_forced`, docs/accuracy.md) between
        ``start_harmonics`` (option, default 8) and ``max_harmonics`` (option, default
        64). The response carries ``amplitude_error``, ``frequency_error`` and
        ``records["harmonics"]``; where ``tol`` is not met, a ``"tolerance_not_met"``
        finding (``response.findings``, and a BranchWarning). Method "mmshbm", impact
        and friction contacts; without ``checkpoint``/``resume``/``callback``.
    verbose : bool
        Show the progress on stderr: the points, with the frequency and amplitude of the
        last; a tqdm bar on a terminal, plain lines every few seconds in a pipe or a log
        file (:mod:`mmshbm._progress`).
    callback : callable(u, record), optional
        Called with every converged point.
    checkpoint : str or Path, optional
        Write every converged point to this file as it comes (JSON lines,
        :mod:`mmshbm.core.checkpoint`), as :func:`~mmshbm.methods.backbone.backbone` does.
    resume : str or Path, optional
        Go on from the last point of this checkpoint file: the result equals the
        uninterrupted run point for point. Model, excitation, method, H, N and method
        options must be those of the file; continuation options and the frequency range
        may differ.
    **options
        Continuation options (``ds``, ``ds_max``, ``max_steps``, ...; defaults
        ``ds=0.02, ds_max=0.3, max_steps=3000, max_newton=12, branch_point_ds=1e-3``) and method options
        (MMS-HBM: ``n_samples``, ``r``, ``backend``, ``stability``; penalty:
        ``penalty_stiffness``, ``n_samples``; shooting: ``steps_per_period``).

    Returns
    -------
    FrequencyResponse
        Every converged point with its stability; ``status`` says why it stopped.

    Raises
    ------
    ValueError, TypeError
        Naming the offending input: a model with no contact (its response is linear), a
        model without damping
        (:func:`~mmshbm.model.damping.model_has_damping`), an empty or inverted frequency
        range, a force of the wrong length or on a massless DOF, an unknown method or option.
    """
    runner.check_model(model)
    runner.check_is_nonlinear(model, "forced response")
    f0, f1 = _frequency_range(frequency_range)
    if tol is not None:
        return _to_tolerance(model, force, (f0, f1), tol, harmonics, method, verbose=verbose,
                             callback=callback, checkpoint=checkpoint, resume=resume, **options)
    if harmonics is None:
        harmonics = 5
    if not model_has_damping(model):
        raise ValueError("the model has no damping: its forced response grows along the backbone without "
                         "bound (no resonance peak to continue around); give it damping with "
                         "model.with_damping(modal_ratio=...) or (rayleigh=(alpha, beta)), or compute the "
                         "conservative backbone, mmshbm.backbone(model)")
    runner.check_method(method, FORCED_METHODS)
    runner.check_harmonics(method, harmonics)
    excitation = force if isinstance(force, Excitation) else harmonic_force(model, force)
    runner.check_callback(callback)
    # the start sits on f0 up to round-off: the bound below it leaves room for that
    copts = runner.continuation_options(options, {"frequency": (f0 * (1 - 1e-9), f1)}, _DEFAULTS)
    checkpoint = runner.path_argument("checkpoint", checkpoint)
    resume = runner.path_argument("resume", resume)
    problem = make_forced_problem(model, excitation, method, harmonics, options)
    header = runner.checkpoint_header(model, method, problem, options, excitation=excitation.to_json())
    progress = None
    if verbose:
        progress, callback = _response_progress(method, model.gap, callback)

    def start():
        return (problem.start_point(f0),
                problem.initial_tangent())

    done = runner.run(problem, copts, start, callback=callback, checkpoint=checkpoint, resume=resume,
                      header=header, header_extra={"frequency_range": [f0, f1]}, close=(progress,))
    res = done.result
    log.info("%s frequency response: %d points, status %s, %.3f s", method, len(res.u), res.status,
             done.elapsed_s)
    response = _assemble(model, excitation, problem, res, method, (f0, f1), options, copts, done)
    if not warn_failed_start(response, model, excitation, f0):
        report_incomplete(response, (f0, f1))
    return response


def _to_tolerance(model: Model, force, frange, tol, harmonics, method: str, *, callback, checkpoint, resume,
                  **options) -> FrequencyResponse:
    """The response with H chosen to meet ``tol`` (:mod:`mmshbm.methods.adaptive_forced`)."""
    from .adaptive import check_tolerance
    from .adaptive_forced import FORCED_TOLERANCE_METHODS, response_to_tolerance

    runner.check_method(method, FORCED_METHODS)
    if method not in FORCED_TOLERANCE_METHODS:
        raise ValueError(f"tol is available for the forced method(s) {', '.join(FORCED_TOLERANCE_METHODS)}, "
                         f"not {method!r}: pass harmonics instead")
    if "confirm" in options:
        raise ValueError("confirm (the next-pair check of an estimate that meets tol) is an option of "
                         "the conservative backbone only; a forced response's estimates are not confirmed")
    settings = check_tolerance(tol, harmonics, "mmshbm", options)
    del settings["confirm"]
    for name, value in (("callback", callback), ("checkpoint", checkpoint), ("resume", resume)):
        if value is not None:
            raise ValueError(f"{name} is not available with tol (the points are refined after the "
                             "continuation): pass harmonics for a fixed H")
    if not model_has_damping(model):  # the same refusal as the fixed-H run, before it starts
        return frequency_response(model, force, frange, settings["start_harmonics"], method, **options)
    excitation = force if isinstance(force, Excitation) else harmonic_force(model, force)
    response = response_to_tolerance(model, excitation, frange, method=method, run=frequency_response,
                                     make_problem=make_forced_problem, **settings, **options)
    report_incomplete(response, frange)  # the fixed-H run's finding is not the result's: said again
    return response


def _response_progress(method: str, gap: float, callback):
    """A progress display (:func:`mmshbm._progress.progress_bar`: a tqdm bar on a terminal,
    plain lines in a pipe or log) that counts the points with the frequency and amplitude
    of the last, and the callback that moves it (then calls the user's ``callback``)."""
    from .._progress import progress_bar

    bar = progress_bar(f"{method} frequency response", unit="pt")

    def advance(u, record):
        f, a = float(record.get("frequency", np.nan)), float(record.get("amplitude", np.nan))
        bar.set_postfix_str(f"{f:.4g} Hz, " + (f"{a / gap:.3g} gaps" if gap > 0 else f"{a:.3g} m"),
                            refresh=False)
        bar.update(1)
        if callback is not None:
            callback(u, record)

    return bar, advance


def warn_failed_start(response: FrequencyResponse, model: Model, excitation: Excitation,
                      frequency: float) -> bool:
    """Warn (:class:`~mmshbm.BranchWarning`) when ``response`` is empty because its first
    point at ``frequency`` (Hz) did not converge (status kind "start failed"), saying how
    far the linear response there swings the amplitude DOF (:func:`linear_amplitude`, in
    gaps) and what to do; returns whether it warned."""
    status = Status.parse(response.status)
    if status.kind != Status.START_FAILED:
        return False
    reach = ""
    if model.gap > 0:
        a = linear_amplitude(model, excitation, frequency) / model.gap
        reach = f"; the linear response there swings {a:.3g} gaps" + (
            ", past the stop: the start is in contact" if a > 1 else ", inside the clearance")
    warnings.warn(f"{response.method} frequency response is empty: its first point at {frequency:g} Hz "
                  f"did not converge ({status.detail}){reach}; start the range lower, where the response "
                  "stays off the stops (below grazing), or lower the force", BranchWarning, stacklevel=3)
    return True


def report_incomplete(response: FrequencyResponse, frequency_range) -> bool:
    """Record an ``"incomplete"`` finding (``response.findings``) and warn
    (:class:`~mmshbm.BranchWarning` of that kind) when ``response`` did not reach the end
    of ``frequency_range`` (:attr:`FrequencyResponse.completed` false); returns whether it did."""
    from ..results.diagnostics import incomplete_reason
    from ..results.findings import Finding

    if response.completed:
        return False
    n = len(response)
    f0, f1 = frequency_range
    status = Status.parse(response.status)
    if status.kind == Status.BOUND and status.detail == "frequency":
        why = f"it turned back and left the range at {f0:g} Hz"
    elif status.kind == Status.BOUND:  # a bound of the caller's own (``bounds=``)
        bounds = dict(response.metadata.get("continuation", {}).get("bounds", {}))
        lo, hi = bounds.get(status.detail, (None, None))
        limits = f" [{lo:g}, {hi:g}]" if lo is not None and hi is not None else ""
        why = f"it reached the bound on {status.detail}{limits}"
    else:
        why = incomplete_reason(status, response.metadata)
    at = f" at {float(response.frequency[-1]):.6g} Hz" if n else ""
    message = (f"{response.method} frequency response ended short of {f1:g} Hz{at}: {why} "
               f"(status {str(status)!r}, {n} points)")
    finding = Finding("incomplete", message, n - 1, n - 1)
    response.metadata["checks"] = [*response.metadata.get("checks", []), finding.to_dict()]
    warnings.warn(BranchWarning(message, "incomplete"), stacklevel=3)
    return True


def linear_amplitude(model: Model, excitation: Excitation, frequency: float) -> float:
    """Amplitude (m) of the amplitude DOF in the linear response at ``frequency`` (Hz), the
    stops ignored: |q̂| of (K − Ω²M + iΩC) q̂ = σ(Ω) F̂."""
    import scipy.sparse.linalg as spla

    omega = 2 * np.pi * frequency
    s, _ = excitation.scale(omega)
    A = model.K - omega**2 * model.M
    if model.damping is not None:
        A = A + 1j * omega * model.damping
    q = spla.spsolve(A.tocsc().astype(complex), s * np.asarray(excitation.vector, dtype=complex))
    return float(abs(q[model.amplitude_dof]))


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


def _assemble(model, excitation, problem, res, method, frange, options, copts, done) -> FrequencyResponse:
    rec = res.records
    n = len(res.u)

    def column(name, fill=np.nan):
        return np.asarray(rec[name], dtype=float) if name in rec else np.full(n, fill)

    amp, force_max = column("amplitude"), column("contact_force_max", 0.0)
    special = runner.mark_grazing(res.special_points, force_max, amp, model.gap)
    extra = {k: v for k, v in rec.items() if k not in (
        "frequency", "amplitude", "phase", "energy", "contact_force_max", "stable", "floquet_max")}
    stable, special = runner.name_bifurcations(rec, special, n)
    meta = runner.run_metadata(model, method, problem, options, copts, done, model_gap=float(model.gap),
                               excitation=excitation.to_json(), frequency_range=list(frange),
                               amplitude_dof=int(model.amplitude_dof))
    return FrequencyResponse(
        frequency=column("frequency"), amplitude=amp, phase=column("phase"), energy=column("energy"),
        contact_force_max=force_max, stable=stable, floquet_max=column("floquet_max"),
        newton_iterations=res.newton_iterations, step_size=res.step_size, states=res.u, status=res.status,
        method=method, harmonics=int(problem.H), special_points=special, metadata=meta,
        solver=problem, residual_histories=res.residual_histories, model=model, records=extra)
