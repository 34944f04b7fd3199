"""Pseudo-arclength predictor-corrector path following.

The driver knows only the continuation problem protocol (:mod:`mmshbm.core.problem`): a
residual of n−1 equations in n scaled unknowns, its Jacobian (dense ndarray or
scipy.sparse), and a ``monitor`` giving the recorded quantities of a point, plus the
capabilities a problem declares (its step rule, a compiled corrector, the record that
caps the step). MMS-HBM, penalty-HBM and shooting all implement it, so they share this
driver and its step control. It reads no record by name: what a branch means (the
family of a nonlinear mode, its jumps over internal resonances) is an event plug-in
(:mod:`mmshbm.core.events`), passed in by the caller: the methods' runs pass the family
following of :mod:`mmshbm.family.follower` for ``follow="family"``.

Algorithm: tangent predictor u_p = u + ds·t; Newton corrector on [R(u); t·(u − u_p)] = 0
with the bordered Jacobian [J; tᵀ]; the new tangent solves [J; tᵀ] t' = [0; 1]. Step
control by Newton effort, ``ds *= 1 + growth·((max_newton − nit)/max_newton)²``, capped
by ``ds_max``; a failed corrector (no convergence, a non-finite residual, a singular
matrix, a jump off the predictor cone or a tangent turning more than ``max_angle``)
halves ds and retries, down to ``ds_min``, then stops cleanly with a status
(:class:`~mmshbm.core.status.Status`). A branch is never lost: every converged point is
in the result, whatever stopped it (including Ctrl-C). Bounds on monitored quantities
stop the branch on a point refined onto the bound by secant iteration in the arclength.
"""

from __future__ import annotations

import copy
import dataclasses
import logging
from collections.abc import Callable

import numpy as np

from .events import BranchEvents, NoEvents, RelocationFailed
from .options import ContinuationOptions, ContinuationProblem, ContinuationResult, ContinuationState
from .problem import as_problem
from .special_points import SpecialPoint
from .status import Status
from .steps import (
    _advance_turn,
    _corrector,
    _curvature,
    _Failure,
    _monitor,
    _next_step,
    _orientation,
    _orientation_safe,
    _outside,
    _tangent,
    newton,
)

__all__ = ["ContinuationOptions", "ContinuationProblem", "ContinuationResult", "ContinuationState",
           "continue_branch", "newton"]

log = logging.getLogger(__name__)


def continue_branch(problem: ContinuationProblem, u0: np.ndarray, t0: np.ndarray,
                    options: ContinuationOptions | None = None,
                    callback: Callable[[np.ndarray, dict], None] | None = None,
                    progress=None, *, resume: ContinuationState | None = None,
                    on_point: Callable[[dict], None] | None = None,
                    catch_interrupt: bool = True, events: BranchEvents | None = None) -> ContinuationResult:
    """Follow the branch of ``problem`` from ``u0`` in the direction ``t0``.

    Parameters
    ----------
    problem : ContinuationProblem
        The required protocol; capabilities are read from a
        :class:`~mmshbm.core.problem.ContinuationProblemBase` (a plain object gets the defaults).
    u0 : ndarray, shape (n,)
        A point near the branch (corrected first, orthogonally to ``t0``).
    t0 : ndarray, shape (n,)
        Initial direction; the first tangent is oriented along it.
    options : ContinuationOptions
    callback : callable(u, record), optional
        Called with every accepted point.
    progress : tqdm-like, optional
        Object with ``update(1)`` and ``set_postfix(**kw)``.
    resume : ContinuationState, optional
        Go on from this state (``u0`` and ``t0`` are then ignored): the points it holds
        are kept, and the rest of the branch is the one an uninterrupted run computes,
        point for point (the driver is deterministic given u, tangent, ds and steps).
    on_point : callable(dict), optional
        Called with the full driver state of every accepted point (keys ``index``,
        ``u``, ``tangent``, ``ds``, ``ds_next``, ``steps``, ``newton``, ``history``,
        ``record``, ``special`` (special points at this index), ``status`` (the
        terminal status if this point ends the branch, else None)); a checkpoint
        writer. Exceptions other than KeyboardInterrupt propagate.
    catch_interrupt : bool
        A KeyboardInterrupt ends the branch with status ``"interrupted"`` (default);
        False lets it propagate: continuations nested inside another run's step (a
        jump's backfill, an auxiliary branch) must not swallow the user's Ctrl-C.
    events : BranchEvents, optional
        The event plug-in (:mod:`mmshbm.core.events`); default none (plain path
        following, whatever ``options.follow`` says: the family following for
        ``follow="family"`` is the caller's to pass,
        :func:`mmshbm.family.follower.default_events`).

    Returns
    -------
    ContinuationResult
        Never raises for a failing branch: the status says why it stopped. Raises
        ValueError if ``options.bounds`` names a quantity the problem does not monitor.
    """
    problem = as_problem(problem)
    opt = options or ContinuationOptions()
    if opt.step_control == "auto":
        opt = _with_step_control(opt, problem.step_control)
    events = NoEvents() if events is None else events
    pts = _Points(resume, opt.ds, on_point, callback, progress, problem.progress_records)
    events.replay(pts.recs, pts.special)
    u = t = None
    ds, step, curvature, det_last = opt.ds, 0, None, 0.0
    bounds = dict(opt.bounds)

    def jump(reason: str, failed: Callable[[str], Status]) -> Status | None:
        """Relocate the branch where the events say; a Status when that ends it."""
        nonlocal u, t, ds, curvature, det_last
        try:
            moved = events.relocate(problem, pts.us, pts.recs, reason, len(pts.us))
        except RelocationFailed as err:
            status = Status(err.kind, str(err)) if err.kind else failed(str(err))
            return status if err.cause is None else status.with_cause(err.cause)
        for n, (u_p, nit_p, hist_p, rec_p, t_p) in enumerate(moved.points):
            events.register(len(pts.us), rec_p, n == 0)
            last = n == len(moved.points) - 1
            pts.accept(u_p, nit_p, 0.0, hist_p, rec_p, t_p, opt.ds, step, [moved.special] if n == 0 else [],
                       terminal=moved.terminal if last else None)
        u, t = moved.points[-1][0], moved.points[-1][4]
        det_last = _orientation_safe(problem, u, t)
        ds, curvature = opt.ds, None
        return moved.terminal

    def jump_failed(err: str) -> Status:
        return Status(Status.JUMP_FAILED, err)

    try:
        if resume is None:
            try:
                u, t, nit, hist, rec, J = _first_point(problem, u0, t0, opt)
            except _Failure as err:
                return pts.result(Status(Status.START_FAILED, str(err)))
            _check_bound_names(opt.bounds, rec)
            terminal = Status(Status.START_OUTSIDE) if _outside(rec, opt.bounds) else None
            events.observe(0, rec)
            det_last = _orientation(J, t)
            pts.accept(u, nit, 0.0, hist, rec, t, opt.ds, 0, terminal=terminal)
            if terminal:
                return pts.result(terminal)
        else:
            u, t = pts.us[-1], np.asarray(resume.tangent, dtype=float)
            ds, step = float(resume.ds), int(resume.steps)
            pts.state.update(t=t, ds=ds, steps=step)
            if resume.previous_tangent is not None and pts.dss:
                t_prev = np.asarray(resume.previous_tangent, dtype=float)
                curvature = _curvature(t_prev, t, float(pts.dss[-1]))
            _check_bound_names(opt.bounds, pts.recs[-1])
            det_last = _orientation_safe(problem, u, t)
        status = Status(Status.MAX_STEPS)
        while step < opt.max_steps:
            try:
                curv = curvature if opt.step_control == "residual" else None
                u_new, nit, hist, J, t_new, sign, rec, turn = _advance_turn(problem, u, t, ds, opt, curv)
            except _Failure as err:
                ds *= 0.5
                log.debug("step failed (%s); ds -> %g", err, ds)
                if ds >= opt.ds_min:
                    continue
                status = Status(Status.DS_MIN, f"step size fell below {opt.ds_min:g} ({err})")
                reason = events.at_ds_min()
                if reason is None:
                    break
                step += 1
                stop = jump(reason, status.with_detail)
                if stop:
                    status = stop
                    break
                continue  # the ds_min status stands until another replaces it
            if _unconfirmed_flip(sign, det_last, ds, opt):
                ds *= 0.5  # crossed a branch point, or jumped across a fold: a shorter step tells
                log.debug("det [J; t] changed sign on a step longer than branch_point_ds; ds -> %g", ds)
                continue
            step += 1
            crossed = _outside(rec, bounds)
            if crossed:
                u_new, nit, hist, rec, t_new = _refine_onto_bound(
                    problem, u, t, ds, crossed, pts.recs[-1], rec, opt, (u_new, nit, hist, rec, t_new))
                status = Status.bound(crossed[0])
                reason = events.at_bound(len(pts.us), rec)
                if reason is None:
                    pts.accept(u_new, nit, ds, hist, rec, t_new, ds, step,
                               [SpecialPoint(str(status), len(pts.us))], terminal=status)
                    break
                pts.accept(u_new, nit, ds, hist, rec, t_new, ds, step, [])
                stop = jump(reason, jump_failed)
                if stop:
                    status = stop
                    break
                continue
            new_special = []
            if t_new[-1] * t[-1] < 0 and min(abs(t_new[-1]), abs(t[-1])) > 1e-6:
                new_special.append(SpecialPoint("fold", len(pts.us)))
            if sign and det_last and sign != det_last:
                new_special.append(SpecialPoint("branch_point", len(pts.us)))
            det_last = sign or det_last
            reason = events.observe(len(pts.us), rec)
            ds_prev = ds
            cap = _step_cap(problem.measure, opt, pts.recs[-1], rec, ds_prev)
            ds = min(cap, _next_step(ds, nit, hist, opt))
            pts.accept(u_new, nit, ds_prev, hist, rec, t_new, ds, step, new_special)
            # κ ≈ dt/ds from the last step, for the next predictor (not across a fold's turn)
            curvature = _curvature(t, t_new, ds_prev, turn)
            u, t = u_new, t_new
            if reason is not None:
                stop = jump(reason, jump_failed)
                if stop:
                    status = stop
                    break
    except KeyboardInterrupt:
        if not catch_interrupt:
            raise
        status = Status(Status.INTERRUPTED)
    return pts.result(status)


def _unconfirmed_flip(sign: float, det_last: float, ds: float, opt: ContinuationOptions) -> bool:
    """True when det [J; t] changed sign (``sign`` against ``det_last``; 0: not computed)
    on a step longer than ``opt.branch_point_ds`` (see :class:`ContinuationOptions`)."""
    limit = opt.branch_point_ds
    return limit is not None and ds > limit and bool(sign) and bool(det_last) and sign != det_last


def _with_step_control(opt: ContinuationOptions, rule) -> ContinuationOptions:
    """``dataclasses.replace(opt, step_control=rule)``; a valid rule is set on a copy without
    validating the other (valid) fields again."""
    if rule not in ("residual", "effort"):
        return dataclasses.replace(opt, step_control=rule)  # "auto" stays, anything else raises
    new = copy.copy(opt)
    object.__setattr__(new, "step_control", rule)
    return new


def _first_point(problem, u0, t0, opt: ContinuationOptions):
    """The first point, corrected from ``u0`` orthogonally to ``t0``: (u, unit tangent,
    iterations, residual history, record, Jacobian). Raises ``_Failure``."""
    t0 = np.asarray(t0, dtype=float)
    t0 = t0 / np.linalg.norm(t0)
    u0 = np.asarray(u0, dtype=float)
    u, nit, hist, J = newton(problem, u0, t0, u0, opt.newton_tol, opt.max_newton, opt.step_tol)
    t = _tangent(J, t0, problem)
    return u, t, nit, hist, _monitor(problem, u), J


class _Points:
    """The accepted points of a branch (or those a resumed state holds) and the driver's
    state after the last one; :meth:`accept` also feeds the checkpoint writer, the
    callback and the progress bar."""

    def __init__(self, resume, ds: float, on_point, callback, progress, progress_records):
        self.on_point, self.callback, self.progress = on_point, callback, progress
        self.progress_records = progress_records
        if resume is None:
            self.us, self.recs, self.nits, self.dss, self.hists = [], [], [], [], []
            self.special = [SpecialPoint("start", 0)]
        else:
            self.us = [np.asarray(v, dtype=float) for v in resume.u]
            self.recs, self.nits = list(resume.records), list(resume.newton_iterations)
            self.dss, self.hists = list(resume.step_size), list(resume.residual_histories)
            self.special = [p if isinstance(p, SpecialPoint) else SpecialPoint(*p)
                            for p in resume.special_points if p[0] != "endpoint"]
            if not self.us:
                raise ValueError("resume holds no point")
        self.state = {"t": None, "ds": ds, "steps": 0}

    def accept(self, u, nit, ds, hist, rec, t, ds_next, steps, new_special=(), terminal=None):
        self.us.append(u.copy())
        self.recs.append(rec)
        self.nits.append(nit)
        self.dss.append(ds)
        self.hists.append(hist)
        if new_special:
            self.special.extend(new_special)
        state = self.state
        state["t"], state["ds"], state["steps"] = t, ds_next, steps
        if self.on_point is not None:
            self.on_point({"index": len(self.us) - 1, "u": u, "tangent": t, "ds": ds, "ds_next": ds_next,
                           "steps": steps, "newton": nit, "history": hist, "record": rec,
                           "special": list(new_special), "status": terminal})
        if self.callback is not None:
            self.callback(u, rec)
        if self.progress is not None:
            self.progress.update(1)
            self.progress.set_postfix({k: f"{v:.4g}" for k, v in rec.items() if k in self.progress_records}
                                      | {"ds": f"{ds:.2g}", "newton": nit})

    def result(self, status: Status) -> ContinuationResult:
        self.special.append(SpecialPoint("endpoint", len(self.us) - 1))
        keys = self.recs[0].keys() if self.recs else ()
        return ContinuationResult(
            u=np.array(self.us), records={k: np.array([r[k] for r in self.recs]) for k in keys},
            newton_iterations=np.array(self.nits, dtype=int), step_size=np.array(self.dss, dtype=float),
            residual_histories=self.hists, special_points=self.special, status=status,
            tangent=self.state["t"], next_ds=float(self.state["ds"]), steps=int(self.state["steps"]))


#: the cap on the step grows past ds_max up to the step that would change the problem's
#: measure (the amplitude) by this fraction (linearly extrapolated from the last step), at
#: most _CAP_GROWTH ds_max
_CAP_AMPLITUDE = 0.02
_CAP_GROWTH = 1.0e6


def _step_cap(measure: str | None, opt: ContinuationOptions, rec_prev: dict, rec_new: dict,
              ds_prev: float) -> float:
    """The largest next step: ``ds_max``, or more where the scaled unknowns move much while
    the record ``measure`` (the problem's, the amplitude) barely does (a branch whose
    unknowns grow along a direction that moves the amplitude DOF little, e.g. a pole
    unknown near kΩ = ω_j): up to the step that changes it by 2 %. Depends only on the
    last two points, so a resumed run takes the same steps."""
    if measure is None:
        return opt.ds_max
    a0, a1 = rec_prev.get(measure), rec_new.get(measure)
    if a0 is None or a1 is None or not ds_prev > 0:
        return opt.ds_max
    da = abs(float(a1) - float(a0))
    if not da > 0:
        return opt.ds_max
    return max(opt.ds_max, min(_CAP_GROWTH * opt.ds_max, _CAP_AMPLITUDE * abs(float(a1)) * ds_prev / da))


def _check_bound_names(bounds, rec: dict) -> None:
    unknown = sorted(set(dict(bounds)) - set(rec))
    if unknown:
        raise ValueError(f"bounds on unknown quantit{'y' if len(unknown) == 1 else 'ies'} "
                         f"{', '.join(map(repr, unknown))}; the problem monitors {sorted(rec)}")


#: the secant's least arclength onto a bound, as a part of the step: above 0 (s = 0 is the
#: previous point again), far below the root's s when the previous point lies within the
#: bound's tolerance of it (a branch relocated onto the bound goes on from there), where a
#: larger floor overshoots the bound by floor·ds·|d record/ds|
_BOUND_S_FLOOR = 1e-12


def _refine_onto_bound(problem, u, t, ds, crossed, rec_prev, rec_new, opt, fallback):
    """Secant iteration in the arclength s ∈ (0, ds) for monitor[name](s) = bound.

    Returns (u, newton iterations, residual history, record, tangent) of the best point."""
    name, target = crossed
    s0, f0 = 0.0, rec_prev[name] - target
    s1, f1 = ds, rec_new[name] - target
    best = fallback
    # Newton starts from the nearest converged point moved onto the new hyperplane (it
    # lies on the branch to within the secant's last correction, far closer than the
    # predictor u + s t): fewer iterations per secant step, same converged point (to the
    # Newton tolerance); if it fails, the step is retried from the predictor.
    near_s, near_u = ds, fallback[0]
    for _ in range(12):
        if f1 == f0:
            break
        s = s1 - f1 * (s1 - s0) / (f1 - f0)
        s = min(max(s, _BOUND_S_FLOOR * ds), ds)
        try:
            try:
                u_s, nit, hist, J = _corrector(problem, u, t, s, opt, start=near_u + (s - near_s) * t)
            except _Failure:  # nonsmooth residuals: the warm start can miss; retry cold
                u_s, nit, hist, J = _corrector(problem, u, t, s, opt)
            rec = _monitor(problem, u_s)
            t_s = _tangent(J, t, problem)
        except _Failure:
            break
        f = rec[name] - target
        best = (u_s, nit, hist, rec, t_s)
        near_s, near_u = s, u_s
        if abs(f) <= 1e-10 * max(abs(target), 1e-300) or abs(s - s1) < 1e-14:
            break
        s0, f0, s1, f1 = s1, f1, s, f
    return best
