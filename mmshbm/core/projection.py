"""Harmonic projection of the proximal contact law on trigonometric polynomials, as plain
functions: the spectrum of an active set and the projection with its Jacobian in NLvib's
coefficient order (the damped and forced methods use these; the conservative MMS-HBM
residual fuses the same kernels, :mod:`mmshbm.core.contact_kernels`)."""

from __future__ import annotations

import math

import numpy as np

from .contact_kernels import _TWO_PI, _spectrum

__all__ = ["project_contact", "contact_spectrum"]


def _tables(H: int, N: int):
    tau = _TWO_PI * np.arange(N) / N
    n = np.arange(2 * H + 1)[:, None]
    return tau, np.cos(n * tau), np.sin(n * tau)


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
    N = 16 * (2 * H + 1) if n_samples is None else int(n_samples)
    if N < 2 * H + 1:
        raise ValueError(f"n_samples must be >= 2H+1 = {2 * H + 1}, got {N}")
    tau, cos_t, sin_t = _tables(H, N)
    C, S = np.empty(2 * H + 1), np.empty(2 * H + 1)
    _spectrum(c, s, cos_t, sin_t, tau, bool(exact), np.empty(N), np.empty(N), np.empty(2 * N + 2), C, S)
    return C, S


def _product_matrix(C: np.ndarray, S: np.ndarray, H: int) -> np.ndarray:
    """G_ab = proj_a[s φ_b] in NLvib order (φ = 1, cos τ, sin τ, ..., cos Hτ, sin Hτ) from the
    spectrum (C, S) of s."""
    G = np.zeros((2 * H + 1, 2 * H + 1))
    for a in range(2 * H + 1):
        m, a_sin = (a + 1) // 2, a > 0 and a % 2 == 0
        w = 1.0 if a == 0 else 2.0
        for b in range(2 * H + 1):
            k, b_sin = (b + 1) // 2, b > 0 and b % 2 == 0
            d, t = abs(m - k), m + k
            if not a_sin and not b_sin:
                v = 0.5 * (C[d] + C[t])
            elif a_sin and b_sin:
                v = 0.5 * (C[d] - C[t])
            elif not a_sin:  # cos m · sin k = ½ (sin (k+m) + sin (k−m))
                v = 0.5 * (S[t] + np.sign(k - m) * S[d])
            else:  # sin m · cos k = ½ (sin (m+k) + sin (m−k))
                v = 0.5 * (S[t] + np.sign(m - k) * S[d])
            G[a, b] = w * v
    return G


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
    p = np.asarray(p, dtype=float)
    if p.ndim != 1 or p.shape[0] % 2 != 1:
        raise ValueError(f"p must be 1-D with 2H+1 entries, got shape {p.shape}")
    lo, hi = float(lo), float(hi)
    if math.isnan(lo) or math.isnan(hi) or lo > hi:
        raise ValueError(f"need lo <= hi, got lo={lo!r}, hi={hi!r}")
    H = (p.shape[0] - 1) // 2
    c = np.concatenate([[p[0]], p[1::2]])
    s = np.concatenate([[0.0], p[2::2]])
    r = np.zeros(2 * H + 1)
    G = np.zeros((2 * H + 1, 2 * H + 1))
    for theta, sign in ((hi, 1.0), (lo, -1.0)):
        if math.isinf(theta):
            continue
        gc, gs = sign * c, sign * s
        gc[0] -= sign * theta  # g = ±(p − θ) > 0 on the active set
        C, S = contact_spectrum(gc, gs, exact, n_samples)
        Gt = _product_matrix(C, S, H)
        G += Gt
        indicator = np.zeros(2 * H + 1)
        indicator[0] = C[0]
        indicator[1::2] = 2 * C[1:H + 1]
        indicator[2::2] = 2 * S[1:H + 1]
        r += Gt @ p - theta * indicator
    return r, G
