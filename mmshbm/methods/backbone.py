"""``mmshbm.backbone``: one entry point for every method (the problems are named in
:mod:`mmshbm.methods.registry`)."""

from __future__ import annotations

import logging
from collections.abc import Mapping

import numpy as np

from .. import _validate as check
from ..model.model import Model
from ..results.branch import Branch
from . import runner
from .limits import check_resources
from .registry import METHODS, is_harmonic_balance, make_problem, method_info

__all__ = ["backbone", "backbone_method", "amplitude_range"]

log = logging.getLogger(__name__)

def backbone(model: Model, harmonics: int | None = None, method: str = "mmshbm",
             max_amplitude: float | None = None, *, tol: float | None = None,
             start_amplitude: float | None = None, bounds: dict | None = None, verbose: bool = False,
             callback=None, checkpoint=None, resume=None, **options) -> Branch:
    """Compute a nonlinear mode (backbone curve) of ``model``.

    Parameters
    ----------
    model : Model
        The structure, e.g. ``mmshbm.default_beam().model(21)``.
    harmonics : int, optional
        Highest harmonic H of the Fourier ansatz (harmonic-balance methods); default 5.
        Not together with ``tol``.
    method : {"mmshbm", "penalty", "shooting", "epmc"}
        MMS-HBM, or one of the baselines. A model with damping (``model.damping``, or
        friction contacts) gets its damped nonlinear mode with "mmshbm": the method becomes
        "epmc" (:mod:`mmshbm.methods.mms.epmc`, :func:`backbone_method`), which the branch's
        ``method`` says, with ``metadata["requested_method"] = "mmshbm"`` and a log record
        (INFO); the branch's ``damping_ratio`` is ξ/(2Ω).
    max_amplitude : float, optional
        Stop at this amplitude (m) of the contact DOF; default 10 gaps.
    tol : float, optional
        Relative tolerance on the frequency of every point at its amplitude: H is chosen
        per point from an error estimate (:mod:`mmshbm.methods.adaptive`, docs/accuracy.md),
        between ``start_harmonics`` (option, default 8) and ``max_harmonics`` (option,
        default 64: the largest H of any solve, the estimates' included); ``confirm``
        (option, default True, conservative backbones only) checks an estimate that meets
        ``tol`` on the next pair of H (``records["error_confirmed"]``). The
        branch carries ``frequency_error`` and ``records["harmonics"]`` (the H of each
        point), ``records["error_extrapolated"]`` (1 where the estimate was divided by
        the contraction of H's last doubling: a point out of reach, or at the cap) and
        ``records["error_not_estimated"]`` (1 at a point off the family front in contact
        whose 2H solve had no cheap start: its estimate is NaN, no part of the
        tolerance's findings or counts); where ``tol`` is not met on the family front it
        has a ``"tolerance_not_met"`` finding. Methods "mmshbm" and "penalty"
        on conservative models, and the damped nonlinear mode ("epmc", on the damping
        ratio too: ``records["damping_error"]``, :mod:`mmshbm.methods.adaptive_damped`);
        without ``checkpoint``/``resume``/``callback``.
    start_amplitude : float, optional
        Amplitude (m) of the first point, on the linear mode, below ``max_amplitude``;
        default half the gap, or less where a contact of the linear mode would reach its
        stop first (several contacts): half the amplitude at which the first contact
        closes; at most half of ``max_amplitude``.
    bounds : dict, optional
        Further bounds on recorded quantities, e.g. ``{"frequency": (0, 60)}`` (Hz),
        ``{"energy": (0, 1.0)}`` (J).
    verbose : bool
        Show the progress on stderr: the amplitude toward ``max_amplitude`` (in gaps), the
        frequency and the number of points; a tqdm bar on a terminal, plain lines every few
        seconds in a pipe or a log file (:mod:`mmshbm._progress`).
    callback : callable(u, record), optional
        Called with every converged point.
    checkpoint : str or Path, optional
        Write every converged point to this file as it comes (JSON lines, see
        :mod:`mmshbm.core.checkpoint`); a killed or interrupted run leaves a valid file.
    resume : str or Path, optional
        Go on from the last point of this checkpoint file, with its tangent and step:
        the result equals the uninterrupted run point for point. The model, method, H,
        N and method options must be those of the file; continuation options and
        bounds may differ (e.g. a larger ``max_steps`` extends a finished run). Pass
        the same path as ``checkpoint`` to keep appending to it.
    **options
        Continuation options (:class:`ContinuationOptions`: ``ds``, ``ds_min``,
        ``ds_max``, ``max_steps``, ``newton_tol``, ``max_newton``, ...) and method options
        (MMS-HBM: ``n_samples``, ``r``, ``mode``, ``backend``; penalty:
        ``penalty_stiffness``; shooting: ``steps_per_period``). A name that is neither
        raises TypeError.

    Returns
    -------
    Branch
        Every converged point, with ``status`` saying why the branch stopped.

    Raises
    ------
    TypeError, ValueError
        For bad input, naming the offending argument and value; a model with no contact
        (neither a stop nor friction: its backbone is its linear mode).
    """
    runner.check_model(model)
    runner.check_is_nonlinear(model, "backbone")
    runner.check_method(method, METHODS)
    if tol is not None:
        return _to_tolerance(model, tol, harmonics, method, max_amplitude, start_amplitude=start_amplitude,
                             bounds=bounds, verbose=verbose, callback=callback, checkpoint=checkpoint,
                             resume=resume, **options)
    if harmonics is None:
        harmonics = 5
    requested = method
    method = backbone_method(model, method)
    if method != requested:
        log.info("the model is damped: its backbone is the damped nonlinear mode (method %r, asked %r)",
                 method, requested)
    runner.check_harmonics(method, harmonics)
    runner.check_callback(callback)
    gap = model.gap
    default_start = start_amplitude is None
    start_amplitude, max_amplitude = amplitude_range(model, start_amplitude, max_amplitude,
                                                     options.get("mode", 1))
    if bounds is not None and not isinstance(bounds, Mapping):
        raise TypeError(f"bounds must be a dict name -> (lo, hi), got {type(bounds).__name__} {bounds!r}")
    copts = runner.continuation_options(options, {"amplitude": (0.0, max_amplitude), **dict(bounds or {})})
    if is_harmonic_balance(method):
        options["harmonics"] = harmonics
    checkpoint = runner.path_argument("checkpoint", checkpoint)
    resume = runner.path_argument("resume", resume)
    check_resources(model, method, options)  # before any allocation: a clear error, not a MemoryError
    problem = make_problem(model, method, **options)
    if default_start and gap > 0 and problem.open_amplitude is not None:
        # the linear mode is a solution only while every contact is open
        start_amplitude = min(start_amplitude, 0.5 * problem.open_amplitude())
    # what a checkpoint file records and a resumed run compares (nothing to build without either)
    header = (runner.checkpoint_header(model, method, problem, options)
              if checkpoint is not None or resume is not None else None)

    progress = None
    if verbose:
        progress, callback = _amplitude_progress(method, max_amplitude, gap, callback)

    def start():
        return problem.linear_mode_point(start_amplitude), problem.initial_tangent()

    done = runner.run(problem, copts, start, callback=callback, checkpoint=checkpoint, resume=resume,
                      header=header, close=(progress,),
                      header_extra={"start_amplitude": start_amplitude, "max_amplitude": max_amplitude})
    res = done.result
    rec = res.records
    n = len(res.u)

    def column(name):
        return rec[name] if name in rec else np.full(n, np.nan)

    amp = column("amplitude")
    special = runner.mark_grazing(res.special_points, column("contact_force_max"), amp, gap)
    if problem.branch_records is not None and n:  # records computed once for the whole branch
        rec.update(problem.branch_records(res.u))
    special = runner.name_internal_resonances(problem, rec, special)
    log.info("%s backbone: %d points, status %s, %.3f s", method, n, res.status, done.elapsed_s)
    metadata = runner.run_metadata(model, method, problem, options, copts, done, max_amplitude=max_amplitude,
                                   start_amplitude=start_amplitude)
    if method != requested:
        metadata["requested_method"] = requested
    branch = Branch(
        frequency=column("frequency"), amplitude=amp, energy=column("energy"),
        contact_force_max=column("contact_force_max"), newton_iterations=res.newton_iterations,
        step_size=res.step_size, states=res.u, status=res.status, method=method,
        harmonics=int(problem.H), special_points=special, metadata=metadata,
        solver=problem, residual_histories=res.residual_histories,
        records={k: v for k, v in rec.items() if k not in _BRANCH_COLUMNS})
    branch.check()  # records mode_share, warns (BranchWarning) when the branch is not what it seems
    return branch


def _to_tolerance(model: Model, tol, harmonics, method: str, max_amplitude, *, callback, checkpoint, resume,
                  **kwargs) -> Branch:
    """The backbone with H chosen to meet ``tol`` (:mod:`mmshbm.methods.adaptive`)."""
    from .adaptive import backbone_to_tolerance, check_tolerance

    damped = backbone_method(model, method) == "epmc"  # the damped nonlinear mode: its own measures
    kwargs_given = set(kwargs)
    settings = check_tolerance(tol, harmonics, "mmshbm" if damped else backbone_method(model, method), kwargs)
    for name, value in (("callback", callback), ("checkpoint", checkpoint), ("resume", resume)):
        if value is not None:
            raise ValueError(f"{name} is not available with tol (the points are refined after the "
                             "continuation): pass harmonics for a fixed H")
    if damped:
        from .adaptive_damped import damped_mode_to_tolerance

        if "confirm" in kwargs_given:
            raise ValueError("confirm (the next-pair check of an estimate that meets tol) is an option of "
                             "the conservative backbone only; a damped mode's estimates are not confirmed")
        del settings["confirm"]

        return damped_mode_to_tolerance(model, run=backbone, method=method, max_amplitude=max_amplitude,
                                        **settings, **kwargs)
    return backbone_to_tolerance(model, run=backbone, method=method, max_amplitude=max_amplitude, **settings,
                                 **kwargs)


def amplitude_range(model: Model, start_amplitude: float | None, max_amplitude: float | None,
                    mode: int = 1) -> tuple[float, float]:
    """The checked (start, max) amplitudes (m) of a backbone of ``model`` (see
    :func:`backbone`): max by default 10 gaps; start by default half the gap (for a
    friction model without gap, half the amplitude where slip begins, else 1 % of max),
    and at most half of max, so that a small max amplitude needs no start of its own.

    Raises
    ------
    ValueError
        A non-positive amplitude, no max for a model without gap, a max the amplitude DOF
        cannot reach, or a given start not below max (both in m and in gaps).
    """
    gap = model.gap
    if max_amplitude is None:
        if gap == 0:
            raise ValueError("the model's gap is 0: pass max_amplitude (m)")
        max_amplitude = 10.0 * gap
    max_amplitude = check.positive("max_amplitude", max_amplitude)
    model.check_amplitude_reach(max_amplitude)
    if start_amplitude is None:
        start_amplitude = 0.5 * gap if gap > 0 else 0.01 * max_amplitude
        if model.friction and gap == 0:  # start stuck: below the amplitude where slip begins
            from .mms.friction_epmc import stuck_mode

            start_amplitude = min(start_amplitude, 0.5 * stuck_mode(model, mode)[2])
        start_amplitude = min(start_amplitude, 0.5 * max_amplitude)
    start_amplitude = check.positive("start_amplitude", start_amplitude)
    if start_amplitude >= max_amplitude:
        def both(a):
            return f"{a:g} m = {a / gap:.4g} gaps" if gap > 0 else f"{a:g} m"

        raise ValueError(f"start_amplitude ({both(start_amplitude)}) must be below max_amplitude "
                         f"({both(max_amplitude)}): lower start_amplitude or raise max_amplitude (or leave "
                         "start_amplitude out: the default starts below max_amplitude)")
    return start_amplitude, max_amplitude


def backbone_method(model: Model, method: str) -> str:
    """The method that computes the backbone asked of ``method``: "mmshbm" on a model with
    damping (viscous, ``model.damping``, or friction contacts) is its damped nonlinear mode,
    "epmc" (:mod:`mmshbm.methods.mms.epmc`); any other name is itself."""
    damped = method_info(method).damped_variant
    if damped is not None and (model.damping is not None or model.friction):
        return damped
    return method


def _amplitude_progress(method: str, max_amplitude: float, gap: float, callback):
    """A progress display (:func:`mmshbm._progress.progress_bar`: a tqdm bar on a terminal,
    plain lines in a pipe or log) that counts the amplitude (in gaps, else mm) toward its
    bound, and the callback that moves it (then calls the user's ``callback``)."""
    from .._progress import progress_bar

    scale, unit = (gap, "gap") if gap > 0 else (1e-3, "mm")
    total = max_amplitude / scale
    bar = progress_bar(f"{method} backbone", unit=unit, total=total,
                       bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.3g}/{total:.3g} " + unit
                       + " [{elapsed}{postfix}]")
    points = [0]

    def advance(u, record):
        points[0] += 1
        bar.n = min(max(float(record.get("amplitude", 0.0)) / scale, 0.0), total)
        f = float(record.get("frequency", float("nan")))
        bar.set_postfix_str(f"{f:.4g} Hz, {points[0]} points", refresh=False)
        bar.refresh()
        if callback is not None:
            callback(u, record)

    return bar, advance


_BRANCH_COLUMNS = ("frequency", "amplitude", "energy", "contact_force_max")
