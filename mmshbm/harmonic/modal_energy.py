"""How the kinetic energy of a periodic motion splits over linear modes and harmonics.

For a periodic motion with NLvib-ordered Fourier coefficients ``Q`` (n_dof, 2H+1) at the
fundamental frequency Ω, the period average of the kinetic energy of harmonic k is

    T_k = ¼ (kΩ)² (Q_c,kᵀ M Q_c,k + Q_s,kᵀ M Q_s,k),

and with M-orthonormal modes φ_j of the DOFs with mass (the massless DOFs carry no kinetic
energy) the modal coordinates η_j = φ_jᵀ M Q split it exactly,
T_k = Σ_j ¼ (kΩ)² (η_c,jk² + η_s,jk²), when all modes are used. The share of mode j in
harmonic k, T_jk / Σ_k T_k, names internal resonances (harmonic k of the motion
exchanging energy with mode j where kΩ ≈ ω_j), and the share of the starting mode over
all harmonics says whether a branch still belongs to its family.
"""

from __future__ import annotations

import numpy as np

__all__ = ["kinetic_energy_shares"]


def kinetic_energy_shares(Phi: np.ndarray, MQ_proj: np.ndarray | None, Q: np.ndarray, omega: float,
                          M=None) -> tuple[np.ndarray, float]:
    """Shares of the period-mean kinetic energy per mode and harmonic.

    Parameters
    ----------
    Phi : ndarray, shape (n, n_modes)
        M-orthonormal mode shapes on the same DOFs as ``Q`` (e.g. ``model.linear_modes``).
    MQ_proj : ndarray, shape (n_modes, n) or None
        ``(M Phi)ᵀ`` if precomputed (the projector onto modal coordinates); else ``M`` is
        used.
    Q : ndarray, shape (n, 2H+1)
        NLvib-ordered coefficients [Q_0, Q_c1, Q_s1, ..., Q_cH, Q_sH] (m, rad).
    omega : float
        Fundamental frequency Ω (rad/s).
    M : sparse or ndarray, shape (n, n), optional
        Mass matrix, needed when ``MQ_proj`` is None, and for the total.

    Returns
    -------
    shares : ndarray, shape (n_modes, H+1)
        T_jk / T, T the total period-mean kinetic energy (column 0 is zero). Rows sum to
        the share of each mode; with all modes the whole array sums to 1.
    total : float
        T (J).
    """
    Q = np.asarray(Q, dtype=float)
    H = (Q.shape[1] - 1) // 2
    if MQ_proj is None:
        MQ_proj = (M @ Phi).T
    eta = MQ_proj @ Q  # (n_modes, 2H+1)
    k2 = (np.arange(1, H + 1) * omega) ** 2
    modal = 0.25 * k2 * (eta[:, 1::2] ** 2 + eta[:, 2::2] ** 2)  # (n_modes, H)
    if M is not None:
        MQ = M @ Q
        quad = np.einsum("ij,ij->j", Q, MQ)
        total = float(0.25 * np.sum(k2 * (quad[1::2] + quad[2::2])))
    else:
        total = float(modal.sum())
    shares = np.zeros((Phi.shape[1], H + 1))
    if total > 0:
        shares[:, 1:] = modal / total
    return shares, total
