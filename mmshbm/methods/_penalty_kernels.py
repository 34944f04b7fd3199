"""Numba kernels of the penalty harmonic-balance baseline (:mod:`mmshbm.methods.penalty_hbm`).

They take plain contiguous float64/int64 arrays and know nothing of models. Neither calls
another kernel, so they can live apart from :mod:`mmshbm.core.kernels` without defeating
numba's on-disk cache; they share its compilation flags (``JIT_OPTIONS``).
"""

from __future__ import annotations

from numba import njit

from ..core.kernels import JIT_OPTIONS

__all__: list[str] = []


@njit(**JIT_OPTIONS)
def _penalty_contact(q, gap, side, kp, lam, active):
    """In place: g_j = gap − side·q_j, λ_j = kp·max(0, −g_j), active_j = (g_j < 0).

    q : (N,) contact DOF samples (m); lam, active : (N,) outputs (N, 0/1).
    """
    for j in range(q.shape[0]):
        g = gap - side * q[j]
        if g < 0.0:
            lam[j] = -kp * g
            active[j] = 1.0
        else:
            lam[j] = 0.0
            active[j] = 0.0


@njit(**JIT_OPTIONS)
def _penalty_hbm_jacobian(K_data, M_data, omega, kp, P, MQ, block_pos, coupling_pos, omega_rows,
                          omega_pos, scale, data):
    """CSR data of the scaled penalty-HBM Jacobian, in place (the pattern is fixed).

    K_data, M_data : (nnz_A,) K and M on the union pattern A of one harmonic block
    omega, kp      : Ω (rad/s) and the penalty stiffness (N/m)
    P              : (H+1, H+1) cosine product matrix of the active set
    MQ             : (H+1, n) M Q_k per harmonic
    block_pos      : (H+1, nnz_A) CSR position of block k's entry e
    coupling_pos   : (H+1, H+1) CSR position of (row m·n + cd, column k·n + cd)
    omega_rows     : (n_l,) the DOFs with mass (rows of the Ω column)
    omega_pos      : (H, n_l) CSR position of (row k·n + omega_rows[r], Ω column), k = 1..H
    scale          : (nnz,) column scale / row scale of every entry
    data           : (nnz,) output
    """
    H1 = P.shape[0]
    for k in range(H1):
        w2 = (k * omega) * (k * omega)
        for e in range(K_data.shape[0]):
            data[block_pos[k, e]] = K_data[e] - w2 * M_data[e]
    for m in range(H1):
        for k in range(H1):
            if m == k:  # on the diagonal of block k: adds to K − (kΩ)² M
                data[coupling_pos[m, k]] += kp * P[m, k]
            else:
                data[coupling_pos[m, k]] = kp * P[m, k]
    for k in range(1, H1):
        factor = -2.0 * k * k * omega
        for r in range(omega_rows.shape[0]):
            data[omega_pos[k - 1, r]] = factor * MQ[k, omega_rows[r]]
    for e in range(data.shape[0]):
        data[e] *= scale[e]
