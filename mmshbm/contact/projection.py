"""The harmonic projection machinery shared by the contact laws: the spectrum of the set
where a trigonometric polynomial is positive (sampled or exact), and the matrices that turn
it into the projection of s(τ)·φ_b(τ) (s the indicator of that set).

A law whose proximal map is piecewise linear in its trial value p(τ) (the unilateral stop
and the clearance, :mod:`mmshbm.contact.unilateral`; Coulomb friction,
:mod:`mmshbm.contact.coulomb`) has, on each piece, a residual linear in p; its harmonic
projection is then a matrix times the coefficients of p,

    proj_m[s · cos kτ] = G_mk = ε_m/2 (C_|m−k| + C_m+k),   C_n = (1/2π) ∫_{s=1} cos nτ dτ,

ε_0 = 1, ε_m = 2 (and the analogous sine terms for a general trigonometric polynomial).
Only the spectrum C_n, S_n (n = 0..2H) of the active set depends on how the projection is
done:

* **sampled** (AFT): C_n = (1/N) Σ_j s(τ_j) cos nτ_j on N samples; a sample changing its
  active set is a kink of the residual.
* **exact** (C¹): the zeros of the trigonometric polynomial that bounds the set are
  bracketed on the N samples and refined to round-off (:mod:`mmshbm.contact.trig`), and
  C_n, S_n are integrated in closed form over the arcs; the residual vanishes at the
  moving arc ends, so the same G is the exact Jacobian (docs/design.md §2, §8).

Kernels take plain arrays; :func:`contact_spectrum` and :func:`cosine_product_matrix`
validate and call them. The cos/sin tables of the sample grid are built once per (H, N)
(:func:`sample_tables`).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numba import njit

from .._kernel_cache import JIT_OPTIONS
from .._kernel_cache import install as _install_cache_policy
from .trig import _TWO_PI, _trig_eval, _zeros

__all__ = ["contact_spectrum", "sample_tables", "cosine_product_matrix"]

_install_cache_policy()


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


@njit(**JIT_OPTIONS)
def _arc_spectrum(c, s, g_t, dg_t, tau_t, roots, C, S):
    """Exact spectrum of the indicator of {g > 0}: C_n = (1/2π)∫ cos nτ, S_n = (1/2π)∫ sin nτ
    over that set, n = 0..len(C)−1 (in place)."""
    n_spec = C.shape[0]
    for p in range(n_spec):
        C[p] = 0.0
        S[p] = 0.0
    nr = _zeros(c, s, g_t, dg_t, tau_t, roots)
    if nr == 0:
        if g_t[0] > 0.0:
            C[0] = 1.0
        return
    for i in range(nr):
        a = roots[i]
        b = roots[i + 1] if i + 1 < nr else roots[0] + _TWO_PI
        if b <= a:
            continue
        g_mid, _, _ = _trig_eval(c, s, 0.5 * (a + b))
        if g_mid <= 0.0:
            continue
        C[0] += b - a
        ca, sa = math.cos(a), math.sin(a)
        cb, sb = math.cos(b), math.sin(b)
        cna, sna, cnb, snb = 1.0, 0.0, 1.0, 0.0
        for p in range(1, n_spec):
            cna, sna = cna * ca - sna * sa, sna * ca + cna * sa
            cnb, snb = cnb * cb - snb * sb, snb * cb + cnb * sb
            C[p] += (snb - sna) / p
            S[p] += (cna - cnb) / p
    for p in range(n_spec):
        C[p] /= _TWO_PI
        S[p] /= _TWO_PI


@njit(**JIT_OPTIONS)
def _sampled_spectrum(g_t, cos_table, sin_table, C, S):
    """Sampled spectrum of the indicator of {g > 0}: C_n = (1/N) Σ_j s_j cos nτ_j (and S_n
    with sines; sin_table may have fewer rows, the rest of S is zero)."""
    N = g_t.shape[0]
    for p in range(C.shape[0]):
        acc = 0.0
        acc_s = 0.0
        for j in range(N):
            if g_t[j] > 0.0:
                acc += cos_table[p, j]
                if p < sin_table.shape[0]:
                    acc_s += sin_table[p, j]
        C[p] = acc / N
        S[p] = acc_s / N


@njit(**JIT_OPTIONS)
def _spectrum(c, s, cos_table, sin_table, tau_t, exact, g_t, dg_t, roots, C, S):
    """Spectrum of {g > 0} for g with coefficients (c, s) of degree H = len(c) − 1: samples
    g_t (and g′ for the exact route) from the tables, then the sampled or exact spectrum."""
    N = g_t.shape[0]
    H = c.shape[0] - 1
    # harmonic by harmonic along the table rows (contiguous), each sample summed in k order
    for j in range(N):
        g_t[j] = c[0]
        dg_t[j] = 0.0
    for k in range(1, H + 1):
        ck = c[k]
        sk = s[k]
        for j in range(N):
            g_t[j] += ck * cos_table[k, j] + sk * sin_table[k, j]
            dg_t[j] += k * (sk * cos_table[k, j] - ck * sin_table[k, j])
    if exact:
        _arc_spectrum(c, s, g_t, dg_t, tau_t, roots, C, S)
    else:
        _sampled_spectrum(g_t, cos_table, sin_table, C, S)


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
def _cosine_product_matrix(S, H, P):
    """P[m, k] = c_m/2 (S[|m−k| mod N] + S[(m+k) mod N]), c_0 = 1, c_m = 2.

    With S_p = (1/N) Σ_j s_j cos pτ_j this is the cosine coefficient m of s(τ)·cos kτ.
    """
    N = S.shape[0]
    for m in range(H + 1):
        cm = 0.5 if m == 0 else 1.0
        for k in range(H + 1):
            d = m - k if m >= k else k - m
            P[m, k] = cm * (S[d % N] + S[(m + k) % N])


def cosine_product_matrix(S: np.ndarray, harmonics: int) -> np.ndarray:
    """Matrix (H+1, H+1) of the cosine projection of s(τ)·cos kτ from the aliased cosine
    spectrum ``S`` (shape (N,), see :meth:`HarmonicTransform.cosine_spectrum`)."""
    S = np.ascontiguousarray(S, dtype=np.float64)
    if S.ndim != 1 or S.shape[0] < 2 * harmonics + 1:
        raise ValueError(f"S must be 1-D with at least 2H+1 = {2 * harmonics + 1} samples, got {S.shape}")
    P = np.empty((harmonics + 1, harmonics + 1))
    _cosine_product_matrix(S, int(harmonics), P)
    return P
