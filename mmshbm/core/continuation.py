"""Pseudo-arclength predictor-corrector path following.

The driver knows only a small protocol (:class:`ContinuationProblem`): a residual of n−1
equations in n scaled unknowns, its Jacobian (dense ndarray or scipy.sparse), and a
``monitor`` giving the recorded quantities of a point. MMS-HBM, penalty-HBM and shooting
all implement it, so they share this driver and its step control.

Algorithm: tangent predictor u_p = u + ds·t; Newton corrector on [R(u); t·(u − u_p)] = 0
with the bordered Jacobian [J; tᵀ]; the new tangent solves [J; tᵀ] t' = [0; 1]. Step
control by Newton effort, ``ds *= 1 + growth·((max_newton − nit)/max_newton)²``, capped
by ``ds_max``; a failed corrector (no convergence, a non-finite residual, a singular
matrix, a jump off the predictor cone or a tangent turning more than ``max_angle``)
halves ds and retries, down to ``ds_min``, then stops cleanly with a status. A branch is
never lost: every converged point is in the result, whatever stopped it (including
Ctrl-C). Bounds on monitored quantities stop the branch on a point refined onto the
bound by secant iteration in the arclength.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable

import numpy as np

from .bordered import bordered_solve as _bordered_solve  # noqa: F401 (the benchmarks' name)
from .family import FAMILY_RECORD, FamilyGuard, family_value, jump
from .options import ContinuationOptions, ContinuationProblem, ContinuationResult, ContinuationState
from .pinned import PinnedFailure
from .special_points import SpecialPoint
from .steps import (
    SKIP_MIN_TOL,  # noqa: F401 (imported from here before the split)
    _corrector,
    _curvature,
    _Failure,
    _monitor,
    _next_step,
    _orientation,
    _orientation_safe,
    _pinned_monitor,
    _predicted_converged,  # noqa: F401
    _step,
    _tangent,
    _tangent_sign,  # noqa: F401
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
                    catch_interrupt: bool = True) -> ContinuationResult:
    """Follow the branch of ``problem`` from ``u0`` in the direction ``t0``.

    Parameters
    ----------
    problem : ContinuationProblem
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

    Returns
    -------
    ContinuationResult
        Never raises for a failing branch: the status says why it stopped. Raises
        ValueError if ``options.bounds`` names a quantity the problem does not monitor.
    """
    opt = options or ContinuationOptions()
    if opt.step_control == "auto":
        opt = dataclasses.replace(opt, step_control=getattr(problem, "step_control", "effort"))
    if resume is None:
        us, recs, nits, dss, hists, special = [], [], [], [], [], [SpecialPoint("start", 0)]
    else:
        us = [np.asarray(v, dtype=float) for v in resume.u]
        recs, nits, dss = list(resume.records), list(resume.newton_iterations), list(resume.step_size)
        hists = list(resume.residual_histories)
        special = [sp_ if isinstance(sp_, SpecialPoint) else SpecialPoint(*sp_)
                   for sp_ in resume.special_points if sp_[0] != "endpoint"]
        if not us:
            raise ValueError("resume holds no point")
    state = {"t": None, "ds": opt.ds, "steps": 0}

    def accept(u, nit, ds, hist, rec, t, ds_next, steps, new_special=(), terminal=None):
        us.append(u.copy())
        recs.append(rec)
        nits.append(nit)
        dss.append(ds)
        hists.append(hist)
        special.extend(new_special)
        state.update(t=t, ds=ds_next, steps=steps)
        if on_point is not None:
            on_point({"index": len(us) - 1, "u": u, "tangent": t, "ds": ds, "ds_next": ds_next,
                      "steps": steps, "newton": nit, "history": hist, "record": rec,
                      "special": list(new_special), "status": terminal})
        if callback is not None:
            callback(u, rec)
        if progress is not None:
            progress.update(1)
            progress.set_postfix({k: f"{v:.4g}" for k, v in rec.items() if k in ("frequency", "amplitude")}
                                 | {"ds": f"{ds:.2g}", "newton": nit})

    def result(status):
        special.append(SpecialPoint("endpoint", len(us) - 1))
        keys = recs[0].keys() if recs else ()
        return ContinuationResult(
            u=np.array(us), records={k: np.array([r[k] for r in recs]) for k in keys},
            newton_iterations=np.array(nits, dtype=int), step_size=np.array(dss, dtype=float),
            residual_histories=hists, special_points=special, status=status, tangent=state["t"],
            next_ds=float(state["ds"]), steps=int(state["steps"]))

    guard = FamilyGuard(opt.family_share, opt.max_excursion) if opt.follow == "family" else None
    if guard is not None:
        for i, rec in enumerate(recs):  # a resumed run replays the guard's decisions
            if any(s[0] == "jump" and s[1] == i for s in special):
                guard.jumped(i, rec)
            else:
                guard.observe(i, rec)
    amplitude_max = float(dict(opt.bounds).get("amplitude", (0.0, math.inf))[1])
    det_sign = {"last": 0.0}
    curvature = {"k": None}  # dt/ds of the last step (second-order predictor)

    def jump_over(reason, step):
        """Jump beyond the family's frontier, fill the family back down from the landing
        point (:func:`_backfill`), accept those points in increasing amplitude; returns
        (u, t, terminal status or None) of the landing point."""
        u_j, nit_j, hist_j, rec_j, t_j, target, i_from = jump(
            problem, guard, us, recs, step=opt.jump_step, amplitude_max=amplitude_max,
            newton_tol=opt.newton_tol, max_newton=opt.max_newton, monitor=_pinned_monitor)
        A_from = float(recs[i_from]["amplitude"])
        frontier = float(recs[guard.frontier_index]["amplitude"])
        filled = _backfill(problem, u_j, t_j, frontier, target, opt) if target > frontier * (1 + 1e-9) else []
        points = filled + [(u_j, nit_j, hist_j, rec_j, t_j)]
        first = points[0][3]
        special_jump = SpecialPoint("jump", len(us), reason=reason, from_index=i_from, amplitude_from=A_from,
                                    amplitude_frontier=frontier, amplitude_to=float(first["amplitude"]),
                                    landing_amplitude=float(target),
                                    frequency_from=float(recs[i_from].get("frequency", math.nan)),
                                    frequency_to=float(first.get("frequency", math.nan)))
        terminal = None
        for n, (u_p, nit_p, hist_p, rec_p, t_p) in enumerate(points):
            if n == 0:
                guard.jumped(len(us), rec_p)
            else:
                guard.observe(len(us), rec_p)
            last = n == len(points) - 1
            if last and (_outside(rec_p, opt.bounds) or target >= amplitude_max):
                terminal = "bound:amplitude"
            accept(u_p, nit_p, 0.0, hist_p, rec_p, t_p, opt.ds, step, [special_jump] if n == 0 else [],
                   terminal=terminal if last else None)
        det_sign["last"] = _orientation_safe(problem, u_j, t_j)
        log.info("jump (%s) from amplitude %.4g to %.4g (landed at %.4g, %d points filled back)", reason,
                 A_from, special_jump.data["amplitude_to"], target, len(filled))
        return u_j, t_j, terminal

    try:
        if resume is None:
            t0 = np.asarray(t0, dtype=float)
            t0 = t0 / np.linalg.norm(t0)
            try:
                u, nit, hist, J = newton(problem, np.asarray(u0, dtype=float), t0,
                                         np.asarray(u0, dtype=float), opt.newton_tol, opt.max_newton,
                                         opt.step_tol)
                t = _tangent(J, t0)
                rec = _monitor(problem, u)
            except _Failure as err:
                return result(f"start failed: {err}")
            _check_bound_names(opt.bounds, rec)
            outside = _outside(rec, opt.bounds)
            terminal = "start outside bounds" if outside else None
            if guard is not None:
                guard.observe(0, rec)
            det_sign["last"] = _orientation(J, t)
            accept(u, nit, 0.0, hist, rec, t, opt.ds, 0, terminal=terminal)
            if terminal:
                return result(terminal)
            ds, step = opt.ds, 0
        else:
            u = us[-1]
            t = np.asarray(resume.tangent, dtype=float)
            ds, step = float(resume.ds), int(resume.steps)
            state.update(t=t, ds=ds, steps=step)
            if resume.previous_tangent is not None and dss:
                t_prev = np.asarray(resume.previous_tangent, dtype=float)
                curvature["k"] = _curvature(t_prev, t, float(dss[-1]))
            _check_bound_names(opt.bounds, recs[-1])
            det_sign["last"] = _orientation_safe(problem, u, t)
        status = "max_steps"
        n_jumps = sum(1 for s in special if s[0] == "jump")
        while step < opt.max_steps:
            try:
                curv = curvature["k"] if opt.step_control == "residual" else None
                u_new, nit, hist, J, t_new, sign, rec = _step(problem, u, t, ds, opt, curv)
                if t_new @ t < math.cos(opt.max_angle) and ds > opt.corner_ds:
                    raise _Failure("tangent turned too far")
            except _Failure as err:
                ds *= 0.5
                log.debug("step failed (%s); ds -> %g", err, ds)
                if ds < opt.ds_min:
                    status = f"ds_min: step size fell below {opt.ds_min:g} ({err})"
                    if guard is not None and guard.active and n_jumps < opt.max_jumps:
                        try:
                            u, t, terminal = jump_over("ds_min", step + 1)
                        except PinnedFailure as jerr:
                            status = f"{status}; {jerr}"
                            break
                        step += 1
                        n_jumps += 1
                        ds = opt.ds
                        curvature["k"] = None
                        if terminal:
                            status = terminal
                            break
                        continue
                    break
                continue
            step += 1
            crossed = _outside(rec, opt.bounds)
            if crossed:
                u_new, nit, hist, rec, t_new = _refine_onto_bound(problem, u, t, ds, crossed, recs[-1], rec,
                                                                  opt, (u_new, nit, hist, rec, t_new))
                status = f"bound:{crossed[0]}"
                action = guard.observe(len(us), rec) if guard is not None else None
                if (guard is not None and guard.active and rec.get("on_family", 1.0) < 0.5
                        and n_jumps < opt.max_jumps):
                    # the bound was reached off the family (a tongue climbing to it): not an
                    # end of the backbone; jump from the frontier instead
                    accept(u_new, nit, ds, hist, rec, t_new, ds, step, [])
                    try:
                        u, t, terminal = jump_over("tongue reached the bound", step)
                    except PinnedFailure as err:
                        status = f"jump failed: {err}"
                        break
                    n_jumps += 1
                    ds = opt.ds
                    curvature["k"] = None
                    if terminal:
                        status = terminal
                        break
                    continue
                accept(u_new, nit, ds, hist, rec, t_new, ds, step, [SpecialPoint(status, len(us))],
                       terminal=status)
                break
            new_special = []
            if t_new[-1] * t[-1] < 0 and min(abs(t_new[-1]), abs(t[-1])) > 1e-6:
                new_special.append(SpecialPoint("fold", len(us)))
            if sign and det_sign["last"] and sign != det_sign["last"]:
                new_special.append(SpecialPoint("branch_point", len(us)))
            det_sign["last"] = sign or det_sign["last"]
            action = guard.observe(len(us), rec) if guard is not None else None
            ds_prev = ds
            ds = min(_step_cap(opt, recs[-1], rec, ds_prev), _next_step(ds, nit, hist, opt))
            accept(u_new, nit, ds_prev, hist, rec, t_new, ds, step, new_special)
            # κ ≈ dt/ds from the last step, for the next predictor (not across a fold's turn)
            curvature["k"] = _curvature(t, t_new, ds_prev)
            u, t = u_new, t_new
            if action == "jump" and n_jumps < opt.max_jumps:
                reason = "loop" if guard.left and guard.away <= opt.max_excursion else "excursion"
                try:
                    u, t, terminal = jump_over(reason, step)
                except PinnedFailure as err:
                    status = f"jump failed: {err}"
                    break
                n_jumps += 1
                ds = opt.ds
                curvature["k"] = None
                if terminal:
                    status = terminal
                    break
    except KeyboardInterrupt:
        if not catch_interrupt:
            raise
        status = "interrupted"
    return result(status)


def _backfill(problem, u, t, frontier: float, landing: float, opt: ContinuationOptions) -> list:
    """The family below a jump's landing point: continued backwards from it (plain path
    following) until it leaves the family (its family measure refined onto ``family_share``) or
    reaches the frontier. Returns the points in increasing amplitude, as tuples
    (u, iterations, history, record, tangent oriented to growing amplitude), without the
    landing point."""
    back = ContinuationOptions(
        ds=opt.ds, ds_min=opt.ds_min, ds_max=opt.ds_max, max_steps=opt.max_excursion,
        newton_tol=opt.newton_tol, step_tol=opt.step_tol, max_newton=opt.max_newton, growth=opt.growth,
        max_angle=opt.max_angle, corner_ds=opt.corner_ds, follow="path",
        bounds={"amplitude": (frontier, landing * (1 + 1e-6)), FAMILY_RECORD: (opt.family_share, 2.0)})
    res = continue_branch(problem, u, -t, back, catch_interrupt=False)
    out = []
    for i in range(len(res.u) - 1, 0, -1):
        rec = {k: v[i] for k, v in res.records.items()}
        share = family_value(rec)
        if share is not None and share < opt.family_share * (1 - 1e-6):
            continue
        tangent = res.u[i - 1] - res.u[i]
        tangent /= max(np.linalg.norm(tangent), 1e-300)
        out.append((res.u[i], int(res.newton_iterations[i]), res.residual_histories[i], rec, tangent))
    return out


#: the cap on the step grows past ds_max up to the step that would change the amplitude by
#: this fraction (linearly extrapolated from the last step), at most _CAP_GROWTH ds_max
_CAP_AMPLITUDE = 0.02
_CAP_GROWTH = 1.0e6


def _step_cap(opt: ContinuationOptions, rec_prev: dict, rec_new: dict, ds_prev: float) -> float:
    """The largest next step: ``ds_max``, or more where the scaled unknowns move much while
    the amplitude barely does (a branch whose unknowns grow along a direction that moves
    the amplitude DOF little, e.g. a pole unknown near kΩ = ω_j): up to the step that
    changes the amplitude by 2 %. Depends only on the last two points, so a resumed run
    takes the same steps."""
    a0, a1 = rec_prev.get("amplitude"), rec_new.get("amplitude")
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


def _outside(rec: dict, bounds) -> tuple | None:
    """(name, bound value) of the first bound that ``rec`` violates, else None."""
    for name, (lo, hi) in dict(bounds).items():
        v = rec.get(name)
        if v is None:
            continue
        if v > hi:
            return (name, float(hi))
        if v < lo:
            return (name, float(lo))
    return None


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
        s = min(max(s, 1e-3 * ds), ds)
        try:
            try:
                u_s, nit, hist, J = _corrector(problem, u, t, s, opt, start=near_u + (s - near_s) * t)
            except _Failure:  # nonsmooth residuals: the warm start can miss; retry cold
                u_s, nit, hist, J = _corrector(problem, u, t, s, opt)
            rec = _monitor(problem, u_s)
            t_s = _tangent(J, t)
        except _Failure:
            break
        f = rec[name] - target
        best = (u_s, nit, hist, rec, t_s)
        near_s, near_u = s, u_s
        if abs(f) <= 1e-10 * max(abs(target), 1e-300) or abs(s - s1) < 1e-14:
            break
        s0, f0, s1, f1 = s1, f1, s, f
    return best
