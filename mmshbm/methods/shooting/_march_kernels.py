"""Compiled period march of :mod:`.friction_march`: Newmark's average acceleration in the
modal coordinates of the open structure, the contact nodes' exact law per step.

Arrays (n modes, m = 2 n_k interface DOFs: contact k's normal DOF at 2k, its friction DOF
at 2k + 1):

* ``w2``, ``cd``, ``kinv`` (n,): ω_k² (1/s²), 2 ζ_k ω_k (1/s), 1/(ω_k² + 2 cd_k/h + 4/h²) (s²);
* ``fc``, ``fs`` (n,): the modal force F_k(τ) = fc_k cos τ + fs_k sin τ (N/kg^½);
* ``psi`` (n, m), ``psiT`` its transpose (contiguous): Φᵀ K_lc K_cc⁻¹ E, the interface
  DOFs' coupling; a force f on them
  drives the modes with −psi f and their displacement is q_I = A_II f − psiᵀ η;
* ``R`` (m, m): the interface compliance over one step, A_II + psiᵀ diag(kinv) psi (m/N);
  ``R0`` = A_II, the compliance with the modes held (the start of a period);
* per contact k: ``side``, ``gap`` (m), ``mu``, ``pre`` (N).

Interface forces: f_{2k} = −side λ_k (λ >= 0 the contact force), f_{2k+1} = g_k (the
support's tangential force on the node). State of contact k's law: ``combo[k]`` in 0..5,
(normal, tangential) = ({open, closed}[c // 3], {stick, slip +, slip −}[c % 3]).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...harmonic.kernels import JIT_OPTIONS


@njit(**JIT_OPTIONS)
def _node_law(cn, ct, rnn, rnt, rtn, rtt, side, gap, mu, pre, u_old, first, out):
    """One contact's exact law with q_n = cn + rnn f_n + rnt g, u_t = ct + rtn f_n + rtt g,
    f_n = −side λ: the first consistent (normal, tangential) combination, ``first`` tried
    first (the order of :mod:`.friction_impact`). ``out`` ← (λ, g, u_t, combo); returns False
    when none holds."""
    s = side
    # in (λ, g): q_n = cn + Rn0 λ + Rn1 g, u_t = ct + Rt0 λ + Rt1 g
    rn0, rn1, rt0, rt1 = -s * rnn, rnt, -s * rtn, rtt
    for k in range(6):
        cb = first if k == 0 else (k - 1 if k - 1 < first else k)
        nm, tg = cb // 3, cb % 3
        if nm == 0:
            e00, e01, r0 = 1.0, 0.0, 0.0
        else:
            e00, e01, r0 = -s * rn0, -s * rn1, s * cn - gap
        if tg == 0:
            e10, e11, r1 = rt0, rt1, u_old - ct
        else:
            sg = 1.0 if tg == 1 else -1.0
            e10, e11, r1 = -sg * mu, 1.0, sg * mu * pre
        det = e00 * e11 - e01 * e10
        if det == 0.0:
            continue
        lam = (r0 * e11 - e01 * r1) / det
        g = (e00 * r1 - e10 * r0) / det
        qn = cn + rn0 * lam + rn1 * g
        ut = ct + rt0 * lam + rt1 * g
        S = mu * (pre + lam)
        tol = 1e-12 * max(1.0, abs(S))
        if nm == 1:
            ok_n = lam >= -tol
        else:
            ok_n = gap - s * qn >= -1e-14 * max(gap, 1e-300)
        if tg == 0:
            ok_t = abs(g) <= S + tol
        else:
            sg = 1.0 if tg == 1 else -1.0
            ok_t = -sg * (ut - u_old) >= -1e-14 * max(abs(ut), 1e-300)
        if ok_n and ok_t and S >= -tol:
            out[0], out[1], out[2], out[3] = max(lam, 0.0), g, ut, cb
            return True
    return False


@njit(**JIT_OPTIONS)
def _active_set(c, R, side, gap, mu, pre, u_old, lam, g, ut, combo, max_iter):
    """All contacts' laws with q_I = c + R f by a primal–dual active set: the linear system
    of every contact's current combination solved at once, each contact whose inequalities
    fail switched (open ↔ closed, stick → slip in the force's sign, slip → stick), until
    none fails. On success updates lam, g, ut, combo and returns the iterations; −1 (nothing
    changed) when it cycles or exceeds max_iter."""
    nk = len(side)
    m = 2 * nk
    cb = combo.copy()
    E = np.empty((m, m))
    r = np.empty(m)
    B = np.empty((m, m))  # q_I = c + B x, x = (λ_0, g_0, λ_1, ...)
    for i in range(m):
        for k in range(nk):
            B[i, 2 * k], B[i, 2 * k + 1] = -side[k] * R[i, 2 * k], R[i, 2 * k + 1]
    for it in range(max_iter):
        E[:, :] = 0.0
        for k in range(nk):
            n, t = 2 * k, 2 * k + 1
            nm, tg = cb[k] // 3, cb[k] % 3
            if nm == 0:
                E[n, n], r[n] = 1.0, 0.0
            else:
                E[n] = -side[k] * B[n]
                r[n] = side[k] * c[n] - gap[k]
            if tg == 0:
                E[t] = B[t]
                r[t] = u_old[k] - c[t]
            else:
                sg = 1.0 if tg == 1 else -1.0
                E[t, n], E[t, t], r[t] = -sg * mu[k], 1.0, sg * mu[k] * pre[k]
        x = np.linalg.solve(E, r)
        q = c + B @ x
        switched = False
        for k in range(nk):
            n, t = 2 * k, 2 * k + 1
            nm, tg = cb[k] // 3, cb[k] % 3
            S = mu[k] * (pre[k] + x[n])
            tol = 1e-12 * max(1.0, abs(S))
            if nm == 1 and x[n] < -tol:
                nm, switched = 0, True
            elif nm == 0 and gap[k] - side[k] * q[n] < -1e-14 * max(gap[k], 1e-300):
                nm, switched = 1, True
            if tg == 0 and abs(x[t]) > S + tol:
                tg, switched = (1 if x[t] > 0 else 2), True
            elif tg != 0:
                sg = 1.0 if tg == 1 else -1.0
                if -sg * (q[t] - u_old[k]) < -1e-14 * max(abs(q[t]), 1e-300):
                    tg, switched = 0, True
            cb[k] = 3 * nm + tg
        if not switched:
            for k in range(nk):
                lam[k], g[k], ut[k], combo[k] = max(x[2 * k], 0.0), x[2 * k + 1], q[2 * k + 1], cb[k]
            return it + 1
    return -1


@njit(**JIT_OPTIONS)
def _interface(c, R, side, gap, mu, pre, u_old, lam, g, ut, combo, max_sweeps, tol):
    """All contacts' laws with q_I = c + R f. One contact: its exact solve (the enumeration
    of :mod:`.friction_impact`). Several: the active set (:func:`_active_set`), and where it
    cycles block Gauss–Seidel over the contacts, each block (normal, tangential) solved
    exactly with the others held. Updates lam, g, ut, combo in place (warm start: their
    values on entry); returns the iterations taken, −1 if a block has no consistent state or
    the sweeps do not settle."""
    if len(side) > 1:
        it = _active_set(c, R, side, gap, mu, pre, u_old, lam, g, ut, combo, 100)
        if it > 0:
            return it
    return _gauss_seidel(c, R, side, gap, mu, pre, u_old, lam, g, ut, combo, max_sweeps, tol)


@njit(**JIT_OPTIONS)
def _gauss_seidel(c, R, side, gap, mu, pre, u_old, lam, g, ut, combo, max_sweeps, tol):
    """Block Gauss–Seidel over the contacts (arguments and return as :func:`_interface`)."""
    nk = len(side)
    out = np.empty(4)
    for sweep in range(max_sweeps):
        change, scale = 0.0, 0.0
        for k in range(nk):
            n, t = 2 * k, 2 * k + 1
            cn, ct = c[n], c[t]
            for i in range(nk):
                if i != k:
                    fn, fg = -side[i] * lam[i], g[i]
                    cn += R[n, 2 * i] * fn + R[n, 2 * i + 1] * fg
                    ct += R[t, 2 * i] * fn + R[t, 2 * i + 1] * fg
            if not _node_law(cn, ct, R[n, n], R[n, t], R[t, n], R[t, t], side[k], gap[k], mu[k], pre[k],
                             u_old[k], combo[k], out):
                return -1
            change = max(change, abs(out[0] - lam[k]), abs(out[1] - g[k]))
            scale = max(scale, abs(out[0]), abs(out[1]))
            lam[k], g[k], ut[k], combo[k] = out[0], out[1], out[2], int(out[3])
        if nk == 1 or change <= tol * max(scale, 1e-300):
            return sweep + 1
    return -1


@njit(**JIT_OPTIONS)
def _march(eta, vel, ut, lam, g, combo, w2, cd, kinv, fc, fs, psi, psiT, R, R0, side, gap, mu, pre,
           h, steps, max_sweeps, tol, rec_eta, rec_lam, rec_g, rec_u):
    """One period of ``steps`` Newmark steps from (eta, vel, ut) at τ = 0, in place (lam, g,
    combo: the law's warm start). Records every step (rows 0..steps) into the ``rec_*``
    arrays when rec_eta has steps + 1 rows. Returns (friction work over the period (J),
    Σ_k −½(g_0 + g_1)(u_1 − u_0) per step, largest sweep count; −1 on a failed step)."""
    n, m = len(eta), psi.shape[1]
    nk = len(side)
    record = rec_eta.shape[0] == steps + 1
    c = np.empty(m)
    f = np.empty(m)
    u_old = ut.copy()
    # the start: the law with the modes held, the acceleration from the equations of motion
    for i in range(m):
        c[i] = -np.dot(psiT[i], eta)
    if _interface(c, R0, side, gap, mu, pre, u_old, lam, g, ut, combo, max_sweeps, tol) < 0:
        return 0.0, -1
    for k in range(nk):
        f[2 * k], f[2 * k + 1] = -side[k] * lam[k], g[k]
    pf = psi @ f
    acc = fc - pf - cd * vel - w2 * eta
    if record:
        rec_eta[0], rec_lam[0], rec_g[0], rec_u[0] = eta, lam, g, ut
    work, worst = 0.0, 0
    pred = np.empty(n)
    for j in range(1, steps + 1):
        tau = 2.0 * np.pi * j / steps
        ct_, st_ = np.cos(tau), np.sin(tau)
        for k in range(n):
            pred[k] = kinv[k] * (fc[k] * ct_ + fs[k] * st_ + 4.0 / h**2 * (eta[k] + h * vel[k]) + acc[k]
                                 + cd[k] * (2.0 / h * eta[k] + vel[k]))
        for i in range(m):
            c[i] = -np.dot(psiT[i], pred)
        g0 = g.copy()
        for k in range(nk):
            u_old[k] = ut[k]
        sw = _interface(c, R, side, gap, mu, pre, u_old, lam, g, ut, combo, max_sweeps, tol)
        if sw < 0:
            return work, -1
        worst = max(worst, sw)
        for k in range(nk):
            f[2 * k], f[2 * k + 1] = -side[k] * lam[k], g[k]
            work -= 0.5 * (g0[k] + g[k]) * (ut[k] - u_old[k])
        pf = psi @ f
        for k in range(n):
            e1 = pred[k] - kinv[k] * pf[k]
            a1 = 4.0 / h**2 * (e1 - eta[k] - h * vel[k]) - acc[k]
            vel[k] = 2.0 / h * (e1 - eta[k]) - vel[k]
            eta[k], acc[k] = e1, a1
        if record:
            rec_eta[j], rec_lam[j], rec_g[j], rec_u[j] = eta, lam, g, ut
    return work, worst
