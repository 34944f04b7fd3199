"""Numba kernels of the alternating frequency-time evaluation and of the condensation:
banded LU of K − (kΩ)²M, the condensed dynamic stiffness, a small dense solve.

Kernels take plain contiguous float64 arrays and know nothing of models; the public
functions validate shapes and call the private ``_kernel`` versions, which the solvers
call directly in their inner loops. Caching: every kernel module takes its flags from
:data:`JIT_OPTIONS` (defined with the cache policy in :mod:`mmshbm._kernel_cache`,
re-exported here), and importing this module installs that policy (a cached kernel is
stale when any kernel file changes), so kernels may call kernels of other files.
The proximal contact law and the cosine product matrix live with the contact laws
(:mod:`mmshbm.contact.unilateral`, :mod:`mmshbm.contact.projection`).
"""

from __future__ import annotations

from numba import njit

from .._kernel_cache import JIT_OPTIONS
from .._kernel_cache import install as _install_cache_policy

__all__ = ["JIT_OPTIONS"]

_install_cache_policy()


# ---------------------------------------------------------------------------- banded LU
# Row band layout: A[i, j] is stored at AB[i, j − i + kl] for −kl <= j − i <= 2kl
# (half bandwidth kl on both sides; the extra kl columns hold the fill-in of partial
# pivoting). A symmetric FE matrix pair K, M renumbered by RCM fits with kl small.


@njit(**JIT_OPTIONS)
def _band_solve(Kb, Mb, kl, w2, B, AB, X):
    """Solve (K − w2 M) X = B by band LU with partial pivoting; returns 0 or, if a pivot
    is exactly zero, its 1-based column (the matrix is singular).

    Kb, Mb : (n, 3kl+1) row band layout (fill columns zero); B, X : (n, m); AB : work (n, 3kl+1).
    """
    n = Kb.shape[0]
    width = Kb.shape[1]
    m = B.shape[1]
    for i in range(n):
        for c in range(width):
            AB[i, c] = Kb[i, c] - w2 * Mb[i, c]
        for q in range(m):
            X[i, q] = B[i, q]
    for j in range(n):
        last_row = j + kl if j + kl < n else n - 1
        p = j
        best = abs(AB[j, kl])
        for i in range(j + 1, last_row + 1):
            v = abs(AB[i, j - i + kl])
            if v > best:
                best = v
                p = i
        if best == 0.0:
            return j + 1
        last_col = j + 2 * kl if j + 2 * kl < n else n - 1
        if p != j:
            for c in range(j, last_col + 1):
                tmp = AB[j, c - j + kl]
                AB[j, c - j + kl] = AB[p, c - p + kl]
                AB[p, c - p + kl] = tmp
            for q in range(m):
                tmp = X[j, q]
                X[j, q] = X[p, q]
                X[p, q] = tmp
        pivot = AB[j, kl]
        for i in range(j + 1, last_row + 1):
            factor = AB[i, j - i + kl] / pivot
            if factor == 0.0:
                continue
            AB[i, j - i + kl] = 0.0
            for c in range(j + 1, last_col + 1):
                AB[i, c - i + kl] -= factor * AB[j, c - j + kl]
            for q in range(m):
                X[i, q] -= factor * X[j, q]
    for i in range(n - 1, -1, -1):
        last_col = i + 2 * kl if i + 2 * kl < n else n - 1
        for q in range(m):
            acc = X[i, q]
            for c in range(i + 1, last_col + 1):
                acc -= AB[i, c - i + kl] * X[c, q]
            X[i, q] = acc / AB[i, kl]
    return 0


@njit(**JIT_OPTIONS)
def _band_quadratic_form(Mb, kl, Z, out):
    """out = Zᵀ M Z for symmetric M in row band layout; Z (n, m), out (m, m)."""
    n = Z.shape[0]
    m = Z.shape[1]
    for p in range(m):
        for q in range(m):
            out[p, q] = 0.0
    for i in range(n):
        j0 = i - kl if i - kl > 0 else 0
        j1 = i + kl + 1 if i + kl + 1 < n else n
        for j in range(j0, j1):
            mij = Mb[i, j - i + kl]
            if mij == 0.0:
                continue
            for p in range(m):
                zp = Z[i, p] * mij
                for q in range(m):
                    out[p, q] += zp * Z[j, q]


@njit(**JIT_OPTIONS)
def _condensed_stiffness(Kb, Mb, kl, K_lc, K_cc, omega, harmonics, D, dD, AB, Z, ZMZ, derivative):
    """D_k = K_cc − K_lcᵀ (K − (kΩ)² M)⁻¹ K_lc and ∂D_k/∂Ω = −2k²Ω ZᵀMZ for k = 1..H.

    D, dD : (H+1, n_c, n_c) outputs (row 0 untouched); AB, Z, ZMZ: work arrays.
    Returns 0, or k·(n+1) + column for the first singular harmonic k.
    """
    n = Kb.shape[0]
    n_c = K_lc.shape[1]
    for k in range(1, harmonics + 1):
        wk = k * omega
        info = _band_solve(Kb, Mb, kl, wk * wk, K_lc, AB, Z)
        if info != 0:
            return k * (n + 1) + info
        for p in range(n_c):
            for q in range(n_c):
                acc = K_cc[p, q]
                for i in range(n):
                    acc -= K_lc[i, p] * Z[i, q]
                D[k, p, q] = acc
        if derivative:
            _band_quadratic_form(Mb, kl, Z, ZMZ)
            scale = -2.0 * k * k * omega
            for p in range(n_c):
                for q in range(n_c):
                    dD[k, p, q] = scale * ZMZ[p, q]
    return 0


# ---------------------------------------------------------------------------- small dense solve
@njit(**JIT_OPTIONS)
def _dense_solve(A, b, LU, x, sign):
    """Solve A x = b by LU with partial pivoting (small dense systems, where LAPACK's call
    overhead dominates). A (n, n) and b (n,) are read only; LU (n, n) is work; ``sign[0]``
    receives the sign of det A (from the pivots and the row swaps). Returns 0, or the
    1-based column of an exactly zero pivot (x and the sign are then undefined)."""
    n = A.shape[0]
    s = 1.0
    for i in range(n):
        for j in range(n):
            LU[i, j] = A[i, j]
        x[i] = b[i]
    for j in range(n):
        p = j
        best = abs(LU[j, j])
        for i in range(j + 1, n):
            v = abs(LU[i, j])
            if v > best:
                best = v
                p = i
        if best == 0.0:
            return j + 1
        if p != j:
            s = -s
            for c in range(n):
                tmp = LU[j, c]
                LU[j, c] = LU[p, c]
                LU[p, c] = tmp
            tmp = x[j]
            x[j] = x[p]
            x[p] = tmp
        pivot = LU[j, j]
        if pivot < 0.0:
            s = -s
        for i in range(j + 1, n):
            factor = LU[i, j] / pivot
            if factor == 0.0:
                continue
            for c in range(j + 1, n):
                LU[i, c] -= factor * LU[j, c]
            x[i] -= factor * x[j]
    for i in range(n - 1, -1, -1):
        acc = x[i]
        for c in range(i + 1, n):
            acc -= LU[i, c] * x[c]
        x[i] = acc / LU[i, i]
    sign[0] = s
    return 0
