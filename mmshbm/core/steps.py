"""One step of the continuation: the Newton corrector on the bordered system, the tangent,
the monitor of a converged point, and the step-length rules (:mod:`mmshbm.core.continuation`
is the driver that strings the steps into a branch).

Newton on [R(u); t·(u − u_p)] = 0 with the bordered Jacobian [J; tᵀ]; the tangent solves
[J; tᵀ] t' = [0; 1] and is oriented along the previous one; the sign of det [J; tᵀ] is kept
for branch points. A problem may provide ``fast_newton`` (a compiled corrector, MMS-HBM's):
the numbers are those of the Python loop. Failures raise ``_Failure``; the driver halves
the step.
"""

from __future__ import annotations

import math

import numpy as np

from .bordered import bordered_solve as _bordered_solve
from .bordered import bordered_solve_sign as _bordered_solve_sign
from .options import ContinuationOptions, ContinuationProblem
from .pinned import PinnedFailure

__all__ = ["newton"]


class _Failure(Exception):
    pass


def newton(problem: ContinuationProblem, u: np.ndarray, tangent: np.ndarray, u_pred: np.ndarray,
           tol: float, max_iter: int, step_tol: float = 0.0):
    """Newton corrector on [R(u); t·(u − u_pred)] = 0.

    Converged when the residual's infinity norm is <= ``tol``, or when the update's is
    <= ``step_tol`` with the residual <= √tol. Returns (u, iterations, residual
    history, Jacobian at u). Raises ``_Failure``.
    """
    fast = problem.fast_newton
    if fast is not None:  # a compiled loop for small dense problems (MMS-HBM, modal back end)
        try:
            out = fast(u, u_pred, tangent, tol, max_iter, step_tol)
        except (ArithmeticError, np.linalg.LinAlgError, ValueError, RuntimeError) as err:
            raise _Failure(str(err)) from None
        if out is not None:
            return out
    history = []
    du_norm = np.inf
    for it in range(max_iter + 1):
        try:
            R, J = problem.residual_and_jacobian(u)
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
        if _predicted_converged(history, tol):
            return u, it + 1, np.array(history + [_predicted(history)]), J
    raise _Failure(f"no convergence in {max_iter} iterations (residual {history[-1]:.2e})")


def _curvature(t_old: np.ndarray, t_new: np.ndarray, ds: float, turn: float | None = None):
    """dt/ds over the last step (the second-order predictor's κ), or None after a jump or a
    refinement (ds = 0) or across a sharp turn (the tangents more than ~26° apart).
    ``turn``: t_new·t_old when the caller has it (the same number)."""
    if ds > 0 and (float(t_new.dot(t_old)) if turn is None else turn) > 0.9:
        kappa = t_new - t_old
        kappa /= ds
        return kappa
    return None


def _next_step(ds: float, nit: int, hist, opt: ContinuationOptions) -> float:
    """The next arclength step (before the ds_max cap) after a converged corrector."""
    if opt.step_control == "effort":
        return ds * (1 + opt.growth * ((opt.max_newton - nit) / opt.max_newton) ** 2)
    r0 = float(hist[0]) if len(hist) else 0.0
    factor = _MAX_GROWTH if r0 <= 0 else (opt.target_residual / r0) ** (1.0 / 3.0)
    return ds * min(_MAX_GROWTH, max(0.5, factor))


#: largest growth of the step from one point to the next (that of the effort rule at
#: growth = 0.5): steps that double run into corners (grazing) of nonsmooth residuals
_MAX_GROWTH = 1.5


def _predicted(history: list) -> float:
    """Residual after the next Newton step predicted from the last two, r_next = C r_k²,
    C = r_k / r_{k−1}² (quadratic convergence)."""
    r_prev, r = history[-2], history[-1]
    return r * (r / r_prev) ** 2 if r_prev > 0 else math.inf


def _predicted_converged(history: list, tol: float) -> bool:
    """True when Newton has entered quadratic convergence (the last residual is at most
    √tol, the last contraction at least tenfold) and the residual after the update just
    made is predicted below tol/10: the point is accepted without evaluating it again
    (the evaluation would accept it). Saves one evaluation per continuation step."""
    if len(history) < 2 or tol < SKIP_MIN_TOL:
        return False
    r_prev, r = history[-2], history[-1]
    return r <= math.sqrt(tol) and r <= 0.1 * r_prev and _predicted(history) <= 0.1 * tol


#: the skip needs a tolerance well above the round-off floor of the scaled residual
#: (~1e-13): below it a predicted residual is not one the arithmetic can deliver
SKIP_MIN_TOL = 1e-11


def _orientation(J, t: np.ndarray) -> float:
    """Sign of det [J; tᵀ] (0 where not computed: sparse or large J). Along a branch it
    changes sign at a simple branch point, not at a fold (the bordered matrix stays
    regular there and t turns continuously)."""
    if not isinstance(J, np.ndarray) or J.shape[1] > _DET_LIMIT:
        return 0.0
    A = np.empty((J.shape[1], J.shape[1]))
    A[:-1] = J
    A[-1] = t
    sign, _ = np.linalg.slogdet(A)
    return float(sign)


#: largest bordered system whose determinant sign is tracked (dense slogdet per point)
_DET_LIMIT = 400


def _tangent(J, t_prev: np.ndarray, problem=None) -> np.ndarray:
    return _tangent_sign(J, t_prev, problem)[0]


def _tangent_sign(J, t_prev: np.ndarray, problem=None) -> tuple[np.ndarray, float]:
    """:func:`_tangent_sign_turn` without t·t_prev."""
    return _tangent_sign_turn(J, t_prev, problem)[:2]


def _tangent_sign_turn(J, t_prev: np.ndarray, problem=None) -> tuple[np.ndarray, float, float]:
    """(t, sign, t·t_prev): the unit tangent (oriented along ``t_prev``), the sign of
    det [J; t] (0 if unknown) and t·t_prev (≥ 0). det [J; t_prev] and det [J; t] share
    their sign when t·t_prev > 0, because both are the cofactor vector of J (a multiple of
    t) dotted with the last row. A ``problem`` whose corrector already solved
    [J; t_prevᵀ] x = e_n gives x (its ``solved_tangent(J, t_prev)`` capability,
    :mod:`mmshbm.core.problem`)."""
    solved = problem.solved_tangent if problem is not None else None
    solved = solved(J, t_prev) if solved is not None else None
    if solved is not None:
        t, sign = solved
    else:
        rhs = np.zeros(len(t_prev))
        rhs[-1] = 1.0
        t, sign = _bordered_solve_sign(J, t_prev, rhs)
    norm2 = float(t.dot(t))  # finite when every entry is (and the norm does not overflow)
    if not math.isfinite(norm2):
        raise _Failure("singular Jacobian at the tangent")
    t /= math.sqrt(norm2)  # np.linalg.norm(t), without its checks
    # t.dot: the BLAS dot t @ t_prev calls, without matmul's dispatch; (-t)·t_prev is -turn
    # exactly (the same products and sums, negated)
    turn = float(t.dot(t_prev))
    return (t, sign, turn) if turn >= 0 else (-t, sign, -turn)


def _orientation_safe(problem, u, t) -> float:
    try:
        _, J = problem.residual_and_jacobian(u)
    except (ArithmeticError, np.linalg.LinAlgError, ValueError, RuntimeError):
        return 0.0
    return _orientation(J, t)


def _monitor(problem, u) -> dict:
    """``problem.monitor(u)``; a numerical failure (e.g. a singular factorisation in the
    recovery) makes the step fail instead of the run."""
    try:
        return problem.monitor(u)
    except (ArithmeticError, np.linalg.LinAlgError, ValueError, RuntimeError) as err:
        raise _Failure(f"monitor failed: {err}") from None


def _pinned_monitor(problem, u) -> dict:
    """:func:`_monitor` for the jumps, whose failures are PinnedFailure."""
    try:
        return _monitor(problem, u)
    except _Failure as err:
        raise PinnedFailure(str(err)) from None


def _step(problem, u, t, ds, opt, curvature):
    """One step from (u, t): corrector, tangent and monitor. Returns (u, iterations,
    residual history, J, tangent, sign of det [J; t], record)."""
    u_new, nit, hist, J = _corrector(problem, u, t, ds, opt, curvature=curvature)
    t_new, sign = _tangent_sign(J, t, problem)
    return u_new, nit, hist, J, t_new, sign, _monitor(problem, u_new)


def _advance(problem, u, t, ds, opt, curvature):
    """:func:`_advance_turn` without t_new·t."""
    return _advance_turn(problem, u, t, ds, opt, curvature)[:7]


def _advance_turn(problem, u, t, ds, opt, curvature):
    """One continuation step (:func:`_step`) that refuses a tangent turned by more than
    ``opt.max_angle`` while the step is longer than ``opt.corner_ds``. For problems with
    ``corner_parameter`` set, a shorter step that turns sharply and reverses the parameter is
    a corner of a nonsmooth branch: the tangent is turned back along the new piece, and a
    failed step is retried at fixed parameter (:func:`_corner_step`). The returns of
    :func:`_step` and t_new·t; raises ``_Failure``."""
    corner = problem.corner_parameter and ds <= opt.corner_ds
    try:
        # _step, with the monitor after the turn test (a refused step is not monitored)
        u_new, nit, hist, J = _corrector(problem, u, t, ds, opt, curvature=curvature)
        t_new, sign, turn = _tangent_sign_turn(J, t, problem)
        if turn < math.cos(opt.max_angle) and ds > opt.corner_ds and not (
                problem.corner_parameter and _kink_crossed(problem, u, t, ds, opt, curvature, t_new, turn)):
            raise _Failure("tangent turned too far")
        try:  # _monitor(problem, u_new), without its call
            rec = problem.monitor(u_new)
        except (ArithmeticError, np.linalg.LinAlgError, ValueError, RuntimeError) as err:
            raise _Failure(f"monitor failed: {err}") from None
        if corner and turn < math.cos(opt.max_angle) and t_new[-1] * t[-1] < 0:
            # at a corner the bordered tangent (oriented along t) points back along the new piece
            t_new, sign, turn = -t_new, -sign, -turn
    except _Failure:
        if not corner:
            raise
        out = _corner_step(problem, u, t, ds, opt)
        return (*out, float(out[4] @ t))
    return u_new, nit, hist, J, t_new, sign, rec, turn


def _kink_crossed(problem, u, t, ds, opt, curvature, t_new, turn) -> bool:
    """True when a step of length ``ds`` from (u, t) that turned the tangent by more than
    ``opt.max_angle`` (t_new·t = ``turn``) crossed a kink of the branch (a point where its
    tangent jumps: the onset of slip of a friction node, whose slider harmonics start to
    grow linearly from a constant) rather than a bend that a shorter step resolves. The
    half step tells: across a bend of curvature κ the tangent turns by κ·ds, half as far
    on the half step; across a kink within the first half it turns as far on both, and
    the two new tangents agree (the piece beyond the kink is straight on this scale).
    Halving to the kink instead costs a failed step per halving and a slow regrowth after
    it. A kink in the second half is found by the driver's next halving. A turn that reverses
    the parameter (t_new's last component against t's) is a corner, not a kink: refused here
    (the corner step takes it once ds <= corner_ds)."""
    if t_new[-1] * t[-1] <= 0:
        return False
    try:
        _, _, _, J_half = _corrector(problem, u, t, 0.5 * ds, opt, curvature=curvature)
        t_half, _, turn_half = _tangent_sign_turn(J_half, t, problem)
    except _Failure:
        return False
    angle, angle_half = math.acos(min(turn, 1.0)), math.acos(min(turn_half, 1.0))
    return angle_half >= 0.75 * angle and float(t_half.dot(t_new)) >= math.cos(0.5 * opt.max_angle)


def _corner_step(problem, u, t, ds, opt):
    """A step across a corner of the branch (the tangent turning by more than 90° within
    one step, where the pseudo-arclength hyperplane ahead does not meet the new piece and the
    bordered tangent points back along it), for problems that set ``corner_parameter``:
    Newton at the parameter of the predictor (the last unknown fixed at u_pred's), the new
    tangent oriented so that the parameter keeps its direction. Same returns as
    :func:`_step`; raises ``_Failure``."""
    u_pred = u + ds * t
    e = np.zeros(len(u))
    e[-1] = 1.0
    u_new, nit, hist, J = newton(problem, u_pred, e, u_pred, opt.newton_tol, opt.max_newton, opt.step_tol)
    if np.linalg.norm(u_new - u_pred) > 4.0 * ds + 10 * opt.newton_tol:
        raise _Failure("corner step left the predictor cone")
    t_new, sign = _tangent_sign(J, t)
    if t_new[-1] * t[-1] < 0:
        t_new, sign = -t_new, -sign
    return u_new, nit, hist, J, t_new, sign, _monitor(problem, u_new)


def _corrector(problem, u, t, ds, opt, start=None, curvature=None):
    """Newton on the hyperplane t·(v − u_pred) = 0 through the predictor u_pred = u + ds t
    (+ ½ ds² κ with the branch's curvature vector κ, when given: a second-order predictor,
    closer to the branch, so Newton needs fewer iterations), from ``start`` (a point on that
    hyperplane; default the predictor)."""
    u_pred = u + ds * t
    if curvature is not None:
        u_pred += 0.5 * ds * ds * curvature
    u0 = u_pred if start is None else start
    fast = problem.fast_newton
    out = None
    if fast is not None:  # newton's compiled loop, without its call
        try:
            out = fast(u0, u_pred, t, opt.newton_tol, opt.max_newton, opt.step_tol)
        except (ArithmeticError, np.linalg.LinAlgError, ValueError, RuntimeError) as err:
            raise _Failure(str(err)) from None
    if out is None:
        out = newton(problem, u0, t, u_pred, opt.newton_tol, opt.max_newton, opt.step_tol)
    u_new, nit, hist, J = out
    d = u_new - u_pred
    if math.sqrt(d.dot(d)) > 2.0 * ds + 10 * opt.newton_tol:  # np.linalg.norm(d), without its checks
        raise _Failure("corrector left the predictor cone")
    return u_new, nit, hist, J


def _outside(rec: dict, bounds) -> tuple | None:
    """(name, bound value) of the first bound that ``rec`` violates, else None."""
    for name, (lo, hi) in (bounds if isinstance(bounds, dict) else dict(bounds)).items():
        v = rec.get(name)
        if v is None:
            continue
        if v > hi:
            return (name, float(hi))
        if v < lo:
            return (name, float(lo))
    return None
