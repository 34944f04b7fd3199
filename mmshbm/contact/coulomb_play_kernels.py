"""Compiled kernels of the displacement-level Coulomb projection (the play operator): the
walk over the extrema of y and the whole projection with its Jacobian in one call.

:func:`_play_projection` is :func:`mmshbm.contact.coulomb.project_coulomb_play` without
Python in between: the extrema of y (zeros of y′, bracketed on the sample grid), the walk
from y's global maximum (:func:`_play_walk`), the closed-form spectra of every piece, the
projected force g and its exact Jacobian. The algorithm and its order of operations are
those of the NumPy evaluation (:func:`mmshbm.contact.coulomb._project_play_numpy`, kept as
its reference); the two agree to round-off.

Kernels only; they take plain contiguous float64 arrays. They call the root finder of
:mod:`mmshbm.contact.trig` and the product matrix of :mod:`mmshbm.contact.projection`
(the package's cache policy, :mod:`mmshbm._kernel_cache`, recompiles a caller when a
callee's file changes).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .._kernel_cache import JIT_OPTIONS
from .._kernel_cache import install as _install_cache_policy
from .projection import _add_product_matrix
from .trig import _TWO_PI, _refine, _trig_eval, _zeros

__all__: list[str] = []

_install_cache_policy()


@njit(**JIT_OPTIONS)
def _play_walk(pts, pv, c, sn, width, A, B, SG, U, TE):
    """The pieces of the play operator between consecutive extrema ``pts`` (values ``pv``)
    of y = c_0 + Σ c_k cos kτ + sn_k sin kτ, starting dragged up at pts[0]; written to
    A, B (arc), SG (σ), U (stick position), TE (extremum that set it). Returns the count."""
    m = 0
    u = pv[0] - width
    t_e = pts[0]
    gc = c.copy()
    zero = np.int64(0)
    for i in range(pts.shape[0] - 1):
        a, b, ya, yb = pts[i], pts[i + 1], pv[i], pv[i + 1]
        if b <= a:
            continue
        sigma = 1 if yb > ya else -1
        level = u + sigma * width
        if sigma * (yb - level) <= 0:  # does not reach the slip threshold: sticks throughout
            A[m], B[m], SG[m], U[m], TE[m] = a, b, 0, u, t_e
            m += 1
            continue
        if sigma * (ya - level) >= 0:
            t_sw = a
        else:
            gc[0] = c[0] - level
            t_sw = _refine(gc, sn, a, b, ya - level, zero)
        if t_sw > a:
            A[m], B[m], SG[m], U[m], TE[m] = a, t_sw, 0, u, t_e
            m += 1
        A[m], B[m], SG[m], U[m], TE[m] = t_sw, b, sigma, np.nan, np.nan
        m += 1
        u, t_e = yb - sigma * width, b
    return m


@njit(**JIT_OPTIONS)
def _play_pieces(y, s, r, tau, cos_t, sin_t, A, B, SG, U, TE):
    """The stick and slip pieces of the play operator of half-width s/r driven by the
    NLvib-ordered y (2H+1,), written to A, B, SG, U, TE (capacity >= 2 (2N + 3)); the
    sample grid τ_j (N,) and its tables cos/sin(k τ_j) ((H+1, N) each). Returns the count
    (the conventions of :func:`mmshbm.contact.coulomb.play_pieces`)."""
    H = (y.shape[0] - 1) // 2
    N = tau.shape[0]
    c = np.empty(H + 1)
    sn = np.empty(H + 1)
    dc = np.empty(H + 1)
    ds = np.empty(H + 1)
    c[0], sn[0], dc[0], ds[0] = y[0], 0.0, 0.0, 0.0
    for k in range(1, H + 1):
        c[k], sn[k] = y[2 * k - 1], y[2 * k]
        dc[k], ds[k] = k * sn[k], -k * c[k]
    # samples of y′ and y″
    d1 = np.zeros(N)
    d2 = np.zeros(N)
    for k in range(1, H + 1):
        for j in range(N):
            ck, sk = cos_t[k, j], sin_t[k, j]
            d1[j] += dc[k] * ck + ds[k] * sk
            d2[j] += k * ds[k] * ck - k * dc[k] * sk
    roots = np.empty(2 * N + 2)
    n_ext = _zeros(dc, ds, d1, d2, tau, roots)
    width = s / r
    if n_ext == 0:
        A[0], B[0], SG[0], U[0], TE[0] = 0.0, _TWO_PI, 0, y[0], np.nan
        return 1
    vals = np.empty(n_ext)
    i_max, i_min = 0, 0
    for i in range(n_ext):
        vals[i] = _trig_eval(c, sn, roots[i])[0]
        if vals[i] > vals[i_max]:
            i_max = i
        if vals[i] < vals[i_min]:
            i_min = i
    y_max, y_min = vals[i_max], vals[i_min]
    if y_max - y_min <= 2 * width:
        A[0], B[0], SG[0] = 0.0, _TWO_PI, 0
        if y[0] < y_max - width:
            U[0], TE[0] = y_max - width, roots[i_max]
        elif y[0] > y_min + width:
            U[0], TE[0] = y_min + width, roots[i_min]
        else:
            U[0], TE[0] = y[0], np.nan
        return 1
    pts = np.empty(n_ext + 1)
    pv = np.empty(n_ext + 1)
    for i in range(n_ext):
        j = (i_max + i) % n_ext
        pts[i], pv[i] = roots[j], vals[j]
    pts[n_ext], pv[n_ext] = roots[i_max] + _TWO_PI, y_max
    for i in range(1, n_ext):
        if pts[i] < pts[0]:
            pts[i] += _TWO_PI
    return _play_walk(pts, pv, c, sn, width, A, B, SG, U, TE)


@njit(**JIT_OPTIONS)
def _play_projection(y, s, r, tau, cos_t, sin_t, jacobian, g, J):
    """The exact projection g (2H+1,) of the support's force r (u − y) of a massless Coulomb
    node driven by y (NLvib-ordered, (2H+1,)), slip force s, stiffness r, written to ``g``;
    with ``jacobian`` also ∂g/∂y to ``J`` (2H+1, 2H+1) (left as it is otherwise). The sample
    grid as :func:`_play_pieces`. Returns the fraction of the period in slip."""
    n = y.shape[0]
    H = (n - 1) // 2
    cap = 2 * (2 * tau.shape[0] + 3)
    A = np.empty(cap)
    B = np.empty(cap)
    SG = np.empty(cap)
    U = np.empty(cap)
    TE = np.empty(cap)
    m = _play_pieces(y, s, r, tau, cos_t, sin_t, A, B, SG, U, TE)
    C_stick = np.zeros(n)
    S_stick = np.zeros(n)
    ind = np.empty(n)
    Cp = np.empty(n)
    Sp = np.empty(n)
    inv2pi = 1.0 / (2.0 * math.pi)
    for q in range(n):
        g[q] = 0.0
    if jacobian:
        for q in range(n):
            for p in range(n):
                J[q, p] = 0.0
    slip = 0.0
    for i in range(m):
        a, b = A[i], B[i]
        # the spectrum (1/2π)∫_a^b (cos, sin) nτ dτ, n = 0..2H, of the piece's indicator
        Cp[0], Sp[0] = (b - a) * inv2pi, 0.0
        # cos/sin of qa and qb by rotation (round-off growing as q ε, q <= 2H)
        ca1, sa1, cb1, sb1 = math.cos(a), math.sin(a), math.cos(b), math.sin(b)
        ca, sa, cb, sb = 1.0, 0.0, 1.0, 0.0
        for q in range(1, n):
            ca, sa = ca * ca1 - sa * sa1, sa * ca1 + ca * sa1
            cb, sb = cb * cb1 - sb * sb1, sb * cb1 + cb * sb1
            Cp[q] = (sb - sa) / q * inv2pi
            Sp[q] = (ca - cb) / q * inv2pi
        ind[0] = Cp[0]
        for k in range(1, H + 1):
            ind[2 * k - 1] = 2.0 * Cp[k]
            ind[2 * k] = 2.0 * Sp[k]
        if SG[i] != 0:
            slip += b - a
            for q in range(n):
                g[q] -= s * SG[i] * ind[q]
            continue
        for q in range(n):
            g[q] += r * U[i] * ind[q]
            C_stick[q] += Cp[q]
            S_stick[q] += Sp[q]
        if not jacobian:
            continue
        if math.isnan(TE[i]):  # full stick at the symmetric position u = mean(y)
            for q in range(n):
                J[q, 0] += r * ind[q]
        else:
            c1, s1 = math.cos(TE[i]), math.sin(TE[i])
            ck, sk = 1.0, 0.0
            for q in range(n):
                J[q, 0] += r * ind[q]
            for k in range(1, H + 1):
                ck, sk = ck * c1 - sk * s1, sk * c1 + ck * s1
                for q in range(n):
                    J[q, 2 * k - 1] += r * ind[q] * ck
                    J[q, 2 * k] += r * ind[q] * sk
    G = np.zeros((n, n))
    _add_product_matrix(C_stick, S_stick, G)
    for q in range(n):
        acc = 0.0
        for p in range(n):
            acc += G[q, p] * y[p]
        g[q] -= r * acc
    if jacobian:
        for q in range(n):
            for p in range(n):
                J[q, p] -= r * G[q, p]
    return slip * inv2pi
