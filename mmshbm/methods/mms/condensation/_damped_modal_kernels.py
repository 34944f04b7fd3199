"""Numba kernel of the damped modal condensation
(:mod:`mmshbm.methods.mms.condensation.damped_condense`, modal back end):
D_k, P̂_1 and their derivatives in Ω and ξ, without the recovery.

The kernel and its helpers live in this one file (numba's on-disk cache does not see
edits to a callee elsewhere); it shares :data:`~mmshbm.harmonic.kernels.JIT_OPTIONS`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ....harmonic.kernels import JIT_OPTIONS


@njit(**JIT_OPTIONS)
def _invert(A, out, work):
    """out <- A⁻¹ for a small complex (n, n) A by Gauss–Jordan with partial pivoting; False
    when a pivot is exactly zero or not finite (A singular)."""
    n = A.shape[0]
    for i in range(n):
        for j in range(n):
            work[i, j] = A[i, j]
            out[i, j] = 1.0 if i == j else 0.0
    for c in range(n):
        p = c
        best = abs(work[c, c])
        for r in range(c + 1, n):
            v = abs(work[r, c])
            if v > best:
                best = v
                p = r
        if not (best > 0.0) or not np.isfinite(best):
            return False
        if p != c:
            for j in range(n):
                work[c, j], work[p, j] = work[p, j], work[c, j]
                out[c, j], out[p, j] = out[p, j], out[c, j]
        piv = 1.0 / work[c, c]
        for j in range(n):
            work[c, j] *= piv
            out[c, j] *= piv
        for r in range(n):
            if r != c:
                f = work[r, c]
                if f != 0.0:
                    for j in range(n):
                        work[r, j] -= f * work[c, j]
                        out[r, j] -= f * out[c, j]
    return True


@njit(**JIT_OPTIONS)
def _far_sum(Pc, dd, h, Kinv, out):
    """out (n_c, n_c) <- Kinv + Σ_m φ_m dd[h, m] φ_mᵀ (Kinv None-like when it has no rows)."""
    n_c, n_m = Pc.shape
    for i in range(n_c):
        for j in range(n_c):
            acc = 0.0j
            for m in range(n_m):
                acc += Pc[i, m] * dd[h, m] * Pc[j, m]
            out[i, j] = acc + (Kinv[i, j] if Kinv.shape[0] else 0.0)


@njit(**JIT_OPTIONS)
def _damped_modal(omega, xi, H, w2, gamma, Pc, Kinv, D0, beta, derivative, xi_derivative, D, dDw, dDx, P, dPw,
                  dPx):
    """The damped modal condensation at (Ω, ξ), harmonics 0..H, in place (the formulas of
    ``DampedCondensation._evaluate_modal``): per harmonic k the mode j nearest kΩ taken out
    by a rank-one update, D_k = B − (Bφ)(Bφ)ᵀ/g, B = A⁻¹, A = K_cc⁻¹ + Σ_{m≠j} φ_m d_m φ_mᵀ,
    g = 1/d_j + φᵀBφ; P̂_1 = D_1 h + (Bφ) β_jᵀ/g with h = Σ_{m≠j} φ_m d_m β_mᵀ.

    w2, gamma : (n_m,) ω_m², φ_mᵀCφ_m;  Pc : (n_c, n_m) φ_c,m;  Kinv : (n_c, n_c) K_cc⁻¹;
    D0 : (n_c, n_c);  beta : (n_m, n_l) modal loads
    D, dDw, dDx : (H+1, n_c, n_c) complex outputs (dDw if ``derivative``, dDx if
    ``xi_derivative``);  P, dPw, dPx : (n_c, n_l) complex outputs.
    Returns 0, 1 when some A is singular, 2 when some g is 0 (outputs incomplete).
    """
    n_c, n_m = Pc.shape
    n_b = beta.shape[1]
    d = np.empty((H, n_m), dtype=np.complex128)
    jsel = np.empty(H, dtype=np.int64)
    inv_dj = np.empty(H, dtype=np.complex128)
    g = np.empty(H, dtype=np.complex128)
    Bk = np.empty((H, n_c, n_c), dtype=np.complex128)
    Bphi = np.empty((H, n_c), dtype=np.complex128)
    A = np.empty((n_c, n_c), dtype=np.complex128)
    work = np.empty((n_c, n_c), dtype=np.complex128)
    for i in range(n_c):
        for j in range(n_c):
            D[0, i, j] = D0[i, j]
    for h in range(H):
        w = (h + 1.0) * omega
        best = np.inf
        jh = 0
        for m in range(n_m):
            inv = complex(w2[m] - w * w, w * (gamma[m] - xi))
            d[h, m] = inv
            v = abs(inv) / w2[m]
            if v < best:
                best = v
                jh = m
        jsel[h] = jh
        inv_dj[h] = d[h, jh]
        for m in range(n_m):
            d[h, m] = 0.0 if m == jh else 1.0 / d[h, m]
        _far_sum(Pc, d, h, Kinv, A)
        if not _invert(A, Bk[h], work):
            return 1
        gh = inv_dj[h]
        for i in range(n_c):
            acc = 0.0j
            for j in range(n_c):
                acc += Bk[h, i, j] * Pc[j, jh]
            Bphi[h, i] = acc
            gh += Pc[i, jh] * acc
        if gh == 0.0:
            return 2
        g[h] = gh
        for i in range(n_c):
            for j in range(n_c):
                D[h + 1, i, j] = Bk[h, i, j] - Bphi[h, i] * Bphi[h, j] / gh
    j0 = jsel[0]
    hfar = np.zeros((n_c, n_b), dtype=np.complex128)
    for i in range(n_c):
        for b in range(n_b):
            acc = 0.0j
            for m in range(n_m):
                acc += Pc[i, m] * (d[0, m] * beta[m, b])
            hfar[i, b] = acc
    for i in range(n_c):
        for b in range(n_b):
            acc = 0.0j
            for j in range(n_c):
                acc += D[1, i, j] * hfar[j, b]
            P[i, b] = acc + Bphi[0, i] * beta[j0, b] / g[0]
    for which in range(2):
        if which == 0 and not derivative:
            continue
        if which == 1 and not xi_derivative:
            continue
        out = dDw if which == 0 else dDx
        dP = dPw if which == 0 else dPx
        dd = np.empty((H, n_m), dtype=np.complex128)
        dinv_j = np.empty(H, dtype=np.complex128)
        for h in range(H):
            k = h + 1.0
            w = k * omega
            for m in range(n_m):
                # ∂(1/d)/∂Ω = k(−2ω + iγ), ∂(1/d)/∂ξ = −iω; the far d's: ∂d = −d² ∂(1/d)
                dinv = complex(-2.0 * k * w, k * (gamma[m] - xi)) if which == 0 else complex(0.0, -w)
                if m == jsel[h]:
                    dinv_j[h] = dinv
                dd[h, m] = -d[h, m] ** 2 * dinv
        dB = np.empty((n_c, n_c), dtype=np.complex128)
        dA = np.empty((n_c, n_c), dtype=np.complex128)
        tmp = np.empty((n_c, n_c), dtype=np.complex128)
        dBphi = np.empty((H, n_c), dtype=np.complex128)
        dg = np.empty(H, dtype=np.complex128)
        for i in range(n_c):
            for j in range(n_c):
                out[0, i, j] = 0.0
        for h in range(H):
            _far_sum(Pc, dd, h, np.empty((0, 0), dtype=np.complex128), dA)
            for i in range(n_c):  # dB = −B dA B
                for j in range(n_c):
                    acc = 0.0j
                    for q in range(n_c):
                        acc += Bk[h, i, q] * dA[q, j]
                    tmp[i, j] = acc
            for i in range(n_c):
                for j in range(n_c):
                    acc = 0.0j
                    for q in range(n_c):
                        acc += tmp[i, q] * Bk[h, q, j]
                    dB[i, j] = -acc
            jh = jsel[h]
            gsum = dinv_j[h]
            for i in range(n_c):
                acc = 0.0j
                for j in range(n_c):
                    acc += dB[i, j] * Pc[j, jh]
                dBphi[h, i] = acc
                gsum += Pc[i, jh] * acc
            dg[h] = gsum
            gh = g[h]
            for i in range(n_c):
                for j in range(n_c):
                    out[h + 1, i, j] = (dB[i, j] - (dBphi[h, i] * Bphi[h, j] + Bphi[h, i] * dBphi[h, j]) / gh
                                        + Bphi[h, i] * Bphi[h, j] * (gsum / gh**2))
        for i in range(n_c):
            for b in range(n_b):
                dh = 0.0j
                acc = 0.0j
                for j in range(n_c):
                    acc += out[1, i, j] * hfar[j, b]
                for j in range(n_c):
                    dhj = 0.0j
                    for m in range(n_m):
                        dhj += Pc[j, m] * (dd[0, m] * beta[m, b])
                    dh += D[1, i, j] * dhj
                bj = beta[j0, b]
                dP[i, b] = acc + dh + (dBphi[0, i] * bj * g[0] - Bphi[0, i] * bj * dg[0]) / g[0] ** 2
    return 0
