"""Compiled period march of :mod:`.pair_march`: the generalised-α scheme on the DOFs with
mass in physical coordinates, each step's massless DOFs in static equilibrium with
Coulomb friction of constant slip force (an l1-regularised quadratic programme).

Arrays (n DOFs with mass, m massless DOFs):

* ``M``, ``C`` (n, n): mass (kg) and damping (N·s/m) of the DOFs with mass;
* ``Kinv`` (n, n): ((1 − α_m)/((1 − α_f) β h²) M + γ/(β h) C + K_ll)⁻¹ (m/N), the step's
  effective flexibility;
* ``G`` (n, m): Kinv K_lc; ``KclKinv`` (m, n): K_cl Kinv;
* ``S`` (m, m): K_cc − K_cl Kinv K_lc (N/m), the massless DOFs' stiffness over one step
  (symmetric positive definite);
* ``Fc``, ``Fs`` (n,): the force F(t) = Fc cos Ωt + Fs sin Ωt (N) on the DOFs with mass;
* ``slip`` (m,): each massless DOF's slip force c_i = μ_i N_i >= 0 (N; 0: a free DOF).

The law on massless DOF i, implicit in the step's increment Δ_i = s_i − s_i⁰: the force it
needs from its support, p_i (the structure's equation K_cl q + K_cc s + p = 0), obeys
|p_i| <= c_i and p_i = c_i sign(Δ_i) where Δ_i ≠ 0. With q eliminated this is the
minimum of ½ Δᵀ S Δ − bᵀ Δ + Σ c_i |Δ_i| (convex: a unique Δ), solved by a primal–dual
active set on {stick, slip +, slip −} warm-started from the previous step, and where that
cycles by cyclic coordinate descent (soft thresholding, convergent for any positive
definite S) whose sign pattern the active set then finishes.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...harmonic.kernels import JIT_OPTIONS


@njit(**JIT_OPTIONS)
def _pdas(S, b, c, state, x, max_iter):
    """The l1 problem by a primal–dual active set from ``state`` (0 stick, ±1 slip): x and
    state in place; the passes, or −1 when it cycles or exceeds ``max_iter``."""
    m = len(b)
    bs = 0.0
    for i in range(m):
        bs = max(bs, abs(b[i]), c[i])
    ftol = 1e-12 * max(bs, 1e-300)
    for it in range(max_iter):
        free = np.empty(m, dtype=np.int64)
        nf = 0
        for i in range(m):
            if state[i] != 0:
                free[nf] = i
                nf += 1
        x[:] = 0.0
        if nf:
            A = np.empty((nf, nf))
            r = np.empty(nf)
            for a in range(nf):
                i = free[a]
                r[a] = b[i] - state[i] * c[i]
                for e in range(nf):
                    A[a, e] = S[i, free[e]]
            y = np.linalg.solve(A, r)
            for a in range(nf):
                x[free[a]] = y[a]
        xs = 0.0
        for i in range(m):
            xs = max(xs, abs(x[i]))
        xtol = 1e-13 * max(xs, 1e-300)
        switched = False
        for i in range(m):
            if state[i] == 0:
                p = b[i]
                for j in range(m):
                    p -= S[i, j] * x[j]
                if abs(p) > c[i] + ftol:
                    state[i] = 1 if p > 0 else -1
                    switched = True
            elif state[i] * x[i] < -xtol:
                state[i] = 0
                switched = True
        if not switched:
            return it + 1
    return -1


@njit(**JIT_OPTIONS)
def _descent(S, b, c, x, max_sweeps, tol):
    """Cyclic coordinate descent on the l1 problem from x (in place): sweeps run, −1 when
    the largest change of a sweep stayed above ``tol`` times max|x|."""
    m = len(b)
    for sweep in range(max_sweeps):
        change, size = 0.0, 0.0
        for i in range(m):
            t = b[i]
            for j in range(m):
                if j != i:
                    t -= S[i, j] * x[j]
            if t > c[i]:
                new = (t - c[i]) / S[i, i]
            elif t < -c[i]:
                new = (t + c[i]) / S[i, i]
            else:
                new = 0.0
            change = max(change, abs(new - x[i]))
            x[i] = new
            size = max(size, abs(new))
        if change <= tol * max(size, 1e-300):
            return sweep + 1
    return -1


@njit(**JIT_OPTIONS)
def _l1_step(S, b, c, state, x, max_iter, max_sweeps):
    """Δ of the step's l1 problem into x, state updated: True on success."""
    keep = state.copy()
    if _pdas(S, b, c, state, x, max_iter) >= 0:
        return True
    x[:] = 0.0
    if _descent(S, b, c, x, max_sweeps, 1e-15) < 0:
        state[:] = keep
        return False
    xs = 0.0
    for i in range(len(x)):
        xs = max(xs, abs(x[i]))
    for i in range(len(x)):
        state[i] = 0 if abs(x[i]) <= 1e-12 * xs else (1 if x[i] > 0 else -1)
    return _pdas(S, b, c, state, x, max_iter) >= 0


@njit(**JIT_OPTIONS)
def _march(q, v, a, s, p, state, M, C, K_ll, K_lc, Kinv, G, KclKinv, S, Fc, Fs, slip, omega, h, t0, steps,
           ramp, alpha_m, alpha_f, beta, gamma, max_iter, max_sweeps, rec_q, rec_s, rec_p):
    """``steps`` generalised-α steps from time t0 (s) on the state (q, v, a, s, p, state)
    in place; the force scaled by the ramp ½(1 − cos(π t/ramp)) for t < ramp (s). Records
    (when their first dimension is steps + 1): q, s, p per step. Returns (input work,
    viscous work, friction work) over the steps (J, trapezoidal), or work[0] = nan when
    a step's law could not be solved."""
    n, m = len(q), len(s)
    bl = np.empty(n)
    bb = np.empty(m)
    dx = np.empty(m)
    work = np.zeros(3)
    rec = rec_q.shape[0] == steps + 1
    c0 = 1.0 / (beta * h * h)
    af1 = 1.0 - alpha_f
    t = t0
    fac = 1.0 if t >= ramp else 0.5 * (1.0 - np.cos(np.pi * t / ramp))
    F_old = fac * (Fc * np.cos(omega * t) + Fs * np.sin(omega * t))
    if rec:
        rec_q[0], rec_s[0], rec_p[0] = q, s, p
    for k in range(steps):
        t = t0 + (k + 1) * h
        fac = 1.0 if t >= ramp else 0.5 * (1.0 - np.cos(np.pi * t / ramp))
        F = fac * (Fc * np.cos(omega * t) + Fs * np.sin(omega * t))
        tm = t - alpha_f * h
        fac = 1.0 if tm >= ramp else 0.5 * (1.0 - np.cos(np.pi * tm / ramp))
        Fm = fac * (Fc * np.cos(omega * tm) + Fs * np.sin(omega * tm))
        # a_{n+1} = c0 q_{n+1} + ah, v_{n+1} = c1 q_{n+1} + vh
        ah = -c0 * (q + h * v + h * h * (0.5 - beta) * a)
        vh = v + h * (1.0 - gamma) * a + gamma * h * ah
        am = (1.0 - alpha_m) * ah + alpha_m * a
        vm_ = af1 * vh + alpha_f * v
        bl[:] = (Fm - M @ am - C @ vm_ - alpha_f * (K_ll @ q + K_lc @ s)) / af1
        qh = Kinv @ bl
        # b = r − S s⁰, r = −K_cl Kinv b_l
        bb[:] = -(KclKinv @ bl) - S @ s
        if not _l1_step(S, bb, slip, state, dx, max_iter, max_sweeps):
            work[0] = np.nan
            return work
        fw = 0.0
        for i in range(m):
            pn = bb[i]
            for j in range(m):
                pn -= S[i, j] * dx[j]
            if state[i] != 0:
                pn = state[i] * slip[i]
            fw += 0.5 * (p[i] + pn) * dx[i]
            p[i] = pn
            s[i] += dx[i]
        qn = qh - G @ s
        dq = qn - q
        an = c0 * qn + ah
        vn = v + h * ((1.0 - gamma) * a + gamma * an)
        work[0] += 0.5 * np.dot(F_old + F, dq)
        vbar = 0.5 * (v + vn)
        work[1] += np.dot(vbar, C @ vbar) * h
        work[2] += fw
        a[:] = an
        v[:] = vn
        q[:] = qn
        F_old = F
        if rec:
            rec_q[k + 1], rec_s[k + 1], rec_p[k + 1] = q, s, p
    return work
