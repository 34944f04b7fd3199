"""The unilateral contact law (Signorini): a rigid stop, or two (a clearance), at a DOF.

Proximal form (λ >= 0 the contact force, g the gap, r > 0):

    λ = prox_{R+}(λ − r g)  ⇔  R = λ − max(0, λ − r g) = 0,

whose zeros are exactly the pairs with 0 <= g ⊥ λ >= 0, whatever r. The active set
s = [λ − r g > 0] gives the semismooth derivative ∂R/∂λ = 1 − s, ∂R/∂g = r s
(:func:`proximal_contact`, pointwise on a time grid).

Interval form on the harmonic-balance unknowns. A contact DOF with admissible positions
[lo, hi] (:func:`~mmshbm.model.contact.admissible_intervals`; ±inf without a stop on a
side: one stop is [−inf, gap] or [−gap, inf], a clearance both bounds finite), the force
f(τ) the structure needs there and its displacement q(τ) satisfy the law exactly when,
for any r > 0 and p = q − f/r,

    R(τ) = f + r [(p − hi)₊ − (lo − p)₊] = 0.

(At the upper stop the structure needs f = −λ <= 0 and q = hi; in between f = 0.) With
the indicator s(τ) of the active set {p > hi} ∪ {p < lo}, R = f + r s (p − θ), θ = hi or
lo: its harmonic projection (:func:`project_contact`) is the product matrix of the active
set's spectrum (:mod:`mmshbm.contact.projection`) times the coefficients of p, minus θ
times the set's own spectrum. A clearance is the same law with both sides finite: it
needs no code of its own.

The MMS-HBM residuals fuse these kernels with the condensed dynamic stiffness
(:mod:`mmshbm.methods.mms.contact_kernels`); the static problem of several stops at one instant
is :mod:`mmshbm.contact.lcp` / :mod:`mmshbm.contact.static`.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numba import njit

from .._kernel_cache import JIT_OPTIONS
from .._kernel_cache import install as _install_cache_policy
from .projection import _add_product_matrix, _check_samples, _spectrum, sample_tables

__all__ = ["proximal_contact", "project_contact", "contact_projection"]

_install_cache_policy()


@njit(**JIT_OPTIONS)
def _proximal_contact(lam, g, r, R, active):
    """In place: R_j = λ_j − max(0, λ_j − r g_j), active_j = (λ_j − r g_j > 0)."""
    for j in range(lam.shape[0]):
        trial = lam[j] - r * g[j]
        if trial > 0.0:
            R[j] = r * g[j]
            active[j] = 1.0
        else:
            R[j] = lam[j]
            active[j] = 0.0


def proximal_contact(lam: np.ndarray, g: np.ndarray, r: float) -> tuple[np.ndarray, np.ndarray]:
    """Residual of the proximal contact law on a time grid.

    Parameters
    ----------
    lam : ndarray, shape (N,)
        Contact force samples λ(τ_j) (N), positive pushing away from the stop.
    g : ndarray, shape (N,)
        Gap samples g_N(τ_j) (m).
    r : float
        Proximal parameter (N/m), > 0.

    Returns
    -------
    R : ndarray, shape (N,)
        λ − max(0, λ − r g) (N); zero exactly where 0 <= g ⊥ λ >= 0.
    active : ndarray, shape (N,)
        1.0 where λ − r g > 0 (contact closed), else 0.0.
    """
    lam = np.ascontiguousarray(lam, dtype=np.float64)
    g = np.ascontiguousarray(g, dtype=np.float64)
    if lam.ndim != 1 or lam.shape != g.shape:
        raise ValueError(f"lam and g must be 1-D of equal length, got {lam.shape} and {g.shape}")
    if not r > 0:
        raise ValueError(f"r must be positive, got {r!r}")
    R = np.empty_like(lam)
    active = np.empty_like(lam)
    _proximal_contact(lam, g, float(r), R, active)
    return R, active




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


def contact_projection(projection: str, H: int, N: int):
    """``project(p, lo, hi) -> (r, G)``: :func:`project_contact`,
    exact (``"exact"``: switching instants located, pieces integrated in closed form, C¹)
    or sampled on N points (``"sampled"``, AFT)."""
    if projection == "exact":
        return project_contact
    if projection == "sampled":
        return functools.partial(project_contact, exact=False, n_samples=N)
    raise ValueError(f"projection must be 'exact' or 'sampled', got {projection!r}")
