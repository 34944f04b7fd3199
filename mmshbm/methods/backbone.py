"""``mmshbm.backbone``: one entry point for every method (the problems are named in
:mod:`mmshbm.methods.registry`)."""

from __future__ import annotations

import dataclasses
import logging
import platform
import time
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from .. import _validate as check
from .._threads import blas_limit
from ..core.continuation import ContinuationOptions, continue_branch
from ..core.resonances import internal_resonances
from ..core.special_points import SpecialPoint
from ..core.status import Status
from ..model.model import Model
from ..results.branch import Branch
from .limits import check_resources
from .registry import _CONTINUATION_FIELDS, METHODS, make_problem, method_options  # noqa: F401 - public here since 0.1

__all__ = ["backbone"]

log = logging.getLogger(__name__)

def backbone(model: Model, harmonics: int = 5, method: str = "mmshbm", max_amplitude: float | None = None,
             *, start_amplitude: float | None = None, bounds: dict | None = None, verbose: bool = False,
             callback=None, checkpoint=None, resume=None, **options) -> Branch:
    """Compute a nonlinear mode (backbone curve) of ``model``.

    Parameters
    ----------
    model : Model
        The structure, e.g. ``mmshbm.default_beam().model(21)``.
    harmonics : int
        Highest harmonic H of the Fourier ansatz (harmonic-balance methods).
    method : {"mmshbm", "penalty", "shooting", "epmc"}
        MMS-HBM, or one of the baselines. A model with damping (``model.damping``) gets
        its damped nonlinear mode with "mmshbm" ("epmc", :mod:`mmshbm.methods.mms.epmc`; the
        branch's ``damping_ratio`` is ξ/(2Ω)).
    max_amplitude : float, optional
        Stop at this amplitude (m) of the contact DOF; default 10 gaps.
    start_amplitude : float, optional
        Amplitude (m) of the first point, on the linear mode; default half the gap, or
        less where a contact of the linear mode would reach its stop first (several
        contacts): half the amplitude at which the first contact closes.
    bounds : dict, optional
        Further bounds on recorded quantities, e.g. ``{"frequency": (0, 60)}`` (Hz),
        ``{"energy": (0, 1.0)}`` (J).
    verbose : bool
        Show a progress bar (tqdm) that counts the amplitude toward ``max_amplitude`` (in
        gaps), with the frequency and the number of points.
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
        For bad input, naming the offending argument and value.
    """
    if not isinstance(model, Model):
        raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
    if not isinstance(method, str) or method not in METHODS:
        raise ValueError(f"unknown method {method!r}; choose one of {sorted(METHODS)}")
    # the backbone of a damped model (viscous or friction) is its damped nonlinear mode (EPMC)
    if method == "mmshbm" and (model.damping is not None or model.friction):
        method = "epmc"
    if method != "shooting":
        check.integer("harmonics", harmonics, minimum=1)
    if callback is not None and not callable(callback):
        raise TypeError(f"callback must be callable, got {type(callback).__name__} {callback!r}")
    gap = model.gap
    if max_amplitude is None:
        if gap == 0:
            raise ValueError("the model's gap is 0: pass max_amplitude (m)")
        max_amplitude = 10.0 * gap
    max_amplitude = check.positive("max_amplitude", max_amplitude)
    model.check_amplitude_reach(max_amplitude)
    default_start = start_amplitude is None
    if start_amplitude is None:
        start_amplitude = 0.5 * gap if gap > 0 else 0.01 * max_amplitude
        if model.friction and gap == 0:  # start stuck: below the amplitude where slip begins
            from .mms.friction_epmc import stuck_mode

            start_amplitude = min(start_amplitude, 0.5 * stuck_mode(model, options.get("mode", 1))[2])
    start_amplitude = check.positive("start_amplitude", start_amplitude)
    if start_amplitude >= max_amplitude:
        raise ValueError(f"start_amplitude ({start_amplitude:g} m) must be below max_amplitude "
                         f"({max_amplitude:g} m)")
    if bounds is not None and not isinstance(bounds, Mapping):
        raise TypeError(f"bounds must be a dict name -> (lo, hi), got {type(bounds).__name__} {bounds!r}")
    cont = {k: options.pop(k) for k in list(options) if k in _CONTINUATION_FIELDS}
    all_bounds = {"amplitude": (0.0, max_amplitude)}
    for name, bound in dict(bounds or {}).items():
        all_bounds[name] = bound
    cont["bounds"] = {**all_bounds, **dict(cont.get("bounds", {}))}
    copts = ContinuationOptions(**cont)
    if method != "shooting":
        options["harmonics"] = harmonics
    checkpoint = _path_argument("checkpoint", checkpoint)
    resume = _path_argument("resume", resume)
    check_resources(model, method, options)  # before any allocation: a clear error, not a MemoryError
    problem = make_problem(model, method, **options)
    if default_start and gap > 0 and problem.open_amplitude is not None:
        # the linear mode is a solution only while every contact is open
        start_amplitude = min(start_amplitude, 0.5 * problem.open_amplitude())
    header = _checkpoint_header(model, method, problem, options)

    state, restored, previous = None, [], None
    if resume is not None:
        from ..core.checkpoint import read_checkpoint

        previous = read_checkpoint(resume)
        _check_resumable(previous.header, header, resume)
        state = previous.state()
        restored = previous.points
        log.info("resuming %s from point %d of %s", method, len(restored) - 1, resume)
    writer = None
    if checkpoint is not None:
        from ..core.checkpoint import CheckpointWriter

        writer = CheckpointWriter(checkpoint, {**header, "continuation": _jsonable(dataclasses.asdict(copts)),
                                               "start_amplitude": start_amplitude,
                                               "max_amplitude": max_amplitude}, restored)

    progress = None
    if verbose:
        progress, callback = _amplitude_progress(method, max_amplitude, gap, callback)
    t0 = time.perf_counter()
    try:
        if previous is not None and _finished(previous, copts):
            res = _finished_result(state, previous.terminal)
        else:
            with blas_limit():  # small dense solves: one BLAS thread unless the user chose (mmshbm._threads)
                res = continue_branch(problem, None if state else problem.linear_mode_point(start_amplitude),
                                      None if state else problem.initial_tangent(), copts, callback=callback,
                                      progress=None, resume=state,
                                      on_point=writer.point if writer is not None else None)
        if writer is not None:
            writer.end(res.status)
    finally:
        if progress is not None:
            progress.close()
        if writer is not None:
            writer.close()
    elapsed = time.perf_counter() - t0
    rec = res.records
    n = len(res.u)

    def column(name):
        return rec[name] if name in rec else np.full(n, np.nan)

    special = list(res.special_points)
    amp = column("amplitude")
    if gap > 0:
        above = np.flatnonzero(amp > gap * (1 + 1e-9))
        if len(above) and above[0] > 0:
            special.insert(1, SpecialPoint("grazing", int(above[0])))
    if problem.branch_records is not None and n:  # records computed once for the whole branch
        rec.update(problem.branch_records(res.u))
    if "modal_shares" in rec and problem.tracked_frequencies is not None:
        named = internal_resonances(rec["frequency"], rec["modal_shares"], problem.tracked_frequencies,
                                    problem.mode)
        special = sorted(special + named, key=lambda s: (s[1], s[0] == "endpoint"))
    log.info("%s backbone: %d points, status %s, %.3f s", method, n, res.status, elapsed)
    metadata = {
        "model": model.description, "method": method, "harmonics": int(problem.H),
        "n_samples": int(problem.N), "max_amplitude": max_amplitude,
        "start_amplitude": start_amplitude, "method_options": _jsonable(options),
        "continuation": _jsonable(dataclasses.asdict(copts)), "elapsed_s": elapsed,
        "python": platform.python_version(), "numpy": np.__version__,
    }
    if checkpoint is not None:
        metadata["checkpoint"] = str(checkpoint)
    if resume is not None:
        metadata["resumed_from"] = str(resume)
        metadata["resumed_points"] = len(restored)
    extra = {}
    if _BRANCH_HAS_RECORDS:
        extra["records"] = {k: v for k, v in rec.items() if k not in _BRANCH_COLUMNS}
    branch = Branch(
        frequency=column("frequency"), amplitude=amp, energy=column("energy"),
        contact_force_max=column("contact_force_max"), newton_iterations=res.newton_iterations,
        step_size=res.step_size, states=res.u, status=res.status, method=method,
        harmonics=int(problem.H), special_points=special, metadata=metadata,
        solver=problem, residual_histories=res.residual_histories, **extra)
    branch.check()  # records mode_share, warns (BranchWarning) when the branch is not what it seems
    return branch


def _amplitude_progress(method: str, max_amplitude: float, gap: float, callback):
    """A tqdm bar that counts the amplitude (in gaps, else mm) toward its bound, and the
    callback that moves it (then calls the user's ``callback``)."""
    from tqdm.auto import tqdm

    scale, unit = (gap, "gap") if gap > 0 else (1e-3, "mm")
    total = max_amplitude / scale
    bar = tqdm(desc=f"{method} backbone", unit=unit, total=total, leave=False, disable=None,
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
_BRANCH_HAS_RECORDS = "records" in {f.name for f in dataclasses.fields(Branch)}


def _path_argument(name: str, value) -> Path | None:
    if value is None:
        return None
    if not isinstance(value, str | Path) or str(value) == "":
        raise TypeError(f"{name} must be a file path (str or Path), got {type(value).__name__} {value!r}")
    return Path(value)


def _checkpoint_header(model: Model, method: str, problem, options: dict) -> dict:
    """What fixes the branch: a resumed run must agree on all of it."""
    from ..core.checkpoint import model_fingerprint

    resolved = problem.solver_settings()
    return {"method": method, "n_unknowns": int(problem.n_unknowns), "model": model_fingerprint(model),
            "model_description": model.description, "solver": resolved,
            "method_options": _jsonable({k: v for k, v in options.items()
                                         if k not in ("harmonics", "n_samples", "r", "mode")})}


def _check_resumable(stored: dict, current: dict, path) -> None:
    for key in ("method", "n_unknowns", "model", "solver", "method_options"):
        if stored.get(key) != current[key]:
            what = "the model's matrices, contact DOF, gap or stop side" if key == "model" else key
            raise ValueError(f"cannot resume from {str(path)!r}: {what} differ(s) from this run "
                             f"(file: {stored.get(key)!r}, now: {current[key]!r})")


def _finished(previous, copts: ContinuationOptions) -> bool:
    """True when the file's branch ended on a bound that still applies."""
    if not previous.terminal:
        return False
    terminal = Status.parse(previous.terminal)
    if terminal.kind != Status.BOUND:
        return terminal.kind == Status.START_OUTSIDE
    name = terminal.detail
    stored = previous.header.get("continuation", {}).get("bounds", {}).get(name)
    now = dict(copts.bounds).get(name)
    return stored is not None and now is not None and [float(b) for b in stored] == [float(b) for b in now]


def _finished_result(state, status):
    from ..core.continuation import ContinuationResult

    recs = state.records
    return ContinuationResult(
        u=np.array(state.u), records={k: np.array([r[k] for r in recs]) for k in recs[0]},
        newton_iterations=np.array(state.newton_iterations, dtype=int),
        step_size=np.array(state.step_size, dtype=float), residual_histories=state.residual_histories,
        special_points=list(state.special_points) + [SpecialPoint("endpoint", len(state.u) - 1)],
        status=Status.parse(status),
        tangent=state.tangent, next_ds=state.ds, steps=state.steps)


def _jsonable(d: dict) -> dict:
    out = {}
    for k, v in d.items():
        if isinstance(v, dict):
            out[k] = _jsonable(v)
        elif isinstance(v, tuple | list):
            out[k] = [float(x) if isinstance(x, int | float | np.number) else x for x in v]
        elif isinstance(v, np.generic):
            out[k] = v.item()
        else:
            out[k] = v
    return out
