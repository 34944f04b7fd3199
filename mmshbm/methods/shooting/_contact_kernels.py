"""Numba kernels of the shooting baseline with several contacts (or contacts on DOFs
with mass): the contact LCP followed along a step, the step's force sum and its
derivatives, the time step and its sensitivities (:mod:`mmshbm.methods.shooting.conservative`).

The contact forces λ (m,) at fixed free gaps h = gap + A q solve the LCP
g = h + G λ >= 0, λ >= 0, gᵀλ = 0; they are followed exactly along each step by
principal pivoting with the kernels of :mod:`mmshbm.contact.lcp`.

Band storage, the band kernels and the tangent layout are those of
:mod:`mmshbm.methods.shooting._kernels`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...contact.lcp import _inverse_sub, _lcp_jacobian, _lcp_path, _lcp_point
from ...harmonic.kernels import JIT_OPTIONS
from ._kernels import (
    _band_solve,
    _band_symv,
    _block_band_solve,
    _block_band_terms,
    _block_inertia,
    _block_update,
)

__all__: list[str] = []  # kernels only

_MAX_NEWTON = 60
# Tangent columns per block (as in _shooting_kernels).
_BLOCK = 16


@njit(**JIT_OPTIONS)
def _force_sum_multi(G, h0, h1, act0, lam0, J0, avf, act1, lam1, F, D0, D1, idx, Ginv, work):
    """The step's force sum F (m,) and its derivatives D0 = ∂F/∂h0, D1 = ∂F/∂h1 (m, m):
    2 ∫₀¹ λ(h0 + s(h1 − h0)) ds (avf) or λ(h0) + λ(h1) (trapezoidal, λ(h0) = lam0 and
    ∂λ/∂h(h0) = J0 given). act1, lam1: the active set and λ at h1. False on failure."""
    m = h0.shape[0]
    for i in range(m):
        act1[i] = act0[i]
    # one call site of the path (numba inlines callees: fewer copies compile faster)
    if _lcp_path(G, h0, h1, act1, avf, lam1, F, D0, D1, idx, Ginv, work) < 0:
        return False
    if avf:
        return True
    if not _lcp_jacobian(G, act1, D1, idx, Ginv, work):
        return False
    for i in range(m):
        F[i] = lam0[i] + lam1[i]
        for j in range(m):
            D0[i, j] = J0[i, j]
    return True


@njit(**JIT_OPTIONS)
def _step_forces(G, AZ, h0, hy, act0, lam0, J0, F_prev, avf, h1, act1, lam1, F, D0, D1, idx, Ginv, work,
                 r, dlt, Mat, h_base, allidx, Inv):
    """Solve h1 = hy + (A Z) F(h0, h1) for the free gaps at the step's end (m,), in place.

    F is the step's force sum (:func:`_force_sum_multi`). Newton on this piecewise-smooth
    equation, which is monotone (I − AZ D1 is invertible: AZ and −D1 are positive
    semidefinite), from hy + AZ F_prev; a full step that does not reduce the residual is
    halved (up to 30 times). Converged when the residual or the update is at round-off
    (exact: on each piece of the path F is smooth, and for the trapezoidal rule linear).
    Returns the Newton iterations, or −1 without convergence.
    """
    m = h0.shape[0]
    eps = 2.220446049250313e-16
    for i in range(m):
        acc = hy[i]
        for j in range(m):
            acc += AZ[i, j] * F_prev[j]
        h1[i] = acc
    rn_prev = np.inf
    backs = 0
    rn = 0.0
    scale = 0.0
    final = False
    for it in range(_MAX_NEWTON + 1):
        if not _force_sum_multi(G, h0, h1, act0, lam0, J0, avf, act1, lam1, F, D0, D1, idx, Ginv, work):
            return -1
        if final:  # the forces at the h1 of an update at round-off
            return it
        scale = 0.0
        rn = 0.0
        for i in range(m):
            acc = 0.0
            for j in range(m):
                acc += AZ[i, j] * F[j]
            r[i] = h1[i] - hy[i] - acc
            scale = max(scale, abs(hy[i]), abs(h1[i]), abs(acc))
            rn = max(rn, abs(r[i]))
        if rn <= 4.0 * eps * scale:
            return it + 1
        if it == _MAX_NEWTON:
            break
        if rn >= rn_prev and backs < 30 and it > 0:
            backs += 1
            for i in range(m):
                dlt[i] *= 0.5
                h1[i] = h_base[i] - dlt[i]
            continue
        backs = 0
        rn_prev = rn
        for i in range(m):
            h_base[i] = h1[i]
            for j in range(m):
                acc = 0.0
                for k in range(m):
                    acc += AZ[i, k] * D1[k, j]
                Mat[i, j] = (1.0 if i == j else 0.0) - acc
        if not _inverse_sub(Mat, allidx, m, Inv, work):
            return -1
        dn = 0.0
        for i in range(m):
            acc = 0.0
            for j in range(m):
                acc += Inv[i, j] * r[j]
            dlt[i] = acc
            h1[i] = h_base[i] - acc
            dn = max(dn, abs(acc))
        final = dn <= 4.0 * eps * scale
    if rn <= 1e3 * eps * scale:
        return _MAX_NEWTON  # stalled at a round-off floor (F is that of the last h1)
    return -1


@njit(**JIT_OPTIONS)
def _contact_product(C, X, nb, out):
    """out[:, :nb] = C X[:, :nb] for a small (m, m) contact-space matrix C."""
    m = C.shape[0]
    for k in range(m):
        for j in range(nb):
            acc = 0.0
            for l2 in range(m):
                acc += C[k, l2] * X[l2, j]
            out[k, j] = acc


@njit(**JIT_OPTIONS)
def _tangent_step_multi(Sf, Mb, Kb, A, Z, F0, Cm, h, q, v, qn, dq, dv, dh, Wb, Yb, AD, T):
    """One step of the tangent columns dq, dv (n, n_par) with several contacts, in place:

        (S − Aᵀ F1 A) dq1 = M(c1 dq0 + c2 dv0 + e(c3 (q1 − q0) − c1 v0)) − K dq0 + Aᵀ F0 A dq0
        dv1 = (2/h)(dq1 − dq0) − dv0 − e (2/h²)(q1 − q0)

    solved as Y = S⁻¹(right-hand side), dq1 = Y + Z Cm (A Y) (Woodbury, Z = S⁻¹Aᵀ,
    Cm = (I − F1 A Z)⁻¹ F1). A (m, n), Z (n, m), F0, Cm (m, m); Wb, Yb (n, _BLOCK),
    AD, T (m, _BLOCK) work arrays.
    """
    n, npar = dq.shape
    m = A.shape[0]
    c1 = 4.0 / (h * h)
    c2 = 4.0 / h
    c3 = 8.0 / (h * h * h)
    c5 = 2.0 / h
    c6 = 2.0 / (h * h)
    for c0 in range(0, npar, _BLOCK):
        nb = min(_BLOCK, npar - c0)
        _block_inertia(c1, c2, c3, q, qn, v, dq, dv, dh, c0, nb, Wb)
        # AD = A dq0, T = F0 AD
        for k in range(m):
            for j in range(nb):
                AD[k, j] = 0.0
            for i in range(n):
                aki = A[k, i]
                if aki != 0.0:
                    for j in range(nb):
                        AD[k, j] += aki * dq[i, c0 + j]
        _contact_product(F0, AD, nb, T)
        # Y = M W − K dq + Aᵀ T
        for i in range(n):
            m0 = Mb[0, i]
            k0 = Kb[0, i]
            for j in range(nb):
                acc = m0 * Wb[i, j] - k0 * dq[i, c0 + j]
                for k in range(m):
                    acc += A[k, i] * T[k, j]
                Yb[i, j] = acc
        _block_band_terms(Mb, Kb, Wb, dq, c0, nb, Yb)
        _block_band_solve(Sf, Yb, nb)
        # dq1 = Y + Z Cm (A Y)
        for k in range(m):
            for j in range(nb):
                acc = 0.0
                for i in range(n):
                    acc += A[k, i] * Yb[i, j]
                AD[k, j] = acc
        _contact_product(Cm, AD, nb, T)
        for i in range(n):
            for k in range(m):
                zik = Z[i, k]
                if zik != 0.0:
                    for j in range(nb):
                        Yb[i, j] += zik * T[k, j]
        _block_update(c5, c6, q, qn, Yb, dq, dv, dh, c0, nb)


@njit(**JIT_OPTIONS)
def _integrate_multi(Sf, Pb, Mb, Kb, A, Z, AZ, G, gap, h, n_steps, avf, q, v, dq, dv, dh, Q, V, LAM):
    """Integrate ``n_steps`` steps of size ``h`` (s) with several contacts, in place.

    One step (F the force sum (m,) of the scheme, h_k = gap + A q_k the free gaps):

        S q1 = P q0 + (4/h) M v0 + Aᵀ F(h0, h1),    v1 = (2/h)(q1 − q0) − v0

    so h1 = hy + (A Z) F(h0, h1) with hy the free gaps of the contact-free predictor y and
    Z = S⁻¹ Aᵀ; :func:`_step_forces` solves it, q1 = y + Z F.

    Parameters as :func:`_integrate`, with A (m, n) the free-gap gradients, Z (n, m),
    AZ = A Z (m, m), G (m, m) the Delassus matrix, gap (m,), and LAM (n_steps+1, m) the
    contact forces at the steps (stored when Q has rows).

    Returns the number of steps that end with a contact closed, or −1 − k if the contact
    problem of step k could not be solved.
    """
    n = q.shape[0]
    m = A.shape[0]
    npar = dq.shape[1]
    store = Q.shape[0] > 0
    Wb = np.empty((n, _BLOCK))
    Yb = np.empty((n, _BLOCK))
    AD = np.empty((m, _BLOCK))
    T = np.empty((m, _BLOCK))
    w = np.empty(n)
    y = np.empty(n)
    t = np.empty(n)
    qn = np.empty(n)
    h0 = np.empty(m)
    hy = np.empty(m)
    h1 = np.empty(m)
    act0 = np.zeros(m, dtype=np.bool_)
    act1 = np.zeros(m, dtype=np.bool_)
    h_base = np.empty(m)
    lam0 = np.zeros(m)
    lam1 = np.zeros(m)
    F = np.zeros(m)
    F_prev = np.zeros(m)
    D0 = np.zeros((m, m))
    D1 = np.zeros((m, m))
    J0 = np.zeros((m, m))
    Cm = np.zeros((m, m))
    Mat = np.zeros((m, m))
    idx = np.empty(m, dtype=np.int64)
    Ginv = np.empty((m, m))
    work = np.empty((m, m))
    r = np.empty(m)
    dlt = np.zeros(m)
    allidx = np.arange(m)
    Inv = np.empty((m, m))
    c2 = 4.0 / h
    closed = 0
    for k in range(m):
        acc = gap[k]
        for i in range(n):
            acc += A[k, i] * q[i]
        h0[k] = acc
    if _lcp_point(G, h0, act0, lam0, idx, Ginv, work) < 0:
        return -1
    if store:
        for i in range(n):
            Q[0, i] = q[i]
            V[0, i] = v[i]
        for k in range(m):
            LAM[0, k] = lam0[k]
    for step in range(n_steps):
        if not avf and not _lcp_jacobian(G, act0, J0, idx, Ginv, work):  # ∂λ/∂h at h0
            return -1 - step
        _band_symv(Pb, q, y)
        for i in range(n):
            w[i] = c2 * v[i]
        _band_symv(Mb, w, t)
        for i in range(n):
            y[i] += t[i]
        _band_solve(Sf, y)
        for k in range(m):
            acc = gap[k]
            for i in range(n):
                acc += A[k, i] * y[i]
            hy[k] = acc
        if _step_forces(G, AZ, h0, hy, act0, lam0, J0, F_prev, avf, h1, act1, lam1, F, D0, D1, idx, Ginv,
                        work, r, dlt, Mat, h_base, allidx, Inv) < 0:
            return -1 - step
        any_closed = False
        for k in range(m):
            if act1[k]:
                any_closed = True
        if any_closed:
            closed += 1
        for i in range(n):
            acc = y[i]
            for k in range(m):
                acc += Z[i, k] * F[k]
            qn[i] = acc
        if npar:
            # Cm = (I − D1 AZ)⁻¹ D1
            for i in range(m):
                for j in range(m):
                    acc = 0.0
                    for k in range(m):
                        acc += D1[i, k] * AZ[k, j]
                    Mat[i, j] = (1.0 if i == j else 0.0) - acc
            if not _inverse_sub(Mat, allidx, m, Inv, work):
                return -1 - step
            for i in range(m):
                for j in range(m):
                    acc = 0.0
                    for k in range(m):
                        acc += Inv[i, k] * D1[k, j]
                    Cm[i, j] = acc
            _tangent_step_multi(Sf, Mb, Kb, A, Z, D0, Cm, h, q, v, qn, dq, dv, dh, Wb, Yb, AD, T)
        for i in range(n):
            v[i] = (2.0 / h) * (qn[i] - q[i]) - v[i]
            q[i] = qn[i]
        for k in range(m):
            h0[k] = h1[k]
            act0[k] = act1[k]
            lam0[k] = lam1[k]
            F_prev[k] = F[k]
        if store:
            for i in range(n):
                Q[step + 1, i] = q[i]
                V[step + 1, i] = v[i]
            for k in range(m):
                LAM[step + 1, k] = lam1[k]
    return closed
