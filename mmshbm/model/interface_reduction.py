"""Reduction of a large structure onto its massless interface DOFs and one output DOF.

A structure with DOFs with mass l (n_l, large: an FE mesh) and massless interface DOFs c
(n_c: the slip DOFs of contact pairs, hundreds to thousands) is reduced to

    DOFs [t, η_1 .. η_m, c]:   t the output DOF (the tip), η generalised coordinates,

with the interface DOFs kept exactly (massless: MMS-HBM condenses onto them) and

    q_l = V η̄ + Ψ_res q_c,     η̄ = (t, η),

V (n_l × (m + 1)) a Ritz basis of the DOFs with mass and Ψ_res q_c the quasi-static rest
(residual flexibility: its inertia neglected). The reduced matrices

    K_ll' = Vᵀ K_ll V,  M' = Vᵀ M_ll V,  K_lc' = Vᵀ K_lc,
    K_cc' = D_0 + K_lc'ᵀ K_ll'⁻¹ K_lc',   D_0 = K_cc − K_cl K_ll⁻¹ K_lc (exact),

keep the static condensation onto the interface exact: the reduced model's interface
flexibility at Ω = 0 is the full model's (D_0 whatever V is), and only the inertia of the
part of the motion outside span V is lost. The basis holds

* the static response to a unit output load with the interface held (w_t = K_ll⁻¹ e_t
  scaled to w_t[t] = 1): the static response to a load at t is exact, and t is the
  physical output DOF (e_tᵀ Ψ_res = 0, because K_ll⁻¹ e_t ∈ span V);
* the ``n_modes`` lowest modes of the DOFs with mass with the interface held
  (K_ll φ = ω² M_ll φ: for contact pairs, the bonded structure), less their output
  component (span{w_t, φ} unchanged, the other columns zero at t);
* ``n_interface`` interface modes: the static interface shapes Ψ X_i (Ψ = −K_ll⁻¹ K_lc)
  of the largest kinetic energy per strain energy, the eigenvectors of
  ΨᵀM_llΨ X = μ D_0 X with the largest μ (the motion the interface's slip drives: a plate
  sliding on a frictionless joint moves as a rigid body through these shapes).

Cost: one sparse LU of K_ll, ARPACK in shift-invert about 0 (n_modes), n_c solves with
the factor (D_0 and the interface pencil, by blocks) and n_interface more; memory n_l × n_c
float32 numbers for Ψ while the pencil is formed.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["InterfaceReduction", "reduce_to_interface"]

log = logging.getLogger(__name__)

#: columns of K_lc solved per block
_BLOCK = 256


@dataclass(frozen=True, eq=False)
class InterfaceReduction:
    """The reduced matrices and the basis (module docstring).

    Attributes
    ----------
    M, K : ndarray, shape (m + 1 + n_c, m + 1 + n_c)
        Reduced mass and stiffness over [t, η, c] (M zero on c).
    basis : ndarray, shape (n_l, m + 1)
        V (the first column w_t, V[t] = e_0).
    residual : ndarray, shape (n_l, n_c) or None
        Ψ_res (kept only when asked: n_l × n_c numbers).
    frequencies : ndarray, shape (n_modes,)
        Frequencies (Hz) of the modes with the interface held.
    """

    M: np.ndarray
    K: np.ndarray
    basis: np.ndarray
    residual: np.ndarray | None
    frequencies: np.ndarray

    @property
    def n_reduced(self) -> int:
        """DOFs with mass of the reduced model (m + 1)."""
        return self.basis.shape[1]

    def load(self, f_l: np.ndarray) -> np.ndarray:
        """Reduced load (m + 1 + n_c,) of a load ``f_l`` (n_l,) on the DOFs with mass
        (Vᵀ f_l; zero on the interface DOFs, which carry no load)."""
        out = np.zeros(self.K.shape[0], dtype=np.result_type(f_l, float))
        out[:self.n_reduced] = self.basis.T @ f_l
        return out


def reduce_to_interface(M_ll, K_ll, K_lc, K_cc, output: int, n_modes: int = 10, n_interface: int = 12,
                        keep_residual: bool = False) -> InterfaceReduction:
    """Reduce onto the interface DOFs c and the output DOF (module docstring).

    Parameters
    ----------
    M_ll, K_ll : sparse (n_l, n_l)
        Mass and stiffness of the DOFs with mass (K_ll positive definite: the structure
        is held by the interface).
    K_lc : sparse (n_l, n_c)
    K_cc : sparse or ndarray (n_c, n_c)
    output : int
        Index into l of the output DOF t.
    n_modes : int
        Modes with the interface held (>= 1).
    n_interface : int
        Interface modes (>= 0, at most n_c).
    keep_residual : bool
        Keep Ψ_res (to recover the DOFs with mass from an interface motion).

    Raises
    ------
    ValueError
        Sizes that do not match, an output index out of range, n_modes >= n_l − 1.
    """
    K_ll = sp.csc_matrix(K_ll)
    M_ll = sp.csr_matrix(M_ll)
    K_lc = sp.csc_matrix(K_lc)
    n_l, n_c = K_lc.shape
    if K_ll.shape != (n_l, n_l) or M_ll.shape != (n_l, n_l) or np.shape(K_cc) != (n_c, n_c):
        raise ValueError(f"block sizes do not match: K_ll {K_ll.shape}, M_ll {M_ll.shape}, "
                         f"K_lc {K_lc.shape}, K_cc {np.shape(K_cc)}")
    if not 0 <= int(output) < n_l:
        raise ValueError(f"output must index a DOF with mass in [0, {n_l - 1}], got {output}")
    if not 1 <= n_modes < n_l - 1:
        raise ValueError(f"n_modes must be in [1, {n_l - 2}], got {n_modes}")
    if isinstance(n_interface, bool) or not isinstance(n_interface, int | np.integer) or n_interface < 0:
        raise ValueError(f"n_interface must be an integer >= 0, got {n_interface!r}")
    n_interface = min(int(n_interface), n_c)
    lu = spla.splu(K_ll, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                   options={"SymmetricMode": True})
    op = spla.LinearOperator((n_l, n_l), matvec=lu.solve, dtype=float)
    # a fixed start vector: ARPACK's default is drawn from a generator that advances with
    # every call in the process, so two builds would differ in round-off (and the Ritz
    # basis below in its rotation), and so would the steps of a continuation on them
    v0 = np.linspace(1.0, 2.0, n_l)
    w2, phi = spla.eigsh(K_ll, k=n_modes, M=M_ll, sigma=0.0, OPinv=op, which="LM", v0=v0)
    order = np.argsort(w2)
    w2, phi = w2[order], phi[:, order]
    e_t = np.zeros(n_l)
    e_t[output] = 1.0
    w_t = lu.solve(e_t)
    w_t /= w_t[output]
    # D_0 and the interface pencil, by blocks of interface DOFs
    K_cc = K_cc.toarray() if sp.issparse(K_cc) else np.asarray(K_cc, dtype=float)
    D0 = np.array(K_cc, dtype=float)
    Z = np.empty((n_l, n_c), dtype=np.float32) if n_interface else None
    for s in range(0, n_c, _BLOCK):
        cols = slice(s, min(s + _BLOCK, n_c))
        Zb = lu.solve(K_lc[:, cols].toarray())  # K_ll⁻¹ K_lc, so Ψ = −Zb
        D0[:, cols] -= (K_lc.T @ Zb)
        if Z is not None:
            Z[:, cols] = Zb
    D0 = 0.5 * (D0 + D0.T)
    columns = [phi - np.outer(w_t, phi[output])]
    if n_interface:
        MZ = (M_ll @ Z).astype(np.float32)
        Mbb = (Z.T @ MZ).astype(float)
        del MZ, Z
        Mbb = 0.5 * (Mbb + Mbb.T)
        _, X = la.eigh(Mbb, D0, subset_by_index=[n_c - n_interface, n_c - 1])
        psi = lu.solve(np.asarray(K_lc @ X))
        columns.append(psi - np.outer(w_t, psi[output]))
    Q = np.hstack(columns)
    # M-orthonormal columns (zero at the output), those that add nothing dropped
    G = Q.T @ (M_ll @ Q)
    g, U = la.eigh(0.5 * (G + G.T))
    keep = g > 1e-12 * g.max()
    Q = Q @ (U[:, keep] / np.sqrt(g[keep]))
    Kq = Q.T @ (K_ll @ Q)
    lam, U = la.eigh(0.5 * (Kq + Kq.T))  # the Ritz modes: K' diagonal in them
    Q = Q @ U
    V = np.hstack([w_t[:, None], Q])
    Kr = V.T @ (K_ll @ V)
    Mr = V.T @ (M_ll @ V)
    Klc_r = np.asarray((K_lc.T @ V).T)
    Kcc_r = D0 + Klc_r.T @ la.solve(Kr, Klc_r, assume_a="pos")
    n_r = V.shape[1]
    K = np.zeros((n_r + n_c, n_r + n_c))
    K[:n_r, :n_r], K[:n_r, n_r:], K[n_r:, :n_r], K[n_r:, n_r:] = Kr, Klc_r, Klc_r.T, Kcc_r
    K = 0.5 * (K + K.T)
    M = np.zeros_like(K)
    M[:n_r, :n_r] = 0.5 * (Mr + Mr.T)
    residual = None
    if keep_residual:
        full = -lu.solve(K_lc.toarray())
        residual = full + V @ la.solve(Kr, Klc_r)
    log.info("interface reduction: %d DOFs with mass, %d interface DOFs -> %d + %d", n_l, n_c, n_r, n_c)
    return InterfaceReduction(M, K, V, residual, np.sqrt(np.maximum(w2, 0.0)) / (2 * np.pi))
