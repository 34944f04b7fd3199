"""Numba kernels of the shooting baseline: banded SPD algebra and the trapezoidal step.

Kernels take plain contiguous float64 arrays and know nothing of models. Symmetric band
matrices use LAPACK's *lower* band storage: ``ab[d, j] = A[j + d, j]`` for
``0 <= d <= p`` (``p`` the half-bandwidth), shape (p+1, n). Sets of tangent vectors are
stored one vector per *row* (shape (m, n)), so that each vector is contiguous.

The step is the trapezoidal rule (Newmark average acceleration, β = 1/4, γ = 1/2) for

    M q'' + K q = λ(q) a,    λ(q) = k_c max(0, −(gap + a·q)),

written in the acceleration form (only ``M`` is multiplied per step):

    w       = (4/h²) q_k + (4/h) v_k + acc_k
    S q_k+1 = M w + λ_k+1 a,                         S = (4/h²) M + K
    acc_k+1 = (4/h²)(q_k+1 − q_k) − (4/h) v_k − acc_k
    v_k+1   = v_k + (h/2)(acc_k + acc_k+1).

The contact force at the new step solves the scalar piecewise-linear equation exactly:
with y = S⁻¹ M w, z = S⁻¹ a and α = a·z > 0, the free gap is h_f = gap + a·y and
λ_k+1 = k_c max(0, −h_f) / (1 + k_c α) (the massless node's scalar LCP).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..kernels import JIT_OPTIONS

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
def _trapezoid(Sf, Mb, a, z, alpha, kc, gap, h, n_steps, q, v, acc, dq, dv, da, dh, Q, V, LAM):
    """Integrate ``n_steps`` trapezoidal steps of size ``h`` (s), in place.

    Parameters
    ----------
    Sf : (p+1, n) band Cholesky factor of S = (4/h²) M + K.
    Mb : (p+1, n) lower band storage of M.
    a, z : (n,) contact direction (free gap = gap + a·q) and S⁻¹ a; alpha = a·z.
    kc, gap : condensed contact stiffness (N/m), gap (m).
    q, v, acc : (n,) state at the start, overwritten with the state at the end.
    dq, dv, da : (m, n) tangent vectors (derivatives of q, v, acc with respect to m
        parameters), propagated in place; m may be 0.
    dh : (m,) derivative of h with respect to each parameter.
    Q, V : (n_steps+1, n) and LAM (n_steps+1,): the trajectory and contact force at
        every step, written when Q has rows (pass (0, n) arrays to skip).

    Returns the number of steps with the contact closed.
    """
    n = q.shape[0]
    m = dq.shape[0]
    store = Q.shape[0] > 0
    w = np.empty(n)
    y = np.empty(n)
    qn = np.empty(n)
    accn = np.empty(n)
    c1 = 4.0 / (h * h)
    c2 = 4.0 / h
    c3 = 8.0 / (h * h * h)
    beta = kc / (1.0 + kc * alpha)
    closed = 0
    if store:
        g = gap
        for i in range(n):
            Q[0, i] = q[i]
            V[0, i] = v[i]
            g += a[i] * q[i]
        LAM[0] = kc * max(0.0, -g)
    for k in range(n_steps):
        for i in range(n):
            w[i] = c1 * q[i] + c2 * v[i] + acc[i]
        _band_symv(Mb, w, y)
        _band_solve(Sf, y)
        hf = gap
        for i in range(n):
            hf += a[i] * y[i]
        active = hf < 0.0
        lam = -beta * hf if active else 0.0
        if active:
            closed += 1
        for i in range(n):
            qn[i] = y[i] + lam * z[i]
            accn[i] = c1 * (qn[i] - q[i]) - c2 * v[i] - acc[i]
        # tangents: (S + k_c s a aᵀ) dq' = M w', Sherman–Morrison with z
        for col in range(m):
            e = dh[col]
            for i in range(n):
                w[i] = c1 * dq[col, i] + c2 * dv[col, i] + da[col, i] + e * (c3 * (qn[i] - q[i]) - c1 * v[i])
            _band_symv(Mb, w, y)
            _band_solve(Sf, y)
            if active:
                ay = 0.0
                for i in range(n):
                    ay += a[i] * y[i]
                ay *= beta
                for i in range(n):
                    y[i] -= ay * z[i]
            for i in range(n):
                dan = c1 * (y[i] - dq[col, i]) - c2 * dv[col, i] - da[col, i] \
                    + e * (c1 * v[i] - c3 * (qn[i] - q[i]))
                dv[col, i] += 0.5 * h * (da[col, i] + dan) + 0.5 * e * (acc[i] + accn[i])
                da[col, i] = dan
                dq[col, i] = y[i]
        for i in range(n):
            v[i] += 0.5 * h * (acc[i] + accn[i])
            q[i] = qn[i]
            acc[i] = accn[i]
        if store:
            for i in range(n):
                Q[k + 1, i] = q[i]
                V[k + 1, i] = v[i]
            LAM[k + 1] = lam
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
