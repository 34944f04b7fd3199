"""Numba kernels of the shooting baseline: banded SPD algebra and the time step.

Kernels take plain contiguous float64 arrays and know nothing of models. Symmetric band
matrices use LAPACK's *lower* band storage: ``ab[d, j] = A[j + d, j]`` for
``0 <= d <= p`` (``p`` the half-bandwidth), shape (p+1, n). Sets of tangent vectors are
stored one vector per *row* (shape (m, n)), so that each vector is contiguous.

The step (:func:`_integrate`) is the trapezoidal rule for

    M q'' + K q = λ(q) a,    λ(q) = k_c max(0, −h(q)),    h(q) = gap + a·q,

with the contact force either at both ends of the step (plain trapezoidal rule) or
averaged exactly along the step (averaged vector field, energy conserving). Either way the
force at the step's end is implicit; it depends on the state only through the scalar free
gap, so with y the contact-free predictor, z = S⁻¹ a and α = a·z the new free gap is the
root of the scalar piecewise-smooth equation h1 = h_y + α F(h0, h1), solved in closed form
(:func:`_contact_root`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...harmonic.kernels import JIT_OPTIONS

__all__ = ["band_cholesky", "band_solve", "band_symv"]


@njit(**JIT_OPTIONS)
def _band_cholesky(ab):
    """In place: lower band storage of A -> that of its Cholesky factor L. False if A is
    not positive definite."""
    p = ab.shape[0] - 1
    n = ab.shape[1]
    for j in range(n):
        s = ab[0, j]
        for k in range(max(0, j - p), j):
            lk = ab[j - k, k]
            s -= lk * lk
        if not s > 0.0:
            return False
        d = math.sqrt(s)
        ab[0, j] = d
        for i in range(j + 1, min(n, j + p + 1)):
            s = ab[i - j, j]
            for k in range(max(0, i - p), j):
                s -= ab[i - k, k] * ab[j - k, k]
            ab[i - j, j] = s / d
    return True


@njit(**JIT_OPTIONS)
def _band_solve(L, b):
    """In place: b <- A⁻¹ b with L the band Cholesky factor of A; b shape (n,)."""
    p = L.shape[0] - 1
    n = L.shape[1]
    for i in range(n):
        s = b[i]
        for k in range(max(0, i - p), i):
            s -= L[i - k, k] * b[k]
        b[i] = s / L[0, i]
    for i in range(n - 1, -1, -1):
        s = b[i]
        for k in range(i + 1, min(n, i + p + 1)):
            s -= L[k - i, i] * b[k]
        b[i] = s / L[0, i]


@njit(**JIT_OPTIONS)
def _band_solve_rows(L, B):
    """In place: every row b of B (m, n) <- A⁻¹ b."""
    for r in range(B.shape[0]):
        _band_solve(L, B[r])


@njit(**JIT_OPTIONS)
def _band_symv(ab, x, out):
    """out <- A x for symmetric A in lower band storage; x, out shape (n,)."""
    p = ab.shape[0] - 1
    n = ab.shape[1]
    for i in range(n):
        out[i] = ab[0, i] * x[i]
    for d in range(1, p + 1):
        for j in range(n - d):
            c = ab[d, j]
            out[j + d] += c * x[j]
            out[j] += c * x[j + d]


@njit(**JIT_OPTIONS)
def _force_sum(h0, h1, kc, avf):
    """The step's contact force sum F (N) and its derivatives (F, ∂F/∂h0, ∂F/∂h1).

    Trapezoidal rule (avf False): F = λ(h0) + λ(h1), λ(h) = k_c max(0, −h).
    Averaged vector field (avf True): F = 2 k_c ∫₀¹ max(0, −(h0 + s(h1 − h0))) ds, the exact
    mean of the force along the straight path between the two states, a C¹ function.
    """
    if not avf:
        f0 = kc if h0 < 0.0 else 0.0
        f1 = kc if h1 < 0.0 else 0.0
        return -f0 * h0 - f1 * h1, -f0, -f1
    if h0 >= 0.0 and h1 >= 0.0:
        return 0.0, 0.0, 0.0
    if h0 <= 0.0 and h1 <= 0.0:
        return -kc * (h0 + h1), -kc, -kc
    if h1 < 0.0:  # h0 > 0 > h1
        d = h0 - h1
        return kc * h1 * h1 / d, -kc * h1 * h1 / (d * d), kc * h1 * (2.0 * h0 - h1) / (d * d)
    d = h1 - h0  # h0 < 0 < h1
    return kc * h0 * h0 / d, kc * h0 * (2.0 * h1 - h0) / (d * d), -kc * h0 * h0 / (d * d)


@njit(**JIT_OPTIONS)
def _contact_root(h0, hy, ak, avf):
    """The free gap h1 at the step's end: the root of h1 = hy + α F(h0, h1) (ak = α k_c)."""
    if not avf:
        ht = hy + (ak * (-h0) if h0 < 0.0 else 0.0)
        return ht if ht >= 0.0 else ht / (1.0 + ak)
    if h0 >= 0.0:
        if hy >= 0.0:
            return hy
        A = 1.0 + ak
        b = h0 + hy
        disc = math.sqrt(b * b - 4.0 * A * h0 * hy)
        if b > 0.0:
            return 2.0 * h0 * hy / (b + disc)
        return (b - disc) / (2.0 * A)
    if hy <= ak * h0:
        return (hy - ak * h0) / (1.0 + ak)
    b = hy + h0
    C = hy * h0 - ak * h0 * h0
    disc = math.sqrt((hy - h0) * (hy - h0) + 4.0 * ak * h0 * h0)
    if b >= 0.0:
        return 0.5 * (b + disc)
    return C / (0.5 * (b - disc))


# Tangent columns are processed in blocks of this many: the band recurrences then run
# over rows with an independent inner loop over the block's columns (SIMD, no latency
# chain), and the block's work arrays stay in cache.
_BLOCK = 16


@njit(**JIT_OPTIONS)
def _block_inertia(c1, c2, c3, q, qn, v, dq, dv, dh, c0, nb, Wb):
    """Wb[:, :nb] = c1 dq0 + c2 dv0 + e (c3 (q1 − q0) − c1 v0) for the columns c0 … c0+nb−1
    (e = dh[col], the column's step-size derivative)."""
    for i in range(qn.shape[0]):
        base = c3 * (qn[i] - q[i]) - c1 * v[i]
        for j in range(nb):
            Wb[i, j] = c1 * dq[i, c0 + j] + c2 * dv[i, c0 + j] + dh[c0 + j] * base


@njit(**JIT_OPTIONS)
def _block_band_terms(Mb, Kb, Wb, dq, c0, nb, Yb):
    """Yb[:, :nb] += (M W − K dq) from the off-diagonal bands (the diagonal is the caller's,
    fused with its contact terms)."""
    n = Yb.shape[0]
    for d in range(1, Mb.shape[0]):
        for r in range(n - d):
            md = Mb[d, r]
            kd = Kb[d, r]
            for j in range(nb):
                Yb[r + d, j] += md * Wb[r, j] - kd * dq[r, c0 + j]
                Yb[r, j] += md * Wb[r + d, j] - kd * dq[r + d, c0 + j]


@njit(**JIT_OPTIONS)
def _block_band_solve(Sf, Yb, nb):
    """In place: Yb[:, :nb] <- S⁻¹ Yb by the band Cholesky factor (forward, then backward)."""
    n = Yb.shape[0]
    p = Sf.shape[0] - 1
    for i in range(n):
        for k in range(max(0, i - p), i):
            lik = Sf[i - k, k]
            for j in range(nb):
                Yb[i, j] -= lik * Yb[k, j]
        inv = 1.0 / Sf[0, i]
        for j in range(nb):
            Yb[i, j] *= inv
    for i in range(n - 1, -1, -1):
        for k in range(i + 1, min(n, i + p + 1)):
            lki = Sf[k - i, i]
            for j in range(nb):
                Yb[i, j] -= lki * Yb[k, j]
        inv = 1.0 / Sf[0, i]
        for j in range(nb):
            Yb[i, j] *= inv


@njit(**JIT_OPTIONS)
def _block_update(c5, c6, q, qn, Yb, dq, dv, dh, c0, nb):
    """The block's new columns: dq1 = Y, dv1 = c5 (dq1 − dq0) − dv0 − e c6 (q1 − q0)."""
    for i in range(qn.shape[0]):
        base = c6 * (qn[i] - q[i])
        for j in range(nb):
            col = c0 + j
            dv[i, col] = c5 * (Yb[i, j] - dq[i, col]) - dv[i, col] - dh[col] * base
            dq[i, col] = Yb[i, j]


@njit(**JIT_OPTIONS)
def _tangent_step(Sf, Mb, Kb, a, z, alpha, F0, F1, h, q, v, qn, dq, dv, dh, Wb, Yb, ad):
    """One step of the tangent columns dq, dv (n, m), in place, given the step's states
    q (start), qn (end), v (start velocity) and the force-sum derivatives F0, F1:

        (S − F1 a aᵀ) dq1 = M(c1 dq0 + c2 dv0 + e(c3 (q1 − q0) − c1 v0)) − K dq0 + F0 (a·dq0) a
        dv1 = (2/h)(dq1 − dq0) − dv0 − e (2/h²)(q1 − q0)

    with e = dh[col] the column's step-size derivative, c1 = 4/h², c2 = 4/h, c3 = 8/h³.
    Wb, Yb (n, _BLOCK) and ad (_BLOCK,) are work arrays.
    """
    n, m = dq.shape
    c1 = 4.0 / (h * h)
    c2 = 4.0 / h
    c3 = 8.0 / (h * h * h)
    c5 = 2.0 / h
    c6 = 2.0 / (h * h)
    sm = F1 / (1.0 - F1 * alpha)
    for c0 in range(0, m, _BLOCK):
        nb = min(_BLOCK, m - c0)
        _block_inertia(c1, c2, c3, q, qn, v, dq, dv, dh, c0, nb, Wb)
        for j in range(nb):
            ad[j] = 0.0
        for i in range(n):
            ai = a[i]
            if ai != 0.0:
                for j in range(nb):
                    ad[j] += ai * dq[i, c0 + j]
        # Y = M W − K dq + F0 (a·dq) a
        for i in range(n):
            m0 = Mb[0, i]
            k0 = Kb[0, i]
            fa = F0 * a[i]
            for j in range(nb):
                Yb[i, j] = m0 * Wb[i, j] - k0 * dq[i, c0 + j] + fa * ad[j]
        _block_band_terms(Mb, Kb, Wb, dq, c0, nb, Yb)
        _block_band_solve(Sf, Yb, nb)
        # Sherman–Morrison along z for the contact's own derivative
        if F1 != 0.0:
            for j in range(nb):
                ad[j] = 0.0
            for i in range(n):
                ai = a[i]
                if ai != 0.0:
                    for j in range(nb):
                        ad[j] += ai * Yb[i, j]
            for j in range(nb):
                ad[j] *= sm
            for i in range(n):
                zi = z[i]
                for j in range(nb):
                    Yb[i, j] += ad[j] * zi
        _block_update(c5, c6, q, qn, Yb, dq, dv, dh, c0, nb)



@njit(**JIT_OPTIONS)
def _start_gap(a, q, v, gap, kc, Q, V, LAM):
    """The contact's gap gap + a·q at the start of a period; with rows in Q, the start's
    state and contact force k_c max(0, −gap) written to row 0 of Q, V and LAM."""
    h0 = gap
    for i in range(q.shape[0]):
        h0 += a[i] * q[i]
    if Q.shape[0] > 0:
        for i in range(q.shape[0]):
            Q[0, i] = q[i]
            V[0, i] = v[i]
        LAM[0] = kc * max(0.0, -h0)
    return h0


@njit(**JIT_OPTIONS)
def _integrate(Sf, Pb, Mb, Kb, a, z, alpha, kc, gap, h, n_steps, avf, q, v, dq, dv, dh, Q, V, LAM):
    """Integrate ``n_steps`` steps of size ``h`` (s), in place.

    One step (F the contact force sum of :func:`_force_sum`, h_k = gap + a·q_k):

        S q1 = P q0 + (4/h) M v0 + F(h0, h1) a,   S = (4/h²) M + K,  P = (4/h²) M − K
        v1   = (2/h)(q1 − q0) − v0

    Parameters
    ----------
    Sf : (p+1, n) band Cholesky factor of S.
    Pb, Mb, Kb : (p+1, n) lower band storage of P, M and K.
    a, z : (n,) contact direction (free gap = gap + a·q) and S⁻¹ a; alpha = a·z.
    kc, gap : condensed contact stiffness (N/m), gap (m).
    avf : averaged-vector-field force (True) or trapezoidal rule (False).
    q, v : (n,) state at the start, overwritten with the state at the end.
    dq, dv : (n, m) tangent vectors, one column per parameter (derivatives of q, v with
        respect to m parameters), propagated in place; m may be 0.
    dh : (m,) derivative of the step size h with respect to each parameter.
    Q, V : (n_steps+1, n) and LAM (n_steps+1,): the states and the contact force
        k_c max(0, −h_k) at every step, written when Q has rows (else pass (0, n) arrays).

    Returns the number of steps that end with the contact closed.
    """
    n = q.shape[0]
    m = dq.shape[1]
    store = Q.shape[0] > 0
    Wb = np.empty((n, _BLOCK))
    Yb = np.empty((n, _BLOCK))
    ad = np.empty(_BLOCK)
    w = np.empty(n)
    y = np.empty(n)
    t = np.empty(n)
    qn = np.empty(n)
    c2 = 4.0 / h
    ak = alpha * kc
    closed = 0
    h0 = _start_gap(a, q, v, gap, kc, Q, V, LAM)
    for k in range(n_steps):
        _band_symv(Pb, q, y)
        for i in range(n):
            w[i] = c2 * v[i]
        _band_symv(Mb, w, t)
        for i in range(n):
            y[i] += t[i]
        _band_solve(Sf, y)
        hy = gap
        for i in range(n):
            hy += a[i] * y[i]
        h1 = _contact_root(h0, hy, ak, avf)
        F, F0, F1 = _force_sum(h0, h1, kc, avf)
        if h1 < 0.0:
            closed += 1
        for i in range(n):
            qn[i] = y[i] + F * z[i]
        if m:
            _tangent_step(Sf, Mb, Kb, a, z, alpha, F0, F1, h, q, v, qn, dq, dv, dh, Wb, Yb, ad)
        for i in range(n):
            v[i] = (2.0 / h) * (qn[i] - q[i]) - v[i]
            q[i] = qn[i]
        h0 = h1
        if store:
            for i in range(n):
                Q[k + 1, i] = q[i]
                V[k + 1, i] = v[i]
            LAM[k + 1] = kc * max(0.0, -h1)
    return closed


# ---------------------------------------------------------------------- public wrappers
def band_cholesky(ab: np.ndarray) -> np.ndarray:
    """Cholesky factor (lower band storage, shape (p+1, n)) of an SPD band matrix given in
    lower band storage ``ab[d, j] = A[j+d, j]``. Raises ValueError if A is not positive
    definite."""
    L = np.array(ab, dtype=np.float64, order="C", copy=True)
    if L.ndim != 2:
        raise ValueError(f"ab must be 2-D (p+1, n), got shape {L.shape}")
    if not _band_cholesky(L):
        raise ValueError("band matrix is not positive definite")
    return L


def band_solve(L: np.ndarray, b: np.ndarray) -> np.ndarray:
    """A⁻¹ b for ``b`` of shape (n,) or (m, n) (one right-hand side per row), with ``L``
    from :func:`band_cholesky`."""
    x = np.array(b, dtype=np.float64, order="C", copy=True)
    if x.shape[-1] != L.shape[1] or x.ndim > 2:
        raise ValueError(f"b must have shape (n,) or (m, n) with n = {L.shape[1]}, got {x.shape}")
    if x.ndim == 1:
        _band_solve(L, x)
    else:
        _band_solve_rows(L, x)
    return x


def band_symv(ab: np.ndarray, x: np.ndarray) -> np.ndarray:
    """A x for symmetric A in lower band storage; x shape (n,)."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    if x.shape != (ab.shape[1],):
        raise ValueError(f"x must have shape ({ab.shape[1]},), got {x.shape}")
    out = np.empty_like(x)
    _band_symv(np.ascontiguousarray(ab, dtype=np.float64), x, out)
    return out
