"""Plain-NumPy references for Coulomb friction: the pointwise law by branches and the
harmonic projection by root bracketing (scipy brentq on a dense grid) and Gauss–Legendre
quadrature on every smooth piece. Nothing here imports :mod:`mmshbm`."""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq


def clip_loop(p, s):
    """clip(p, −s, s) by explicit branches."""
    out = np.empty(len(p))
    for j, pj in enumerate(p):
        out[j] = s if pj > s else (-s if pj < -s else pj)
    return out


def synth(coef, tau):
    """NLvib-ordered coefficients evaluated at tau (any shape)."""
    tau = np.asarray(tau, dtype=float)
    H = (len(coef) - 1) // 2
    out = np.full(tau.shape, coef[0])
    for k in range(1, H + 1):
        out = out + coef[2 * k - 1] * np.cos(k * tau) + coef[2 * k] * np.sin(k * tau)
    return out


def basis(H, tau):
    """(2H+1, n) rows 1, cos τ, sin τ, ..., cos Hτ, sin Hτ."""
    rows = [np.ones_like(tau)]
    for k in range(1, H + 1):
        rows += [np.cos(k * tau), np.sin(k * tau)]
    return np.array(rows)


def breakpoints(p, s, n_grid=20000):
    """Sorted zeros of p − s and p + s on [0, 2π) (bracketed on a dense grid)."""
    tau = np.linspace(0.0, 2 * np.pi, n_grid + 1)
    roots = []
    for level in (s, -s):
        g = synth(p, tau) - level
        for j in range(n_grid):
            if g[j] == 0.0:
                roots.append(tau[j])
            elif g[j] * g[j + 1] < 0:
                roots.append(brentq(lambda t, lv=level: synth(p, t) - lv, tau[j], tau[j + 1], xtol=1e-15))
    return np.sort(np.array(roots))


def project_clip(p, s, nodes=40):
    """(proj[clip(p, −s, s)] (2H+1,), proj[[|p| < s] φ_b] (2H+1, 2H+1)) by quadrature on
    the pieces between switching instants, each split into pieces of length <= π/(2H)."""
    H = (len(p) - 1) // 2
    edges = np.concatenate([[0.0], breakpoints(p, s), [2 * np.pi]])
    x, w = np.polynomial.legendre.leggauss(nodes)
    weight = np.array([1 / (2 * np.pi)] + [1 / np.pi] * (2 * H))
    proj = np.zeros(2 * H + 1)
    Jac = np.zeros((2 * H + 1, 2 * H + 1))
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        if b - a <= 0:
            continue
        n_sub = max(1, int(np.ceil((b - a) * 2 * H / np.pi)))
        sub = np.linspace(a, b, n_sub + 1)
        for lo, hi in zip(sub[:-1], sub[1:], strict=True):
            t = 0.5 * (hi - lo) * x + 0.5 * (hi + lo)
            wt = 0.5 * (hi - lo) * w
            pv = synth(p, t)
            E = basis(H, t)
            proj += E @ (wt * clip_loop(pv, s))
            inside = (np.abs(pv) < s).astype(float)
            Jac += (E * (wt * inside)) @ E.T
    return proj * weight, Jac * weight[:, None]


def play_force_sampled(y, s, r, n=2**17, periods=2):
    """proj[r (u − y)] with u the play operator of half-width s/r driven by y, by the clamp
    recursion on n samples per period (exact on the piecewise-linear interpolant of the
    samples), started at u = mean(y) and run ``periods`` periods; the last period is
    projected by the trapezoidal rule. Error O((2π/n)²)."""
    H = (len(y) - 1) // 2
    tau = 2 * np.pi * np.arange(n) / n
    yt = synth(y, tau)
    w = s / r
    u = y[0]
    for _ in range(periods - 1):
        for j in range(n):
            u = min(max(u, yt[j] - w), yt[j] + w)
    ut = np.empty(n)
    for j in range(n):
        u = min(max(u, yt[j] - w), yt[j] + w)
        ut[j] = u
    g = r * (ut - yt)
    E = basis(H, tau)
    weight = np.array([1.0] + [2.0] * (2 * H)) / n
    return (E @ g) * weight
