"""The corrector of the fused friction forced response in one compiled call: the Newton
loop of :func:`mmshbm.methods.mms.corrector.corrector_to_roundoff` (the same steps, the
same tests, the same tolerances) around the fused evaluation
(:func:`~mmshbm.methods.mms._friction_fused._forced_friction_evaluate`), with the bordered
systems [J; tᵀ] solved by the small dense LU of :func:`mmshbm.core.bordered.bordered_solve`
(:func:`~mmshbm.harmonic.kernels._dense_solve`).

The loop, as there: Newton on [R(u); t·(u − u_pred)] = 0 with the merit
m(v) = max(max|R(v)|, |t·(v − u_pred)|); above the tolerance each step is halved (down to
1/4096) until m decreases by 1e-4 λ m; once m <= tol Newton goes on while a step halves m,
tries the steps 1/2 … 1/64 above the round-off floor, and stops at the round-off of u
(every |du_i| <= 8 ε max(|u_i|, 1)) or when no step lowers m (the better point returned);
a stall with m above max(floor, stall·tol) and a step above ``step_tol`` is a failure; a
backtracking failure with a step <= ``step_tol`` and m <= √tol is the residual's floor.

Kernels only; plain contiguous arrays. Cross-file callees are safe under the package's
cache policy (:mod:`mmshbm._kernel_cache`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..._kernel_cache import JIT_OPTIONS
from ..._kernel_cache import install as _install_cache_policy
from ...harmonic.kernels import _dense_solve
from ._friction_fused import _forced_friction_evaluate

__all__: list[str] = []

_install_cache_policy()

_EPS = float(np.finfo(float).eps)

#: statuses of :func:`_forced_friction_correct` (info[2] holds the number they report)
CONVERGED, NOT_FINITE, SINGULAR_JACOBIAN, STALLED, NO_CONVERGENCE, SINGULAR_CONDENSATION = range(6)


@njit(**JIT_OPTIONS)
def _evaluate_at(v, cs, rs, length, fx, wk, jacobian, R, J):
    """:func:`_forced_friction_evaluate` at ``v`` with its constant arguments ``fx`` and work
    buffers ``wk`` as tuples (the order of that kernel's arguments)."""
    return _forced_friction_evaluate(
        v, cs, rs, length, fx[0], fx[1], fx[2], fx[3], fx[4], fx[5], fx[6], fx[7], fx[8], fx[9], fx[10],
        fx[11], fx[12], fx[13], fx[14], fx[15], fx[16], fx[17], fx[18], fx[19], fx[20], fx[21], fx[22],
        fx[23], fx[24], fx[25], fx[26], jacobian, wk[0], wk[1], wk[2], wk[3], wk[4], wk[5], wk[6], wk[7],
        wk[8], wk[9], wk[10], wk[11], wk[12], wk[13], R, J)


@njit(**JIT_OPTIONS)
def _merit(v, u_pred, t, R):
    """max(max|R|, |t·(v − u_pred)|), NaN in R propagating (as NumPy's max, then Python's
    max of the two)."""
    m = 0.0
    for a in range(R.shape[0]):
        x = abs(R[a])
        if x != x:
            m = x
            break
        if a == 0 or x > m:
            m = x
    d = 0.0
    for a in range(v.shape[0]):
        d += t[a] * (v[a] - u_pred[a])
    d = abs(d)
    if d > m:
        m = d
    return m


@njit(**JIT_OPTIONS)
def _max_abs(v):
    m = 0.0
    for a in range(v.shape[0]):
        x = abs(v[a])
        if x != x:
            return x
        if x > m:
            m = x
    return m


@njit(**JIT_OPTIONS)
def _forced_friction_correct(u0, u_pred, t, tol, max_iter, step_tol, floor, stall, min_step,
                             cs, rs, length, fx, wk, u_out, J_out, history, info):
    """Newton from ``u0`` (n,) on [R(u); t·(u − u_pred)] = 0 (module docstring), in place.

    u_pred, t : (n,) the predictor and the tangent; tol, max_iter, step_tol as the Python
                corrector; floor the merit at the residual's round-off, stall the factor of
                tol above which a stall fails, min_step the smallest backtracking step
    cs, rs, length, fx, wk : the evaluation's scalings, constant arguments and work buffers
                (:func:`_evaluate_at`)
    u_out (n,), J_out (n − 1, n) <- the point and the Jacobian at it (or at the iterate one
    round-off step before it); history (>= 2 max_iter + 3,) <- the merits; info (3,) <-
    [iterations, merits recorded, the number the status reports: the last merit, or Ω in
    rad/s of a singular condensation].
    Returns a status (CONVERGED …; the outputs other than info are complete only when
    CONVERGED).
    """
    n = u0.shape[0]
    m = n - 1
    u = u0.copy()
    ut = np.empty(n)
    uh = np.empty(n)
    R = np.empty(m)
    J = np.empty((m, n))
    Rt = np.empty(m)
    Jt = np.empty((m, n))
    Rh = np.empty(m)
    no_j = np.empty((0, 0))
    A = np.empty((n, n))
    rhs = np.empty(n)
    LU = np.empty((n, n))
    x = np.empty(n)
    du = np.empty(n)
    sign = np.empty(1)
    omega_scale = cs[n - 1]
    info[0] = 0.0
    info[1] = 0.0
    info[2] = 0.0
    if _evaluate_at(u, cs, rs, length, fx, wk, True, R, J) != 0:
        info[2] = u[n - 1] * omega_scale
        return SINGULAR_CONDENSATION
    r = _merit(u, u_pred, t, R)
    has_j = True
    history[0] = r
    nh = 1
    r_new = r
    r_lam = r
    full = True
    status = 0
    stall_tol = max(floor, stall * tol)
    for it in range(max_iter + 1):
        info[0] = it
        info[1] = nh
        info[2] = history[nh - 1]
        if not math.isfinite(r):
            return NOT_FINITE
        if not has_j:
            if _evaluate_at(u, cs, rs, length, fx, wk, True, R, J) != 0:
                info[2] = u[n - 1] * omega_scale
                return SINGULAR_CONDENSATION
            has_j = True
        # the bordered solve [J; tᵀ] du = −[R; t·(u − u_pred)]
        d = 0.0
        for a in range(n):
            d += t[a] * (u[a] - u_pred[a])
        for a in range(m):
            for b in range(n):
                A[a, b] = J[a, b]
            rhs[a] = R[a]
        for b in range(n):
            A[m, b] = t[b]
        rhs[m] = d
        if _dense_solve(A, rhs, LU, x, sign) != 0:
            return SINGULAR_JACOBIAN
        for a in range(n):
            du[a] = -x[a]
            if not math.isfinite(du[a]):
                return SINGULAR_JACOBIAN
        du_max = _max_abs(du)
        if r <= tol:
            # at the tolerance: on to the round-off of u (corrector.at_roundoff)
            at_roundoff = True
            for a in range(n):
                if abs(du[a]) > 8 * _EPS * max(abs(u[a]), 1.0):
                    at_roundoff = False
                    break
            if at_roundoff:
                r_new = r
                take = False
            else:
                for a in range(n):
                    ut[a] = u[a] + du[a]
                if _evaluate_at(ut, cs, rs, length, fx, wk, True, Rt, Jt) != 0:
                    info[2] = ut[n - 1] * omega_scale
                    return SINGULAR_CONDENSATION
                r_new = _merit(ut, u_pred, t, Rt)
                if r_new <= 0.5 * r:  # the full step halves the merit: on
                    u, ut = ut, u
                    R, Rt = Rt, R
                    J, Jt = Jt, J
                    r = r_new
                    history[nh] = r
                    nh += 1
                    continue
                halved = False
                if r > floor and du_max > step_tol:
                    lam = 0.5
                    while lam >= 1.0 / 64:
                        for a in range(n):
                            uh[a] = u[a] + lam * du[a]
                        if _evaluate_at(uh, cs, rs, length, fx, wk, False, Rh, no_j) != 0:
                            info[2] = uh[n - 1] * omega_scale
                            return SINGULAR_CONDENSATION
                        r_lam = _merit(uh, u_pred, t, Rh)
                        if r_lam < (1 - 1e-4 * lam) * r:
                            halved = True
                            break
                        lam *= 0.5
                if halved:  # a shorter step lowered the merit: on, the Jacobian to evaluate
                    u, uh = uh, u
                    R, Rh = Rh, R
                    has_j = False
                    r = r_lam
                    history[nh] = r
                    nh += 1
                    continue
                take = r_new < r
            if take:  # done at the full step's point, its Jacobian evaluated there
                for a in range(n):
                    u_out[a] = ut[a]
                for a in range(m):
                    for b in range(n):
                        J_out[a, b] = Jt[a, b]
            else:
                r_new = r
                for a in range(n):
                    u_out[a] = u[a]
                for a in range(m):
                    for b in range(n):
                        J_out[a, b] = J[a, b]
            if r_new > stall_tol and du_max > step_tol:
                info[2] = r_new
                return STALLED
            if r_new < r:
                history[nh] = r_new
                nh += 1
            info[1] = nh
            info[2] = history[nh - 1]
            return CONVERGED
        if it == max_iter:
            break
        # above the tolerance: the step halved until the merit decreases (corrector.backtrack)
        lam = 1.0
        ok = False
        while True:
            for a in range(n):
                ut[a] = u[a] + lam * du[a]
            full = lam == 1.0
            if full:
                status = _evaluate_at(ut, cs, rs, length, fx, wk, True, Rt, Jt)
            else:
                status = _evaluate_at(ut, cs, rs, length, fx, wk, False, Rt, no_j)
            if status != 0:
                info[2] = ut[n - 1] * omega_scale
                return SINGULAR_CONDENSATION
            r_new = _merit(ut, u_pred, t, Rt)
            if r_new < (1 - 1e-4 * lam) * r:
                ok = True
                break
            if lam <= min_step:
                break
            lam *= 0.5
        if not ok:
            if du_max <= step_tol and r <= math.sqrt(tol):  # the residual's floor above tol
                for a in range(n):
                    u_out[a] = u[a]
                for a in range(m):
                    for b in range(n):
                        J_out[a, b] = J[a, b]
                info[1] = nh
                return CONVERGED
            break
        u, ut = ut, u
        R, Rt = Rt, R
        if full:
            J, Jt = Jt, J
        has_j = full
        r = r_new
        history[nh] = r
        nh += 1
    info[1] = nh
    info[2] = history[nh - 1]
    return NO_CONVERGENCE
