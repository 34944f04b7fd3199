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
import scipy.sparse.linalg as spla

from . import _validate as check

__all__ = ["ContinuationOptions", "ContinuationProblem", "ContinuationResult", "continue_branch", "newton"]

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
        Monitored quantities per point (each shape (n_points,)).
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
    """

    u: np.ndarray
    records: dict
    newton_iterations: np.ndarray
    step_size: np.ndarray
    residual_histories: list
    special_points: list
    status: str


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
        except (ArithmeticError, np.linalg.LinAlgError, ValueError) as err:
            raise _Failure(f"residual failed: {err}") from None
        arc = float(tangent @ (u - u_pred))
        norm = max(float(np.max(np.abs(R))) if R.size else 0.0, abs(arc))
        history.append(norm)
        if not math.isfinite(norm):
            raise _Failure("non-finite residual")
        if norm <= tol or (du_norm <= step_tol and norm <= math.sqrt(tol)):
            return u, it, np.array(history), J
        if it == max_iter:
            break
        du = _bordered_solve(J, tangent, np.append(R, arc))
        if not np.all(np.isfinite(du)):
            raise _Failure("singular Jacobian")
        u = u - du
        du_norm = float(np.max(np.abs(du)))
    raise _Failure(f"no convergence in {max_iter} iterations (residual {history[-1]:.2e})")


def _bordered_solve(J, t: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve [J; tᵀ] x = rhs for dense or sparse J."""
    if sp.issparse(J):
        A = sp.vstack([J, sp.csr_matrix(t[None, :])], format="csc")
        try:
            return spla.splu(A).solve(rhs)
        except RuntimeError:
            return np.full_like(rhs, np.nan)
    A = np.vstack([J, t[None, :]])
    try:
        return np.linalg.solve(A, rhs)
    except np.linalg.LinAlgError:
        return np.full_like(rhs, np.nan)


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
                    progress=None) -> ContinuationResult:
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
        Called with every accepted point (e.g. to checkpoint it).
    progress : tqdm-like, optional
        Object with ``update(1)`` and ``set_postfix(**kw)``.

    Returns
    -------
    ContinuationResult
        Never raises for a failing branch: the status says why it stopped.
    """
    opt = options or ContinuationOptions()
    t0 = np.asarray(t0, dtype=float)
    t0 = t0 / np.linalg.norm(t0)
    us, recs, nits, dss, hists, special = [], [], [], [], [], [("start", 0)]

    def accept(u, nit, ds, hist):
        rec = problem.monitor(u)
        us.append(u.copy())
        recs.append(rec)
        nits.append(nit)
        dss.append(ds)
        hists.append(hist)
        if callback is not None:
            callback(u, rec)
        if progress is not None:
            progress.update(1)
            progress.set_postfix({k: f"{v:.4g}" for k, v in rec.items() if k in ("frequency", "amplitude")}
                                 | {"ds": f"{ds:.2g}", "newton": nit})
        return rec

    def result(status):
        special.append(("endpoint", len(us) - 1))
        keys = recs[0].keys() if recs else ()
        return ContinuationResult(
            u=np.array(us), records={k: np.array([r[k] for r in recs]) for k in keys},
            newton_iterations=np.array(nits, dtype=int), step_size=np.array(dss),
            residual_histories=hists, special_points=special, status=status)

    try:
        u, nit, hist, J = newton(problem, np.asarray(u0, dtype=float), t0, np.asarray(u0, dtype=float),
                                 opt.newton_tol, opt.max_newton, opt.step_tol)
        t = _tangent(J, t0)
    except _Failure as err:
        return result(f"start failed: {err}")
    accept(u, nit, 0.0, hist)
    if _outside(recs[-1], opt.bounds):
        return result("start outside bounds")

    ds = opt.ds
    status = "max_steps"
    try:
        step = 0
        while step < opt.max_steps:
            try:
                u_new, nit, hist, J = _corrector(problem, u, t, ds, opt)
                t_new = _tangent(J, t)
                if t_new @ t < math.cos(opt.max_angle) and ds > opt.corner_ds:
                    raise _Failure("tangent turned too far")
            except _Failure as err:
                ds *= 0.5
                log.debug("step failed (%s); ds -> %g", err, ds)
                if ds < opt.ds_min:
                    status = f"ds_min: step size fell below {opt.ds_min:g} ({err})"
                    break
                continue
            step += 1
            rec = problem.monitor(u_new)
            crossed = _outside(rec, opt.bounds)
            if crossed:
                u_new, nit, hist = _refine_onto_bound(problem, u, t, ds, crossed, recs[-1], rec, opt,
                                                      (u_new, nit, hist))
                accept(u_new, nit, ds, hist)
                special.append((f"bound:{crossed[0]}", len(us) - 1))
                status = f"bound:{crossed[0]}"
                break
            if t_new[-1] * t[-1] < 0 and min(abs(t_new[-1]), abs(t[-1])) > 1e-6:
                special.append(("fold", len(us)))
            accept(u_new, nit, ds, hist)
            u, t = u_new, t_new
            ds = min(opt.ds_max, ds * (1 + opt.growth * ((opt.max_newton - nit) / opt.max_newton) ** 2))
    except KeyboardInterrupt:
        status = "interrupted"
    return result(status)


def _corrector(problem, u, t, ds, opt):
    u_pred = u + ds * t
    u_new, nit, hist, J = newton(problem, u_pred, t, u_pred, opt.newton_tol, opt.max_newton, opt.step_tol)
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
    """Secant iteration in the arclength s ∈ (0, ds) for monitor[name](s) = bound."""
    name, target = crossed
    s0, f0 = 0.0, rec_prev[name] - target
    s1, f1 = ds, rec_new[name] - target
    best = fallback
    for _ in range(12):
        if f1 == f0:
            break
        s = s1 - f1 * (s1 - s0) / (f1 - f0)
        s = min(max(s, 1e-3 * ds), ds)
        try:
            u_s, nit, hist, _ = _corrector(problem, u, t, s, opt)
        except _Failure:
            break
        f = problem.monitor(u_s)[name] - target
        best = (u_s, nit, hist)
        if abs(f) <= 1e-10 * max(abs(target), 1e-300) or abs(s - s1) < 1e-14:
            break
        s0, f0, s1, f1 = s1, f1, s, f
    return best
