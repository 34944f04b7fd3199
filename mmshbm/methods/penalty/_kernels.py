"""Numba kernels of the penalty harmonic-balance baseline (:mod:`mmshbm.methods.penalty.hbm`).

They take plain contiguous float64/int64 arrays and know nothing of models. Neither calls
another kernel, so they can live apart from :mod:`mmshbm.harmonic.kernels` without defeating
numba's on-disk cache; they share its compilation flags (``JIT_OPTIONS``).
"""

from __future__ import annotations

from numba import njit

from ...harmonic.kernels import JIT_OPTIONS

__all__: list[str] = []


@njit(**JIT_OPTIONS)
def _penalty_contacts(q, slot, gap, side, kp, kp_ref, force, active):
    """Penalty forces of several contacts on the samples of their DOFs, in place.

    For contact i on the DOF in row ``slot[i]`` of ``q``: g_j = gap_i − side_i·q_j,
    λ_j = kp_i·max(0, −g_j). Outputs per distinct DOF d (rows of ``q``):

    force[d, j]  = Σ_{i on d} side_i λ_j         (N; what the residual's row d gets)
    active[d, j] = Σ_{i on d} (kp_i / kp_ref[d]) [g_j < 0]

    q : (n_d, N) samples of the distinct contact DOFs (m)
    slot : (n_ct,) int; gap, side, kp : (n_ct,); kp_ref : (n_d,) the factor the Jacobian
    kernel multiplies ``active``'s cosine product matrix by
    force, active : (n_d, N) outputs
    """
    n_d, N = q.shape
    for d in range(n_d):
        for j in range(N):
            force[d, j] = 0.0
            active[d, j] = 0.0
    for i in range(slot.shape[0]):
        d = slot[i]
        s = side[i]
        ratio = kp[i] / kp_ref[d]
        for j in range(N):
            g = gap[i] - s * q[d, j]
            if g < 0.0:
                force[d, j] += s * (-kp[i] * g)
                active[d, j] += ratio


@njit(**JIT_OPTIONS)
def _penalty_hbm_jacobian(K_data, M_data, omega, kp_ref, P, MQ, block_pos, coupling_pos, omega_rows,
                          omega_pos, scale, data):
    """CSR data of the scaled penalty-HBM Jacobian, in place (the pattern is fixed).

    K_data, M_data : (nnz_A,) K and M on the union pattern A of one harmonic block
    omega          : Ω (rad/s)
    kp_ref         : (n_d,) penalty stiffness factor of each distinct contact DOF (N/m)
    P              : (n_d, H+1, H+1) cosine product matrices of the (weighted) active sets
    MQ             : (H+1, n) M Q_k per harmonic
    block_pos      : (H+1, nnz_A) CSR position of block k's entry e
    coupling_pos   : (n_d, H+1, H+1) CSR position of (row m·n + d, column k·n + d)
    omega_rows     : (n_l,) the DOFs with mass (rows of the Ω column)
    omega_pos      : (H, n_l) CSR position of (row k·n + omega_rows[r], Ω column), k = 1..H
    scale          : (nnz,) column scale / row scale of every entry
    data           : (nnz,) output
    """
    H1 = P.shape[1]
    for k in range(H1):
        w2 = (k * omega) * (k * omega)
        for e in range(K_data.shape[0]):
            data[block_pos[k, e]] = K_data[e] - w2 * M_data[e]
    for d in range(P.shape[0]):
        kp = kp_ref[d]
        for m in range(H1):
            for k in range(H1):
                if m == k:  # on the diagonal of block k: adds to K − (kΩ)² M
                    data[coupling_pos[d, m, k]] += kp * P[d, m, k]
                else:
                    data[coupling_pos[d, m, k]] = kp * P[d, m, k]
    for k in range(1, H1):
        factor = -2.0 * k * k * omega
        for r in range(omega_rows.shape[0]):
            data[omega_pos[k - 1, r]] = factor * MQ[k, omega_rows[r]]
    for e in range(data.shape[0]):
        data[e] *= scale[e]
