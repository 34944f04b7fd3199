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

import logging
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
import scipy.sparse as sp

from .. import _validate as check
from .bordered import solve_bordered_sparse
from .special_points import SpecialPoint

__all__ = ["ContinuationOptions", "ContinuationProblem", "ContinuationResult", "ContinuationState",
           "continue_branch", "newton"]

log = logging.getLogger(__name__)


class ContinuationProblem(Protocol):
    """What the driver needs from a problem (all vectors in scaled units)."""

    n_unknowns: int

    def evaluate(self, u: np.ndarray, jacobian: bool = True):
        """Residual (n−1,) and, if ``jacobian``, the Jacobian (n−1, n), dense or sparse."""

    def monitor(self, u: np.ndarray) -> dict:
        """Scalar quantities recorded per point (e.g. frequency, amplitude, energy)."""


@dataclass(frozen=True)
class ContinuationOptions:
    """Options of the path follower (scaled arclength units). Validated on creation.

    Attributes
    ----------
    ds, ds_min, ds_max : float
        Initial, smallest and largest arclength step.
    max_steps : int
        Largest number of continuation steps (points after the first).
    newton_tol : float
        Convergence: infinity norm of the scaled residual.
    step_tol : float
        Convergence also when the scaled Newton update's infinity norm falls below
        this while the residual is below √newton_tol: where the residual has a
        round-off floor (near a pole of the condensed stiffness, kΩ close to an
        eigenfrequency of the clamped-contact structure) the iterate is then known to
        ``step_tol``.
    max_newton : int
        Newton iterations per corrector before the step counts as failed.
    growth : float
        ``a`` in ds *= 1 + a·((max_newton − nit)/max_newton)².
    max_angle : float
        Largest angle (rad) between consecutive tangents; more means the step jumped.
    corner_ds : float
        Below this step the angle test is waived: the sampled (AFT) contact residual is
        piecewise smooth, so where a sample point changes its active set the branch
        has a genuine corner that no step size removes.
    bounds : Mapping[str, tuple[float, float]]
        Stop when a monitored quantity leaves [lo, hi]; the last point is refined onto
        the bound. E.g. ``{"amplitude": (0, 1e-2), "frequency": (0, 80)}``.
    """

    ds: float = 0.1
    ds_min: float = 1e-7
    ds_max: float = 2.0
    max_steps: int = 1000
    newton_tol: float = 1e-10
    step_tol: float = 1e-8
    max_newton: int = 10
    growth: float = 0.5
    max_angle: float = math.radians(30.0)
    corner_ds: float = 1e-4
    bounds: Mapping[str, tuple[float, float]] = field(default_factory=dict)

    def __post_init__(self):
        ds_min = check.positive("ds_min", self.ds_min)
        ds = check.positive("ds", self.ds)
        ds_max = check.positive("ds_max", self.ds_max)
        if not ds_min <= ds <= ds_max:
            raise ValueError(f"need ds_min <= ds <= ds_max, got {ds_min} <= {ds} <= {ds_max}")
        check.integer("max_steps", self.max_steps, minimum=1)
        check.positive("newton_tol", self.newton_tol)
        check.positive("step_tol", self.step_tol)
        check.integer("max_newton", self.max_newton, minimum=1)
        check.positive("corner_ds", self.corner_ds)
        check.non_negative("growth", self.growth)
        angle = check.positive("max_angle", self.max_angle)
        if angle > math.pi:
            raise ValueError(f"max_angle must be <= pi, got {angle}")
        for name, bound in dict(self.bounds).items():
            try:
                lo, hi = (float(b) for b in bound)
            except (TypeError, ValueError):
                raise ValueError(f"bounds[{name!r}] must be a pair (lo, hi), got {bound!r}") from None
            if not lo < hi:
                raise ValueError(f"bounds[{name!r}] must satisfy lo < hi, got {bound!r}")


@dataclass
class ContinuationResult:
    """The converged points of a branch and why it stopped.

    Attributes
    ----------
    u : ndarray, shape (n_points, n)
        Scaled unknowns per point.
    records : dict[str, ndarray]
        Monitored quantities per point (each shape (n_points,) or (n_points, ...)).
    newton_iterations : ndarray of int, shape (n_points,)
    step_size : ndarray, shape (n_points,)
        Arclength step that led to each point (0 for the first).
    residual_histories : list of ndarray
        Corrector residual norms per Newton iteration, per point.
    special_points : list of (str, int)
        ("start", 0), ("fold", i), bound hits, and ("endpoint", last).
    status : str
        Why the branch stopped: "max_steps", "bound:<name>", "ds_min: ...",
        "interrupted", "start failed: ...".
    tangent : ndarray, shape (n,) or None
        Unit tangent at the last point (None if no point converged).
    next_ds : float
        The step the driver would have tried next.
    steps : int
        Continuation steps taken (points after the first).
    """

    u: np.ndarray
    records: dict
    newton_iterations: np.ndarray
    step_size: np.ndarray
    residual_histories: list
    special_points: list
    status: str
    tangent: np.ndarray | None = None
    next_ds: float = math.nan
    steps: int = 0


@dataclass
class ContinuationState:
    """Everything the driver needs to go on from its last accepted point, as if it had
    never stopped (what a checkpoint file stores; see :mod:`mmshbm.core.checkpoint`).

    Attributes
    ----------
    u : list of ndarray, each shape (n,)
        Scaled unknowns of the points so far.
    records : list of dict
        Monitored quantities per point.
    newton_iterations : list of int
    step_size : list of float
    residual_histories : list of ndarray
    special_points : list of (str, int)
        Special points so far (no "endpoint").
    tangent : ndarray, shape (n,)
        Unit tangent at the last point.
    ds : float
        The step to try next.
    steps : int
        Continuation steps taken so far.
    """

    u: list
    records: list
    newton_iterations: list
    step_size: list
    residual_histories: list
    special_points: list
    tangent: np.ndarray
    ds: float
    steps: int


class _Failure(Exception):
    pass


def newton(problem: ContinuationProblem, u: np.ndarray, tangent: np.ndarray, u_pred: np.ndarray,
           tol: float, max_iter: int, step_tol: float = 0.0):
    """Newton corrector on [R(u); t·(u − u_pred)] = 0.

    Converged when the residual's infinity norm is <= ``tol``, or when the update's is
    <= ``step_tol`` with the residual <= √tol. Returns (u, iterations, residual
    history, Jacobian at u). Raises ``_Failure``.
    """
    history = []
    du_norm = np.inf
    for it in range(max_iter + 1):
        try:
            R, J = problem.evaluate(u, jacobian=True)
        except (ArithmeticError, np.linalg.LinAlgError, ValueError, RuntimeError) as err:
            # ArithmeticError includes condense.SingularDynamicStiffness (kΩ on a pole);
            # RuntimeError is what SuperLU raises for an exactly singular matrix
            raise _Failure(f"residual failed: {err}") from None
        arc = float(tangent @ (u - u_pred))
        norm = max(float(np.abs(R).max()) if R.size else 0.0, abs(arc))
        history.append(norm)
        if not math.isfinite(norm):
            raise _Failure("non-finite residual")
        if norm <= tol or (du_norm <= step_tol and norm <= math.sqrt(tol)):
            return u, it, np.array(history), J
        if it == max_iter:
            break
        rhs = np.empty(len(R) + 1)
        rhs[:-1] = R
        rhs[-1] = arc
        du = _bordered_solve(J, tangent, rhs)
        du_norm = float(np.abs(du).max())
        if not math.isfinite(du_norm):
            raise _Failure("singular Jacobian")
        u = u - du
    raise _Failure(f"no convergence in {max_iter} iterations (residual {history[-1]:.2e})")


def _bordered_solve(J, t: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve [J; tᵀ] x = rhs for dense or sparse J."""
    if not isinstance(J, np.ndarray) and sp.issparse(J):
        return solve_bordered_sparse(J, t, rhs)  # block elimination, full LU fallback
    n = len(rhs)
    A = np.empty((n, n))
    A[:-1] = J
    A[-1] = t
    if n <= _SMALL_DENSE:
        x = np.empty(n)
        if _small_dense_solver()(A, np.ascontiguousarray(rhs, dtype=float), np.empty((n, n)), x):
            return np.full_like(rhs, np.nan)
        return x
    try:
        return np.linalg.solve(A, rhs)
    except np.linalg.LinAlgError:
        return np.full_like(rhs, np.nan)


#: bordered systems up to this size are solved by a Numba LU (LAPACK's call overhead
#: dominates below it; measured 2.1 against 7.6 µs at n = 13, 10 against 16 µs at n = 33,
#: 53 against 37 µs at n = 64)
_SMALL_DENSE = 40


def _small_dense_solver():
    """The Numba LU kernel (imported on first use: importing numba is not cheap)."""
    global _dense_solve
    if _dense_solve is None:
        from .kernels import _dense_solve
    return _dense_solve


_dense_solve = None


def _tangent(J, t_prev: np.ndarray) -> np.ndarray:
    rhs = np.zeros(len(t_prev))
    rhs[-1] = 1.0
    t = _bordered_solve(J, t_prev, rhs)
    if not np.all(np.isfinite(t)):
        raise _Failure("singular Jacobian at the tangent")
    t /= np.linalg.norm(t)
    return t if t @ t_prev >= 0 else -t


def continue_branch(problem: ContinuationProblem, u0: np.ndarray, t0: np.ndarray,
                    options: ContinuationOptions | None = None,
                    callback: Callable[[np.ndarray, dict], None] | None = None,
                    progress=None, *, resume: ContinuationState | None = None,
                    on_point: Callable[[dict], None] | None = None) -> ContinuationResult:
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

    Returns
    -------
    ContinuationResult
        Never raises for a failing branch: the status says why it stopped. Raises
        ValueError if ``options.bounds`` names a quantity the problem does not monitor.
    """
    opt = options or ContinuationOptions()
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
            accept(u, nit, 0.0, hist, rec, t, opt.ds, 0, terminal=terminal)
            if terminal:
                return result(terminal)
            ds, step = opt.ds, 0
        else:
            u = us[-1]
            t = np.asarray(resume.tangent, dtype=float)
            ds, step = float(resume.ds), int(resume.steps)
            state.update(t=t, ds=ds, steps=step)
            _check_bound_names(opt.bounds, recs[-1])
        status = "max_steps"
        while step < opt.max_steps:
            try:
                u_new, nit, hist, J = _corrector(problem, u, t, ds, opt)
                t_new = _tangent(J, t)
                if t_new @ t < math.cos(opt.max_angle) and ds > opt.corner_ds:
                    raise _Failure("tangent turned too far")
                rec = _monitor(problem, u_new)
            except _Failure as err:
                ds *= 0.5
                log.debug("step failed (%s); ds -> %g", err, ds)
                if ds < opt.ds_min:
                    status = f"ds_min: step size fell below {opt.ds_min:g} ({err})"
                    break
                continue
            step += 1
            crossed = _outside(rec, opt.bounds)
            if crossed:
                u_new, nit, hist, rec, t_new = _refine_onto_bound(problem, u, t, ds, crossed, recs[-1], rec,
                                                                  opt, (u_new, nit, hist, rec, t_new))
                status = f"bound:{crossed[0]}"
                accept(u_new, nit, ds, hist, rec, t_new, ds, step, [SpecialPoint(status, len(us))],
                       terminal=status)
                break
            new_special = []
            if t_new[-1] * t[-1] < 0 and min(abs(t_new[-1]), abs(t[-1])) > 1e-6:
                new_special.append(SpecialPoint("fold", len(us)))
            ds_prev = ds
            ds = min(opt.ds_max, ds * (1 + opt.growth * ((opt.max_newton - nit) / opt.max_newton) ** 2))
            accept(u_new, nit, ds_prev, hist, rec, t_new, ds, step, new_special)
            u, t = u_new, t_new
    except KeyboardInterrupt:
        status = "interrupted"
    return result(status)


def _monitor(problem, u) -> dict:
    """``problem.monitor(u)``; a numerical failure (e.g. a singular factorisation in the
    recovery) makes the step fail instead of the run."""
    try:
        return problem.monitor(u)
    except (ArithmeticError, np.linalg.LinAlgError, ValueError, RuntimeError) as err:
        raise _Failure(f"monitor failed: {err}") from None


def _check_bound_names(bounds, rec: dict) -> None:
    unknown = sorted(set(dict(bounds)) - set(rec))
    if unknown:
        raise ValueError(f"bounds on unknown quantit{'y' if len(unknown) == 1 else 'ies'} "
                         f"{', '.join(map(repr, unknown))}; the problem monitors {sorted(rec)}")


def _corrector(problem, u, t, ds, opt, start=None):
    """Newton on the hyperplane t·(v − u − ds t) = 0, from ``start`` (a point on that
    hyperplane; default the predictor u + ds t)."""
    u_pred = u + ds * t
    u_new, nit, hist, J = newton(problem, u_pred if start is None else start, t, u_pred, opt.newton_tol,
                                 opt.max_newton, opt.step_tol)
    if np.linalg.norm(u_new - u_pred) > 2.0 * ds + 10 * opt.newton_tol:
        raise _Failure("corrector left the predictor cone")
    return u_new, nit, hist, J


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
