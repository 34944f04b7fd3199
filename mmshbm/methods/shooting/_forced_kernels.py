"""Numba kernel of the forced shooting baseline (:mod:`mmshbm.methods.shooting.forced`).

The step is the trapezoidal rule with the contact force averaged along the step (AVF) of
:mod:`mmshbm.methods.shooting._kernels`, extended by damping and a harmonic force, in the
modal coordinates of the open-contact structure (M = I, K_open = Λ):

    S η₁ = P η₀ + (4/h) ν₀ + F(h₀, h₁) â + g_k,      ν₁ = (2/h)(η₁ − η₀) − ν₀,
    S = (4/h²) I + (2/h) Γ + Λ,   P = (4/h²) I + (2/h) Γ − Λ,   g_k = f(t_k) + f(t_k+1),

with Γ = Φᵀ C Φ (diagonal for modal or Rayleigh damping), â = Φᵀ a the contact direction
and F the AVF force sum of the free gap h = gap + â·η (``_force_sum`` and ``_contact_root``
of the conservative shooting kernels). S⁻¹ is passed as a dense matrix (diagonal when Γ
is).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...harmonic.kernels import JIT_OPTIONS
from ._kernels import _contact_root, _force_sum, _start_gap

__all__: list[str] = []


@njit(**JIT_OPTIONS)
def _apply(A, diag, x, out):
    """out = A x (A dense (n, n), or its diagonal in A[0] when diag)."""
    n = x.shape[0]
    if diag:
        for i in range(n):
            out[i] = A[0, i] * x[i]
    else:
        for i in range(n):
            s = 0.0
            for j in range(n):
                s += A[i, j] * x[j]
            out[i] = s


@njit(**JIT_OPTIONS)
def _forced_integrate(Sinv, P, Gam, diag, a, z, alpha, kc, gap, h, dh, G, dG, q, v, dq, dv, Q, V, LAM):
    """Integrate len(G) − 1 steps of size h in place (modal coordinates, see the module).

    Sinv, P, Gam : (n, n) dense, or (1, n) diagonals when ``diag``: S⁻¹, P and Γ.
    a, z : (n,) contact direction â and S⁻¹ â; alpha = â·z.
    dh : (m,) ∂h/∂parameter per tangent column.
    G : (N+1, n) the force samples f(t_k) (modal); dG : (m,) the factor ∂ log σ/∂parameter
        per column (the force scales with σ(Ω)).
    q, v : (n,) the state, overwritten; dq, dv : (n, m) tangents, in place.
    Q, V : (N+1, n), LAM : (N+1,): states and contact force at every step if Q has rows.
    """
    n = q.shape[0]
    m = dq.shape[1]
    steps = G.shape[0] - 1
    store = Q.shape[0] > 0
    y = np.empty(n)
    w = np.empty(n)
    t = np.empty(n)
    qn = np.empty(n)
    W = np.empty(n)
    Y = np.empty(n)
    Tt = np.empty(n)
    ak = alpha * kc
    h0 = _start_gap(a, q, v, gap, kc, Q, V, LAM)
    c1 = 4.0 / (h * h)
    c2 = 4.0 / h
    c3 = 8.0 / (h * h * h)
    c5 = 2.0 / h
    c6 = 2.0 / (h * h)
    for k in range(steps):
        # y = S⁻¹ (P q + (4/h) v + g)
        _apply(P, diag, q, w)
        for i in range(n):
            w[i] += c2 * v[i] + G[k, i] + G[k + 1, i]
        _apply(Sinv, diag, w, y)
        hy = gap
        for i in range(n):
            hy += a[i] * y[i]
        h1 = _contact_root(h0, hy, ak, True)
        F, F0, F1 = _force_sum(h0, h1, kc, True)
        for i in range(n):
            qn[i] = y[i] + F * z[i]
        sm = F1 / (1.0 - F1 * alpha)
        for col in range(m):
            e = dh[col]
            # W = P dq + (4/h) dv + e[(8/h³ + 2/h² Γ)(q1 − q0) − (4/h²) v0] + F0 (â·dq) â + dlogσ g
            for i in range(n):
                Tt[i] = dq[i, col]
            _apply(P, diag, Tt, W)
            for i in range(n):
                t[i] = qn[i] - q[i]
            _apply(Gam, diag, t, Y)
            ad = 0.0
            for i in range(n):
                ad += a[i] * dq[i, col]
            for i in range(n):
                W[i] += (c2 * dv[i, col] + e * (c3 * t[i] + c6 * Y[i] - c1 * v[i]) + F0 * ad * a[i]
                         + dG[col] * (G[k, i] + G[k + 1, i]))
            _apply(Sinv, diag, W, Y)
            ay = 0.0
            for i in range(n):
                ay += a[i] * Y[i]
            for i in range(n):
                Y[i] += sm * ay * z[i]
            for i in range(n):
                dv[i, col] = c5 * (Y[i] - dq[i, col]) - dv[i, col] - e * c6 * t[i]
                dq[i, col] = Y[i]
        for i in range(n):
            v[i] = c5 * (qn[i] - q[i]) - v[i]
            q[i] = qn[i]
        h0 = h1
        if store:
            for i in range(n):
                Q[k + 1, i] = q[i]
                V[k + 1, i] = v[i]
            LAM[k + 1] = kc * max(0.0, -h1)
    return 0
