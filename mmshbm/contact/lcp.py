"""The static contact problem of several stops at one instant, as a linear
complementarity problem (LCP), solved exactly by principal pivoting.

The contact forces λ (m,) at fixed free gaps h = gap + A q solve

    g = h + G λ >= 0,   λ >= 0,   gᵀλ = 0

(G the Delassus matrix of the massless contact DOFs, 1/k_p on the diagonal of a penalty
spring on a DOF with mass; :func:`~mmshbm.contact.table.contact_law` builds A and G).
λ(h) is continuous and piecewise linear: on the region of an active set J,
λ_J = −G_JJ⁻¹ h_J. Along a straight path h(s) = h0 + s (h1 − h0) it is followed exactly by
principal pivoting (:func:`_lcp_path`): on each piece λ and g are affine in s, and the
piece ends where an active λ_j or an inactive g_i reaches zero. The solution at one h
follows the path from a point where every gap is open (:func:`_lcp_point`,
:func:`lcp_solve`). The shooting integrator follows λ along each time step with the same
kernels (:mod:`mmshbm.methods.shooting._contact_kernels`).

Two enumerations of the active sets serve the few contacts of the other users:
:func:`lcp_enumerated` (λ at one h, least squares on each G_JJ: the admissible signals of
:mod:`mmshbm.contact.static`) and :func:`lcp_active_sets` (the closed set per column, the
least violated one at round-off boundaries, skipping both stops of one DOF: the phases of
the exact reference, :mod:`mmshbm.methods.exact.system`).
"""

from __future__ import annotations

import itertools

import numpy as np
from numba import njit

from .._kernel_cache import JIT_OPTIONS
from .._kernel_cache import install as _install_cache_policy

__all__ = ["lcp_solve", "lcp_enumerated", "lcp_active_sets"]

_install_cache_policy()


@njit(**JIT_OPTIONS)
def _inverse_sub(G, idx, nJ, Ginv, work):
    """In place: Ginv[:nJ, :nJ] <- (G[idx, idx])⁻¹ for the first nJ entries of ``idx``, by
    Gauss–Jordan elimination with partial pivoting. False if singular."""
    for a in range(nJ):
        for b in range(nJ):
            work[a, b] = G[idx[a], idx[b]]
            Ginv[a, b] = 1.0 if a == b else 0.0
    for col in range(nJ):
        piv = col
        big = abs(work[col, col])
        for r in range(col + 1, nJ):
            if abs(work[r, col]) > big:
                big = abs(work[r, col])
                piv = r
        if not big > 0.0:
            return False
        if piv != col:
            for b in range(nJ):
                tmp = work[col, b]
                work[col, b] = work[piv, b]
                work[piv, b] = tmp
                tmp = Ginv[col, b]
                Ginv[col, b] = Ginv[piv, b]
                Ginv[piv, b] = tmp
        d = 1.0 / work[col, col]
        for b in range(nJ):
            work[col, b] *= d
            Ginv[col, b] *= d
        for r in range(nJ):
            if r != col:
                f = work[r, col]
                if f != 0.0:
                    for b in range(nJ):
                        work[r, b] -= f * work[col, b]
                        Ginv[r, b] -= f * Ginv[col, b]
    return True


@njit(**JIT_OPTIONS)
def _lcp_path(G, h0, h1, act, integral, lam1, F, D0, D1, idx, Ginv, work):
    """Follow the LCP solution λ(h(s)) along h(s) = h0 + s (h1 − h0), s from 0 to 1.

    act : (m,) bool, the active set valid at h0 on entry, the one at h1 on exit.
    integral : also accumulate F = 2 ∫₀¹ λ ds (N) and its derivatives D0 = ∂F/∂h0,
        D1 = ∂F/∂h1 (m, m) (exact: λ is linear on each piece and continuous, so
        F = Σ (s_k+1 − s_k)(λ(s_k) + λ(s_k+1)), D1 = Σ J_k (s_k+1² − s_k²),
        D0 = Σ J_k ((1 − s_k)² − (1 − s_k+1)²) with J_k = ∂λ/∂h on piece k).
    lam1 : (m,) output, λ(h1). idx (m,) int, Ginv, work (m, m): work arrays.
    Returns the number of pieces, or −1 if the path does not end (degenerate pivoting)
    or meets a singular G_JJ.
    """
    m = h0.shape[0]
    if integral:
        for i in range(m):
            F[i] = 0.0
            for j in range(m):
                D0[i, j] = 0.0
                D1[i, j] = 0.0
    s0 = 0.0
    pieces = 0
    while True:
        pieces += 1
        if pieces > 4 * m + 8:
            return -1
        nJ = 0
        for i in range(m):
            if act[i]:
                idx[nJ] = i
                nJ += 1
        if nJ and not _inverse_sub(G, idx, nJ, Ginv, work):
            return -1
        # λ_J(s) = −Ginv h_J(s): value at s0 and slope; g(s) = h(s) + G_:J λ_J(s)
        s_next = 1.0
        leave = -1
        for a in range(nJ):
            val = 0.0
            slope = 0.0
            for b in range(nJ):
                jb = idx[b]
                val -= Ginv[a, b] * (h0[jb] + s0 * (h1[jb] - h0[jb]))
                slope -= Ginv[a, b] * (h1[jb] - h0[jb])
            lam1[idx[a]] = val  # λ at s0 (reused below)
            work[a, 0] = slope  # (work's column 0 is free once Ginv is formed)
            if slope < 0.0:
                s = s0 - val / slope if val > 0.0 else s0
                if s < s_next:
                    s_next = s
                    leave = idx[a]
        for i in range(m):
            if act[i]:
                continue
            val = h0[i] + s0 * (h1[i] - h0[i])
            slope = h1[i] - h0[i]
            for a in range(nJ):
                val += G[i, idx[a]] * lam1[idx[a]]
                slope += G[i, idx[a]] * work[a, 0]
            if slope < 0.0:
                s = s0 - val / slope if val > 0.0 else s0
                if s < s_next:
                    s_next = s
                    leave = i
        if s_next >= 1.0:
            s_next = 1.0
            leave = -1
        ds = s_next - s0
        if integral and nJ:
            for a in range(nJ):
                ia = idx[a]
                F[ia] += ds * (2.0 * lam1[ia] + ds * work[a, 0])
            c1 = s_next * s_next - s0 * s0
            c0 = (1.0 - s0) * (1.0 - s0) - (1.0 - s_next) * (1.0 - s_next)
            for a in range(nJ):
                for b in range(nJ):
                    D1[idx[a], idx[b]] -= c1 * Ginv[a, b]
                    D0[idx[a], idx[b]] -= c0 * Ginv[a, b]
        if leave < 0:
            for i in range(m):
                lam1[i] = 0.0
            for a in range(nJ):
                val = 0.0
                for b in range(nJ):
                    val -= Ginv[a, b] * h1[idx[b]]
                lam1[idx[a]] = max(val, 0.0)
            return pieces
        act[leave] = not act[leave]
        s0 = s_next


@njit(**JIT_OPTIONS)
def _lcp_jacobian(G, act, J, idx, Ginv, work):
    """J <- ∂λ/∂h = −E_J G_JJ⁻¹ E_Jᵀ (m, m) for the active set ``act``. False if singular."""
    m = act.shape[0]
    for i in range(m):
        for j in range(m):
            J[i, j] = 0.0
    nJ = 0
    for i in range(m):
        if act[i]:
            idx[nJ] = i
            nJ += 1
    if nJ and not _inverse_sub(G, idx, nJ, Ginv, work):
        return False
    for a in range(nJ):
        for b in range(nJ):
            J[idx[a], idx[b]] = -Ginv[a, b]
    return True


@njit(**JIT_OPTIONS)
def _lcp_point(G, h, act, lam, idx, Ginv, work):
    """The LCP solution at h (λ (m,) and the active set ``act``, outputs), by following
    the path from a point with every free gap positive (λ = 0 there) to h. Returns the
    number of pieces, or −1 (see :func:`_lcp_path`)."""
    m = h.shape[0]
    start = np.empty(m)
    big = 1.0
    for i in range(m):
        big = max(big, abs(h[i]))
    for i in range(m):
        start[i] = abs(h[i]) + big
        act[i] = False
    dummy = np.empty((0, 0))
    return _lcp_path(G, start, h, act, False, lam, lam, dummy, dummy, idx, Ginv, work)



def lcp_solve(G: np.ndarray, h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The solution of the LCP g = h + G λ >= 0, λ >= 0, gᵀλ = 0 for each column of ``h``.

    Parameters
    ----------
    G : ndarray, shape (m, m)
        Symmetric positive semidefinite, with G_JJ nonsingular on the active sets met.
    h : ndarray, shape (m,) or (m, n_t)

    Returns
    -------
    lam : ndarray, like ``h``
    active : ndarray of bool, like ``h``
    """
    G = np.ascontiguousarray(G, dtype=np.float64)
    H = np.asarray(h, dtype=np.float64)
    Hc = H.reshape(H.shape[0], -1)
    m, n_t = Hc.shape
    lam = np.zeros((m, n_t))
    act = np.zeros((m, n_t), dtype=bool)
    idx, Ginv, work = np.empty(m, dtype=np.int64), np.empty((m, m)), np.empty((m, m))
    a, lk = np.zeros(m, dtype=np.bool_), np.zeros(m)
    for j in range(n_t):
        if _lcp_point(G, np.ascontiguousarray(Hc[:, j]), a, lk, idx, Ginv, work) < 0:
            raise RuntimeError(f"the contact LCP has no unique solution at h = {Hc[:, j]}")
        lam[:, j], act[:, j] = lk, a
    return lam.reshape(H.shape), act.reshape(H.shape)


def lcp_enumerated(G: np.ndarray, h: np.ndarray) -> np.ndarray:
    """λ (m,) >= 0 with g = h + Gλ >= 0 and g·λ = 0 for one h (m,): exact, by active sets
    (least squares on each G_JJ, so a singular G_JJ is no obstacle), the set of the
    negative free gaps first, then every set in order of size (2^m sets at most; the
    admissible signals of :mod:`mmshbm.contact.static`)."""
    n = len(h)
    if np.all(h >= 0):
        return np.zeros(n)
    tol = 1e-10 * max(float(np.max(np.abs(h))), 1e-300)
    guess = tuple(np.flatnonzero(h < 0))
    subsets = (s for k in range(1, n + 1) for s in itertools.combinations(range(n), k))
    sets = itertools.chain([guess], (s for s in subsets if s != guess))
    for active in sets:
        idx = list(active)
        lam = np.zeros(n)
        sol = np.linalg.lstsq(G[np.ix_(idx, idx)], -h[idx], rcond=None)[0]
        if np.any(sol < -1e-10 * max(float(np.max(np.abs(sol))), 1e-300)):
            continue
        lam[idx] = np.maximum(sol, 0.0)
        g = h + G @ lam
        if np.all(g >= -tol):
            return lam
    raise ValueError("the static contact problem has no solution (conflicting stops?)")


def lcp_active_sets(G: np.ndarray, h: np.ndarray, dofs: np.ndarray) -> list:
    """The closed contacts of the LCP ``g = h + G λ >= 0, λ >= 0, gᵀλ = 0`` for each column
    of ``h`` (n_contacts, n_t), by enumeration of the active sets in order of size (the
    first feasible one; sets closing both stops of one DOF are skipped). A column no set
    solves exactly (round-off at a boundary) gets the set of least violation.
    Enumeration is meant for the few contacts of the exact reference (2^n sets)."""
    n, n_t = h.shape
    if n > 16:
        raise ValueError(f"the exact reference enumerates contact states: {n} contacts are too many (<= 16)")
    best = [None] * n_t
    violation = np.full(n_t, np.inf)
    todo = np.ones(n_t, dtype=bool)
    for size in range(n + 1):
        for J in itertools.combinations(range(n), size):
            if len({int(dofs[i]) for i in J}) < size:
                continue
            cols = np.flatnonzero(todo)
            if not len(cols):
                return best
            Jl = list(J)
            N = [i for i in range(n) if i not in J]
            H = h[:, cols]
            if size:
                try:
                    lam = -np.linalg.solve(G[np.ix_(Jl, Jl)], H[Jl])
                except np.linalg.LinAlgError:
                    continue
                g = H[N] + G[np.ix_(N, Jl)] @ lam if N else np.zeros((0, len(cols)))
            else:
                lam = np.zeros((0, len(cols)))
                g = H
            viol = np.maximum(0.0, -np.concatenate([lam, g])).max(axis=0) if n else np.zeros(len(cols))
            for k, col in enumerate(cols):
                if viol[k] == 0.0:
                    best[col] = J
                    todo[col] = False
                elif viol[k] < violation[col]:
                    violation[col] = viol[k]
                    best[col] = J
    return best
