"""Numba kernel of the modal condensation (:mod:`mmshbm.harmonic.modal`).

One kernel, no callees in other files (numba's on-disk cache does not see edits to a
callee elsewhere); it shares :data:`~mmshbm.harmonic.kernels.JIT_OPTIONS`.
"""

from __future__ import annotations

from numba import njit

from .kernels import JIT_OPTIONS


@njit(**JIT_OPTIONS)
def _modal_dynamic_stiffness(D0, B, w2, Rs, omega, H, keep, pole_rtol, D, dD, derivative):
    """Condensed dynamic stiffness from fixed-interface modes, in place.

    For k = 0..H, with x = (kΩ)² and the P residual terms Rs[p−1] = Σ_{j>m} b_j b_jᵀ/ω_j^{2p+2},

        D_k  = D_0 − Σ_j keep[k, j] b_j b_jᵀ x / (ω_j² (ω_j² − x)) − Σ_p x^p Rs[p−1],
        dD_k = −Σ_j keep[k, j] b_j b_jᵀ 2k²Ω / (ω_j² − x)² − Σ_p 2p k^{2p} Ω^{2p−1} Rs[p−1]  (∂/∂Ω).

    D0 : (n_c, n_c); Rs : (P, n_c, n_c); B : (m, n_c), row j = b_jᵀ; w2 : (m,) = ω_j²; keep : (H+1, m)
    uint8 (0 leaves mode j out of harmonic k); D, dD : (H+1, n_c, n_c) outputs (dD is
    not touched unless ``derivative``). Returns 0, or 1 + k·m + j for the first kept
    term whose |ω_j² − x| <= pole_rtol·ω_j² (an exact pole: the outputs are then
    incomplete).
    """
    m, n_c = B.shape
    for k in range(H + 1):
        x = (k * omega) * (k * omega)
        dk = 2.0 * k * k * omega
        for a in range(n_c):
            for b in range(a, n_c):
                D[k, a, b] = D0[a, b]
                if derivative:
                    dD[k, a, b] = 0.0
        if k > 0:
            xp = 1.0
            for p in range(1, Rs.shape[0] + 1):
                dxp = 2.0 * p * xp * k * k * omega  # ∂(x^p)/∂Ω = 2p x^{p-1} k² Ω
                xp *= x
                for a in range(n_c):
                    for b in range(a, n_c):
                        D[k, a, b] -= xp * Rs[p - 1, a, b]
                        if derivative:
                            dD[k, a, b] -= dxp * Rs[p - 1, a, b]
        if k > 0:
            for j in range(m):
                if keep[k, j] == 0:
                    continue
                den = w2[j] - x
                if abs(den) <= pole_rtol * w2[j]:
                    return 1 + k * m + j
                c = x / (w2[j] * den)
                d = dk / (den * den)
                for a in range(n_c):
                    ca = c * B[j, a]
                    da = d * B[j, a]
                    for b in range(a, n_c):
                        D[k, a, b] -= ca * B[j, b]
                        if derivative:
                            dD[k, a, b] -= da * B[j, b]
        for a in range(n_c):
            for b in range(a + 1, n_c):
                D[k, b, a] = D[k, a, b]
                if derivative:
                    dD[k, b, a] = dD[k, a, b]
    return 0
