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
    """The contact rows of the damped MMS-HBM residual (:mod:`mmshbm.methods._damped_hbm`), in
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
