"""Trigonometric polynomials g(τ) = c_0 + Σ_{k=1..H} (c_k cos kτ + s_k sin kτ): their value
and derivatives, and their zeros on one period located to round-off. The zeros are the
switching instants of a contact law on a harmonic-balance point (where the trial value of
the proximal map crosses a bound of its set); every exact projection of a law
(:mod:`mmshbm.contact.projection`, :mod:`mmshbm.contact.coulomb`) integrates its pieces
between them.

Kernels only; they take plain arrays: c, s of shape (H+1,) (``s[0]`` unused), τ in rad.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .._kernel_cache import JIT_OPTIONS
from .._kernel_cache import install as _install_cache_policy

__all__: list[str] = []

_install_cache_policy()

_TWO_PI = 2.0 * math.pi


@njit(**JIT_OPTIONS)
def _trig_eval(c, s, tau):
    """g(τ), g′(τ), g″(τ) of g = c_0 + Σ_k (c_k cos kτ + s_k sin kτ); c, s shape (H+1,)."""
    H = c.shape[0] - 1
    c1 = math.cos(tau)
    s1 = math.sin(tau)
    ck = 1.0
    sk = 0.0
    g = c[0]
    g1 = 0.0
    g2 = 0.0
    for k in range(1, H + 1):
        ck, sk = ck * c1 - sk * s1, sk * c1 + ck * s1
        a = c[k] * ck + s[k] * sk
        b = -c[k] * sk + s[k] * ck
        g += a
        g1 += k * b
        g2 -= k * k * a
    return g, g1, g2


@njit(**JIT_OPTIONS)
def _refine(c, s, a, b, fa, order):
    """Zero of g (order 0) or of g′ (order 1) in the bracket [a, b], where the function has
    the sign of ``fa`` at a and the opposite sign at b: safeguarded Newton (bisection
    whenever a step leaves the bracket), to round-off in τ: it stops where the function
    value is below the round-off of its evaluation (Newton's steps there only hop between
    neighbouring doubles; an end of the bracket with such a value is the zero), or where
    the step or the bracket is at round-off in τ."""
    H = c.shape[0] - 1
    noise = abs(c[0]) if order == 0 else 0.0
    for k in range(1, H + 1):
        noise += (abs(c[k]) + abs(s[k])) * (1.0 if order == 0 else k)
    noise *= 8e-16
    if abs(fa) <= noise:  # a zero on a sample: Newton would bisect towards it to round-off
        return a
    gb, gb1, _ = _trig_eval(c, s, b)
    if abs(gb if order == 0 else gb1) <= noise:
        return b
    x = 0.5 * (a + b)
    for _ in range(100):
        g, g1, g2 = _trig_eval(c, s, x)
        f = g if order == 0 else g1
        df = g1 if order == 0 else g2
        if abs(f) <= noise:
            return x
        if (f > 0.0) == (fa > 0.0):
            a = x
        else:
            b = x
        step_ok = df != 0.0
        xn = x - f / df if step_ok else 0.5 * (a + b)
        if not (a < xn < b):
            xn = 0.5 * (a + b)
        if abs(xn - x) <= 2e-16 * (1.0 + abs(x)) or b - a <= 4e-16 * (1.0 + abs(a)):
            return xn
        x = xn
    return x


@njit(**JIT_OPTIONS)
def _zeros(c, s, g_t, dg_t, tau_t, roots):
    """Zeros of g on [0, 2π), bracketed on the samples g_t = g(τ_j), dg_t = g′(τ_j) at
    τ_j = tau_t[j] (equispaced, τ_0 = 0); returns their count (stored sorted in ``roots``)."""
    N = g_t.shape[0]
    n = 0
    # the order as run-time integers: literal arguments would compile _refine twice
    root, extremum = np.int64(0), np.int64(1)
    # |g″| <= M2 everywhere, so between two samples of one sign g stays beyond
    # min(|g_a|, |g_b|) − M2 h²/8: a hidden pair of zeros needs a sample within that margin
    m2 = 0.0
    for k in range(1, c.shape[0]):
        m2 += k * k * (abs(c[k]) + abs(s[k]))
    h = _TWO_PI / N
    margin = 1.01 * m2 * h * h / 8.0 + 1e-300
    for j in range(N):
        jn = j + 1 if j + 1 < N else 0
        a = tau_t[j]
        b = tau_t[jn] if jn > 0 else _TWO_PI
        ga = g_t[j]
        gb = g_t[jn]
        if ga == 0.0:
            if n < roots.shape[0]:
                roots[n] = a
                n += 1
            continue
        if (ga > 0.0) != (gb > 0.0):
            if gb == 0.0:
                continue  # the next interval records it
            if n < roots.shape[0]:
                roots[n] = _refine(c, s, a, b, ga, root)
                n += 1
        elif dg_t[j] * dg_t[jn] < 0.0 and min(abs(ga), abs(gb)) <= margin:
            # an extremum inside: a pair of close zeros hides if it lies on the other side
            t_ext = _refine(c, s, a, b, dg_t[j], extremum)
            g_ext, _, _ = _trig_eval(c, s, t_ext)
            if g_ext != 0.0 and (g_ext > 0.0) != (ga > 0.0) and n + 1 < roots.shape[0]:
                roots[n] = _refine(c, s, a, t_ext, ga, root)
                roots[n + 1] = _refine(c, s, t_ext, b, g_ext, root)
                n += 2
    return n


