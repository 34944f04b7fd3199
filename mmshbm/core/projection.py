"""Harmonic projection of the proximal contact law on trigonometric polynomials, as plain
functions: the spectrum of an active set and the projection with its Jacobian in NLvib's
coefficient order (the damped and forced methods use these; the conservative MMS-HBM
residual fuses the same kernels, :mod:`mmshbm.core.contact_kernels`).

The projection and its Jacobian are compiled (``_project``, ``_contact_rows``); the
cos/sin tables of the sample grid are built once per (H, N) (:func:`sample_tables`). These
kernels call :func:`~mmshbm.core.contact_kernels._spectrum` in another file: numba's cache
does not see edits there, so clear it after editing that file
(``find mmshbm -name '*.nb[ic]' -delete``).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numba import njit

from .contact_kernels import _TWO_PI, _spectrum
from .kernels import JIT_OPTIONS

__all__ = ["project_contact", "contact_spectrum", "sample_tables"]


@functools.lru_cache(maxsize=64)
def sample_tables(H: int, N: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(τ (N,), cos nτ (2H+1, N), sin nτ (2H+1, N)) on τ_j = 2πj/N, n = 0..2H; built once per
    (H, N) and shared: never write to them."""
    tau = _TWO_PI * np.arange(N) / N
    n = np.arange(2 * H + 1)[:, None]
    return tau, np.cos(n * tau), np.sin(n * tau)


def _check_samples(H: int, n_samples: int | None) -> int:
    N = 16 * (2 * H + 1) if n_samples is None else int(n_samples)
    if N < 2 * H + 1:
        raise ValueError(f"n_samples must be >= 2H+1 = {2 * H + 1}, got {N}")
    return N


def contact_spectrum(c: np.ndarray, s: np.ndarray | None = None, exact: bool = True,
                     n_samples: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Spectrum of the set where the trigonometric polynomial g is positive.

    Parameters
    ----------
    c, s : ndarray, shape (H+1,)
        g(τ) = c_0 + Σ_{k=1..H} (c_k cos kτ + s_k sin kτ) (``s[0]`` unused; None: zero).
    exact : bool
        Arcs between exactly located zeros (True) or sample means (False).
    n_samples : int, optional
        Samples per period (bracketing grid, or the sampled rule); default 16·(2H+1).

    Returns
    -------
    C, S : ndarray, shape (2H+1,)
        C_n = (1/2π)∫_{g>0} cos nτ dτ and S_n likewise with sines, n = 0..2H.
    """
    c = np.ascontiguousarray(c, dtype=float)
    H = c.shape[0] - 1
    s = np.zeros(H + 1) if s is None else np.ascontiguousarray(s, dtype=float)
    if c.ndim != 1 or s.shape != c.shape:
        raise ValueError(f"c and s must be 1-D of equal length, got {c.shape} and {s.shape}")
    N = _check_samples(H, n_samples)
    tau, cos_t, sin_t = sample_tables(H, N)
    C, S = np.empty(2 * H + 1), np.empty(2 * H + 1)
    _spectrum(c, s, cos_t, sin_t, tau, bool(exact), np.empty(N), np.empty(N), np.empty(2 * N + 2), C, S)
    return C, S


@njit(**JIT_OPTIONS)
def _add_product_matrix(C, S, G):
    """G += [proj_a[s φ_b]] in NLvib order (φ = 1, cos τ, sin τ, ..., cos Hτ, sin Hτ) from the
    spectrum (C, S) of s; G is (2H+1, 2H+1)."""
    n = G.shape[0]
    for a in range(n):
        m = (a + 1) // 2
        a_sin = a > 0 and a % 2 == 0
        w = 1.0 if a == 0 else 2.0
        for b in range(n):
            k = (b + 1) // 2
            b_sin = b > 0 and b % 2 == 0
            d = m - k if m >= k else k - m
            t = m + k
            if not a_sin and not b_sin:
                v = 0.5 * (C[d] + C[t])
            elif a_sin and b_sin:
                v = 0.5 * (C[d] - C[t])
            elif not a_sin:  # cos m · sin k = ½ (sin (k+m) + sin (k−m))
                v = 0.5 * (S[t] + (1.0 if k > m else (-1.0 if k < m else 0.0)) * S[d])
            else:  # sin m · cos k = ½ (sin (m+k) + sin (m−k))
                v = 0.5 * (S[t] + (1.0 if m > k else (-1.0 if m < k else 0.0)) * S[d])
            G[a, b] += w * v


def _product_matrix(C: np.ndarray, S: np.ndarray, H: int) -> np.ndarray:
    """G (2H+1, 2H+1) with G_ab = proj_a[s φ_b] from the spectrum (C, S) of s (n = 0..2H)."""
    G = np.zeros((2 * H + 1, 2 * H + 1))
    _add_product_matrix(np.ascontiguousarray(C, dtype=float), np.ascontiguousarray(S, dtype=float), G)
    return G


@njit(**JIT_OPTIONS)
def _project(p, lo, hi, exact, cos_t, sin_t, tau, r, G):
    """In place: r (2H+1,) the projection of (p − hi)₊ − (lo − p)₊ for NLvib-ordered p, and
    G (2H+1, 2H+1) = ∂r/∂p (``project_contact``). lo/hi = ∓inf: no stop on that side."""
    n = p.shape[0]
    H = (n - 1) // 2
    N = tau.shape[0]
    gc = np.empty(H + 1)
    gs = np.empty(H + 1)
    g_t = np.empty(N)
    dg_t = np.empty(N)
    roots = np.empty(2 * N + 2)
    C = np.empty(2 * H + 1)
    S = np.empty(2 * H + 1)
    Gt = np.empty((n, n))
    for a in range(n):
        r[a] = 0.0
        for b in range(n):
            G[a, b] = 0.0
    for side in range(2):
        theta = hi if side == 0 else lo
        sign = 1.0 if side == 0 else -1.0
        if math.isinf(theta):
            continue
        gc[0] = sign * p[0] - sign * theta  # g = ±(p − θ) > 0 on the active set
        gs[0] = 0.0
        for k in range(1, H + 1):
            gc[k] = sign * p[2 * k - 1]
            gs[k] = sign * p[2 * k]
        _spectrum(gc, gs, cos_t, sin_t, tau, exact, g_t, dg_t, roots, C, S)
        for a in range(n):
            for b in range(n):
                Gt[a, b] = 0.0
        _add_product_matrix(C, S, Gt)
        for a in range(n):
            acc = 0.0
            for b in range(n):
                acc += Gt[a, b] * p[b]
                G[a, b] += Gt[a, b]
            if a == 0:
                ind = C[0]
            elif a % 2 == 1:
                ind = 2.0 * C[(a + 1) // 2]
            else:
                ind = 2.0 * S[a // 2]
            r[a] += acc - theta * ind


@njit(**JIT_OPTIONS)
def _contact_rows(x, F, rows, n_c, lo, hi, rr, exact, cos_t, sin_t, tau, R, G):
    """The contact rows of the damped MMS-HBM residual (:mod:`mmshbm.methods.mms.damped`), in
    place: for contact j at massless DOF i = rows[j] with coefficients idx = m·n_c + i,
    R[idx] = F[idx] + r_j φ(p), p = x[idx] − F[idx]/r_j, and G[j] = ∂φ/∂p (2H+1, 2H+1)."""
    n = G.shape[1]
    p = np.empty(n)
    phi = np.empty(n)
    for j in range(rows.shape[0]):
        i = rows[j]
        rj = rr[j]
        for m in range(n):
            p[m] = x[m * n_c + i] - F[m * n_c + i] / rj
        _project(p, lo[j], hi[j], exact, cos_t, sin_t, tau, phi, G[j])
        for m in range(n):
            R[m * n_c + i] = F[m * n_c + i] + rj * phi[m]


@njit(**JIT_OPTIONS)
def _block_times(D, x, out):
    """out (n_x,) = 𝔇 x for the real block matrix 𝔇 of the complex D_k (H+1, n_c, n_c) in NLvib
    order: D_0 on the mean, [[Re, Im], [−Im, Re]] D_k on (cos k, sin k)."""
    H1 = D.shape[0]
    n_c = D.shape[1]
    for i in range(n_c):
        acc = 0.0
        for j in range(n_c):
            acc += D[0, i, j].real * x[j]
        out[i] = acc
    for k in range(1, H1):
        c = (2 * k - 1) * n_c
        s = 2 * k * n_c
        for i in range(n_c):
            acc_c = 0.0
            acc_s = 0.0
            for j in range(n_c):
                dr = D[k, i, j].real
                di = D[k, i, j].imag
                acc_c += dr * x[c + j] + di * x[s + j]
                acc_s += dr * x[s + j] - di * x[c + j]
            out[c + i] = acc_c
            out[s + i] = acc_s


@njit(**JIT_OPTIONS)
def _damped_residual(D, dD, x, load, dload, rows, lo, hi, rr, exact, cos_t, sin_t, tau, jacobian, R, Jx, Jp):
    """The damped MMS-HBM contact residual (:mod:`mmshbm.methods.mms.damped`) with F = 𝔇 x − load
    the force the structure needs, in place.

    D      : (H+1, n_c, n_c) complex D_k; dD : (n_p, H+1, n_c, n_c) their derivatives in the
             parameters (read if ``jacobian``)
    x      : (n_x,) NLvib-ordered coefficients of the massless DOFs, n_x = (2H+1) n_c
    load   : (n_x,) the condensed load; dload : (n_x, n_p) its derivatives
    rows, lo, hi, rr : per contact its massless DOF, interval and proximal parameter
    R      : (n_x,) <- F, and on contact rows F + r φ(x − F/r)
    Jx, Jp : (n_x, n_x), (n_x, n_p) <- ∂R/∂x, ∂R/∂params (if ``jacobian``)
    """
    n_c = D.shape[1]
    n = 2 * D.shape[0] - 1
    n_x = n * n_c
    n_p = dD.shape[0]
    n_k = rows.shape[0]
    _block_times(D, x, R)
    for a in range(n_x):
        R[a] -= load[a]
    F = R.copy()
    G = np.empty((n_k, n, n))
    _contact_rows(x, F, rows, n_c, lo, hi, rr, exact, cos_t, sin_t, tau, R, G)
    if not jacobian:
        return
    dF = np.empty(n_x)
    for p in range(n_p):
        _block_times(dD[p], x, dF)
        for a in range(n_x):
            Jp[a, p] = dF[a] - dload[a, p]
    for a in range(n_x):
        for b in range(n_x):
            Jx[a, b] = 0.0
    for i in range(n_c):
        for j in range(n_c):
            Jx[i, j] = D[0, i, j].real
    for k in range(1, D.shape[0]):
        c = (2 * k - 1) * n_c
        s = 2 * k * n_c
        for i in range(n_c):
            for j in range(n_c):
                dr = D[k, i, j].real
                di = D[k, i, j].imag
                Jx[c + i, c + j] = dr
                Jx[c + i, s + j] = di
                Jx[s + i, c + j] = -di
                Jx[s + i, s + j] = dr
    # contact rows: ∂R/∂x = (I − G) 𝔇 + r G on the DOF's own columns, ∂R/∂params = (I − G) ∂F
    dFi = np.empty((n, n_p))
    for jc in range(n_k):
        i = rows[jc]
        Gj = G[jc]
        for m in range(n):
            for p in range(n_p):
                dFi[m, p] = Jp[m * n_c + i, p]
        for m in range(n):
            row = m * n_c + i
            w0 = (1.0 if m == 0 else 0.0) - Gj[m, 0]
            for j in range(n_c):
                Jx[row, j] = w0 * D[0, i, j].real
            for k in range(1, D.shape[0]):
                c = 2 * k - 1
                s = 2 * k
                wc = (1.0 if m == c else 0.0) - Gj[m, c]
                ws = (1.0 if m == s else 0.0) - Gj[m, s]
                for j in range(n_c):
                    dr = D[k, i, j].real
                    di = D[k, i, j].imag
                    Jx[row, c * n_c + j] = wc * dr - ws * di
                    Jx[row, s * n_c + j] = wc * di + ws * dr
            for b in range(n):
                Jx[row, b * n_c + i] += rr[jc] * Gj[m, b]
            for p in range(n_p):
                v = 0.0
                for mm in range(n):
                    v += ((1.0 if mm == m else 0.0) - Gj[m, mm]) * dFi[mm, p]
                Jp[row, p] = v


def project_contact(p: np.ndarray, lo: float, hi: float, exact: bool = True,
                    n_samples: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Harmonic projection of (p − hi)₊ − (lo − p)₊ and its Jacobian.

    Parameters
    ----------
    p : ndarray, shape (2H+1,)
        NLvib-ordered coefficients [p_0, p_c1, p_s1, ..., p_cH, p_sH] of p(τ).
    lo, hi : float
        The admissible interval (``-inf`` / ``inf`` for a side without a stop), lo <= hi.
    exact : bool
        Exact (C¹) projection with the switching instants located (default), or the
        sampled AFT projection.
    n_samples : int, optional
        Samples per period; default 16·(2H+1).

    Returns
    -------
    r : ndarray, shape (2H+1,)
        NLvib-ordered projection (proj_0 = mean, proj_cm = (1/π)∫ · cos mτ, ...).
    G : ndarray, shape (2H+1, 2H+1)
        ∂r/∂p: the projection of s(τ)·φ_b(τ), s the indicator of the active set.
    """
    p = np.ascontiguousarray(p, dtype=float)
    if p.ndim != 1 or p.shape[0] % 2 != 1:
        raise ValueError(f"p must be 1-D with 2H+1 entries, got shape {p.shape}")
    lo, hi = float(lo), float(hi)
    if math.isnan(lo) or math.isnan(hi) or lo > hi:
        raise ValueError(f"need lo <= hi, got lo={lo!r}, hi={hi!r}")
    H = (p.shape[0] - 1) // 2
    tau, cos_t, sin_t = sample_tables(H, _check_samples(H, n_samples))
    r = np.empty(2 * H + 1)
    G = np.empty((2 * H + 1, 2 * H + 1))
    _project(p, lo, hi, bool(exact), cos_t, sin_t, tau, r, G)
    return r, G
