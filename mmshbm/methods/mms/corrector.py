"""The corrector of the MMS-HBM forced response with friction: Newton on the bordered
system [R(u); t·(u − u_pred)] = 0, stopped at the solve's round-off.

A residual below the continuation's tolerance does not bound the error of the point: the
error is the residual times the condition of the Jacobian, and a point accepted at
|R| = 1e-10 sits up to ~1e-8 off the branch (friction at zero normal load, the linear
system, came out 1.5e-7 off the linear response). So once the
residual meets the tolerance Newton goes on while a step still halves the merit, and stops
when the step is at the round-off of u (every |du_i| <= 8 ε max(|u_i|, 1), u scaled to
O(1)) or no longer halves it (the residual's floor, kept as it is: the better of the last
two points is returned). Where the residual has a floor above the tolerance (near a pole
of the condensed stiffness) a step no longer lowering the merit with the step <=
``step_tol`` and the residual <= √tol is accepted, as by :func:`mmshbm.core.steps.newton`.

Globalised by halving the step until the merit decreases: the friction rows are
semismooth, and where a node sticks only briefly plain Newton cycles. Once the tolerance
is met, a stall above round-off (no step, halved down to 1/64, lowers the merit) with a
Newton step above ``step_tol`` is a failure, not a converged point: on a corner of the
branch such points were measured up to 5e-5 off it. A stall with a small step is the
residual's floor (a stiff model's scaled residual bottoms out near 1e-12).
"""

from __future__ import annotations

import math

import numpy as np

from ...core.bordered import bordered_solve

__all__ = ["corrector_to_roundoff", "at_roundoff", "backtrack"]

_EPS = float(np.finfo(float).eps)
#: a scaled merit below this is at the residual's round-off (scaled unknowns and rows are
#: O(1); the terms of the rows reach ~1e2 near a resonance): no line search below it
_FLOOR = 1e3 * _EPS
#: with the line search, a corrector that stalls above this times the tolerance has failed
_STALL = 1e-2


def _step_at_roundoff(u: np.ndarray, du: np.ndarray, scale) -> bool:
    """Every |du_i| <= 8 ε max(|u_i|, scale_i)."""
    return bool(np.all(np.abs(du) <= 8 * _EPS * np.maximum(np.abs(u), scale)))


def at_roundoff(merit, x: np.ndarray, dx: np.ndarray, r: float, R, scale, floor: float = 0.0, first=None,
                small: float = 0.0):
    """One Newton step ``dx`` from a point whose merit ``r`` already meets the tolerance:
    (done, x, merit, residual). Done when the step is at the round-off of x (``scale``: the
    size below which |x_i| counts as that size), or when x + dx does not halve the merit
    and, with the merit above ``floor`` (a level well above the residual's round-off) and a
    step above ``small`` (a step at the residual's floor is noise), no step halved down to
    1/64 lowers it (a corner of the semismooth rows): then the better point. Otherwise the
    step that lowered it is taken and Newton goes on. ``first``: the merit for the full
    step, when it differs (one that also returns the Jacobian)."""
    if _step_at_roundoff(x, dx, scale):
        return True, x, r, R
    r_new, R_new = (first or merit)(x + dx)
    if r_new <= 0.5 * r:
        return False, x + dx, r_new, R_new
    if r > floor and float(np.abs(dx).max()) > small:
        lam = 0.5
        while lam >= 1.0 / 64:
            r_lam, R_lam = merit(x + lam * dx)
            if r_lam < (1 - 1e-4 * lam) * r:
                return False, x + lam * dx, r_lam, R_lam
            lam *= 0.5
    if r_new < r:
        return True, x + dx, r_new, R_new
    return True, x, r, R


def backtrack(merit, x: np.ndarray, dx: np.ndarray, r: float, min_step: float = 1.0 / 4096, first=None):
    """x + λ dx with λ = 1, 1/2, ... down to ``min_step``: the first with merit below
    (1 − 1e-4 λ) r (``first``: the merit for λ = 1, when it differs). Returns (x, merit,
    residual, decreased)."""
    lam = 1.0
    while True:
        r_new, R_new = (first if first is not None and lam == 1.0 else merit)(x + lam * dx)
        if r_new < (1 - 1e-4 * lam) * r:
            return x + lam * dx, r_new, R_new, True
        if lam <= min_step:
            return x, r, merit(x)[1], False
        lam *= 0.5


def corrector_to_roundoff(problem, u: np.ndarray, u_pred: np.ndarray, tangent: np.ndarray, tol: float,
                          max_iter: int, step_tol: float, solve=None):
    """Newton on [R(u); t·(u − u_pred)] = 0 for ``problem`` (``residual``,
    ``residual_and_jacobian`` on scaled unknowns), each step halved until the merit
    max(|R|, |t·(u − u_pred)|) decreases, stopped at round-off (module docstring).

    ``solve(J, t, rhs)``: the bordered linear solve (default
    :func:`~mmshbm.core.bordered.bordered_solve`, the dense LU).

    Returns (u, iterations, merit history, Jacobian at u or at the iterate one round-off
    step before it). Raises RuntimeError when it does not converge in ``max_iter`` or stalls
    above round-off once the tolerance is met (the continuation then retries the step).
    """

    def size(R, v):
        return max(float(np.abs(R).max()) if R.size else 0.0, abs(float(tangent @ (v - u_pred))))

    def merit(v):  # (merit, (R, None))
        R = problem.residual(v)
        return size(R, v), (R, None)

    def merit_full(v):  # (merit, (R, J)): a full step is taken most of the time
        R, J = problem.residual_and_jacobian(v)
        return size(R, v), (R, J)

    stall_tol = max(_FLOOR, _STALL * tol)
    r, (R, J) = merit_full(u)
    history = [r]
    for it in range(max_iter + 1):
        if not math.isfinite(r):
            raise RuntimeError("non-finite residual")
        if J is None:
            R, J = problem.residual_and_jacobian(u)
        du = -(solve or bordered_solve)(J, tangent, np.append(R, tangent @ (u - u_pred)))
        if not np.all(np.isfinite(du)):
            raise RuntimeError("singular Jacobian")
        if r <= tol:
            done, u_new, r_new, RJ = at_roundoff(merit, u, du, r, (R, J), 1.0, _FLOOR, merit_full, step_tol)
            if done:
                if r_new > stall_tol and float(np.abs(du).max()) > step_tol:
                    # no step lowers a merit above round-off and the Newton step is not small:
                    # Newton has stalled on a corner of the semismooth rows (a point accepted
                    # there was measured 5e-5 off the branch at a scaled residual of 8.5e-11,
                    # its Newton steps 1e-6 to 1e-4; at the residual's floor of a stiff model,
                    # 1e-12 to 1e-11 on NLvib's friction beam, the steps are 1e-12)
                    raise RuntimeError(f"Newton stalled at residual {r_new:.2e}")
                if r_new < r:
                    history.append(r_new)
                # the Jacobian at the point returned where it was evaluated there
                return u_new, it, np.array(history), (RJ[1] if RJ[1] is not None else J)
            u, r, (R, J) = u_new, r_new, RJ
            history.append(r)
            continue
        if it == max_iter:
            break
        u_new, r_new, RJ, ok = backtrack(merit, u, du, r, first=merit_full)
        if not ok:
            if float(np.abs(du).max()) <= step_tol and r <= math.sqrt(tol):
                return u, it, np.array(history), J  # the residual's floor above the tolerance
            break
        u, r, (R, J) = u_new, r_new, RJ
        history.append(r)
    raise RuntimeError(f"no convergence in {max_iter} iterations (residual {history[-1]:.2e})")
