"""Poles of the condensed dynamic stiffness, removed by extra unknowns.

With the massless DOFs clamped, the structure has the M-orthonormal modes (φ_j, ω_j) and
the condensed dynamic stiffness is

    D(ω) = K_cc − K_cl S(ω)⁻¹ K_lc = K_cc − Σ_j b_j b_jᵀ / (ω_j² − ω²),   b_j = K_cl φ_j.

At ω = kΩ = ω_j it has a pole: the force D_k a_k is then a product ∞·0 (the solution has
b_jᵀa_k → 0), computed with a relative error that grows like 1/|ω_j² − (kΩ)²| (a
round-off floor of Newton's residual). For the pairs (k, j) whose pole can be met on the
branch (ω_j/k in the frequency range of the backbone) MMS-HBM keeps

    η_jk = b_jᵀ a_k / (ω_j² − (kΩ)²)

as an extra unknown with the regular equation (ω_j² − (kΩ)²) η_jk − b_jᵀ a_k = 0, and
writes the force with the regular part of D_k:

    F_k = D_k^reg a_k − Σ_j b_j η_jk,       D_k^reg = K_cc − Σ_{i not a pole of k} b_i b_iᵀ/(ω_i² − (kΩ)²),
    ∂D_k^reg/∂Ω = −2k²Ω Z_regᵀ M Z_reg,     Z_reg = S_k⁻¹ (K_lc − M Φ_P B_Pᵀ) (projected).

D_k^reg comes from one solve with S_k whose right-hand side has no component along the
pole modes (Φ_Pᵀ(K_lc − MΦ_P B_Pᵀ) = 0), so it is consistent even at the pole; the
solution's error, which grows along φ_j as S_k becomes singular, is projected out
(y ← y − Φ_P Φ_Pᵀ M y). Nothing is singular at kΩ = ω_j: the method neither fails nor
loses precision there. The motion of the DOFs with mass is q_l,k = −Z_reg a_k − Σ_j φ_j η_jk.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as la
import scipy.sparse.linalg as spla

from ....harmonic.condense import Condensation, SingularDynamicStiffness
from ....harmonic.kernels import _band_solve

__all__ = ["PoleSet"]


def groups_of_distinct_harmonics(k: np.ndarray) -> list[np.ndarray]:
    """Indices of pole pairs (harmonics ``k``, shape (n_p,)) in groups of distinct
    harmonics: the r-th pair of every harmonic in group r, groups in increasing r. Per
    group, the pairs' harmonics can be written at once without two pairs on one column."""
    rank = np.zeros(len(k), dtype=np.int64)
    seen: dict[int, int] = {}
    for p, kp in enumerate(k):
        rank[p] = seen.get(int(kp), 0)
        seen[int(kp)] = rank[p] + 1
    return [np.flatnonzero(rank == r) for r in range(int(rank.max()) + 1 if len(k) else 0)]


class PoleSet:
    """The pole pairs (harmonic k, clamped mode j) of a condensation over a frequency range.

    Parameters
    ----------
    cond : Condensation
        The condensation (banded or splu back end).
    model : Model
    harmonics : int
        H.
    omega_range : (float, float)
        Range of Ω (rad/s) the branch can reach; pairs with ω_j/k inside it (widened by
        3 %) are regularised.

    Attributes
    ----------
    pairs : list of (k, j)
        Harmonic k >= 1 and clamped mode index j (0-based) of each extra unknown η.
    omega2 : ndarray, shape (n_p,)
        ω_j² per pair.
    b : ndarray, shape (n_p, n_c)
        b_j = K_cl φ_j per pair.
    """

    def __init__(self, cond: Condensation, model, harmonics: int, omega_range: tuple[float, float]):
        self.cond = cond
        self.H = int(harmonics)
        lo, hi = float(omega_range[0]) * 0.97, float(omega_range[1]) * 1.03
        # the modal back end (mmshbm.harmonic.modal) has its modes and leaves a term out itself
        self.modal = cond.backend == "modal"
        if self.modal:
            w, phi = np.asarray(cond.omega_j, dtype=float), np.asarray(cond.phi_j, dtype=float)
        else:
            w, phi = _clamped_modes(model, cond, self.H * hi)
        pairs = [(k, j) for k in range(1, self.H + 1) for j in range(len(w)) if lo <= w[j] / k <= hi]
        self.pairs = pairs
        self.n = len(pairs)
        self.modes_w = w
        self.phi = phi  # (n_l, n_modes): RCM order (banded, splu) or model.l order (modal)
        self.omega2 = np.array([w[j] ** 2 for _, j in pairs])
        self.k = np.array([k for k, _ in pairs], dtype=np.int64)
        B = np.asarray(cond.b_j, dtype=float).T if self.modal else cond.K_lc.T @ phi  # (n_c, n_modes)
        self.B = B
        self.b = np.ascontiguousarray(np.array([B[:, j] for _, j in pairs]).reshape(self.n, cond.n_c))
        self._by_k = {}
        for k, j in pairs:
            self._by_k.setdefault(k, []).append(j)
        self._j = np.array([j for _, j in pairs], dtype=np.int64)
        self.groups = groups_of_distinct_harmonics(self.k)

    # ------------------------------------------------------------------ condensation
    def _solve(self, w2: float, rhs: np.ndarray) -> np.ndarray:
        c = self.cond
        if c.backend == "banded":
            X = np.empty_like(rhs)
            info = _band_solve(c._Kb, c._Mb, c.half_band, w2, np.ascontiguousarray(rhs), c._AB, X)
            if info:  # an exact zero pivot: move off the pole by one part in 1e14
                info = _band_solve(c._Kb, c._Mb, c.half_band, w2 * (1 + 1e-14), np.ascontiguousarray(rhs),
                                   c._AB, X)
                if info:
                    raise SingularDynamicStiffness(f"K_ll - {w2:.6g} M_ll is singular")
            return X
        c._S.data = c._K_data - w2 * c._M_data
        try:
            return spla.splu(c._S, permc_spec="NATURAL").solve(rhs)
        except RuntimeError as err:
            raise SingularDynamicStiffness(f"K_ll - {w2:.6g} M_ll is singular: {err}") from None

    def _z_regular(self, k: int, omega: float) -> np.ndarray:
        """Z_reg of harmonic k (RCM order), shape (n_l, n_c)."""
        c = self.cond
        js = self._by_k.get(k, [])
        if not js:
            return self._solve((k * omega) ** 2, c.K_lc)
        Phi = self.phi[:, js]
        MPhi = c.M_ll @ Phi
        rhs = c.K_lc - MPhi @ self.B[:, js].T
        y = self._solve((k * omega) ** 2, rhs)
        return y - Phi @ (MPhi.T @ y)

    def dynamic_stiffness(self, omega: float, derivative: bool = True):
        """Regular parts D_k^reg and ∂D_k^reg/∂Ω, k = 0..H, shape (H+1, n_c, n_c) each (dD
        None unless ``derivative``)."""
        c = self.cond
        H = self.H
        if self.modal:  # its regular part lacks the static b_j b_jᵀ/ω_j² of the pole modes
            out = c.dynamic_stiffness(omega, H, derivative=derivative, exclude=self.pairs)
            D, dD = out if derivative else (out, None)
            for p, (k, _) in enumerate(self.pairs):
                D[k] += np.outer(self.b[p], self.b[p]) / self.omega2[p]
            return D, dD
        try:
            out = c.dynamic_stiffness(omega, H, derivative=derivative)
            D, dD = out if derivative else (out, None)
        except SingularDynamicStiffness:
            D = np.empty((H + 1, c.n_c, c.n_c))
            dD = np.zeros_like(D) if derivative else None
            D[0] = c.D0
            for k in range(1, H + 1):
                if k not in self._by_k:
                    Z = self._z_regular(k, omega)
                    D[k] = c.K_cc - c.K_lc.T @ Z
                    if derivative:
                        dD[k] = -2.0 * k * k * omega * (Z.T @ (c.M_ll @ Z))
        for k in self._by_k:
            Z = self._z_regular(k, omega)
            D[k] = c.K_cc - c.K_lc.T @ Z
            if derivative:
                dD[k] = -2.0 * k * k * omega * (Z.T @ (c.M_ll @ Z))
        return D, dD

    def recover(self, omega: float, Qc: np.ndarray, eta: np.ndarray) -> np.ndarray:
        """Coefficients (n_l, 2H+1) of the DOFs with mass (``model.l`` order) from the cosine
        and sine coefficients of the massless DOFs (NLvib order, (n_c, 2H+1)) and η (n_p,)
        of the cosine part: q_l,k = −Z_reg a_k − Σ_j φ_j η_jk."""
        c = self.cond
        Qc = np.asarray(Qc, dtype=float)
        H = (Qc.shape[1] - 1) // 2
        if self.modal:  # q_l,k = −Z_excl a_k − φ_j η_jk (kΩ)²/ω_j²
            Ql = c.recover(omega, Qc, exclude=self.pairs)
            # (kΩ)² as a scalar power per pair (an array's square may round differently)
            k_omega2 = np.array([(k * omega) ** 2 for k, _ in self.pairs])
            for g in self.groups:  # distinct harmonics in a group; each column's pairs in order
                Ql[:, 2 * self.k[g] - 1] -= self.phi[:, self._j[g]] * eta[g] * k_omega2[g] / self.omega2[g]
            return Ql
        Ql = np.empty((c.n_l, 2 * H + 1))
        Ql[c.perm, 0] = -c._Z0 @ Qc[:, 0]
        for k in range(1, H + 1):
            Z = self._z_regular(k, omega)
            cos_part = -Z @ Qc[:, 2 * k - 1]
            for p, (kp, j) in enumerate(self.pairs):
                if kp == k:
                    cos_part -= self.phi[:, j] * eta[p]
            Ql[c.perm, 2 * k - 1] = cos_part
            Ql[c.perm, 2 * k] = -Z @ Qc[:, 2 * k]
        return Ql


def _clamped_modes(model, cond: Condensation, omega_max: float):
    """(ω_j rad/s ascending, φ_j M-orthonormal in the condensation's RCM order) of the
    structure with its massless DOFs clamped, every mode up to ``omega_max``."""
    b = model.blocks
    n_l = cond.n_l
    if n_l <= 600:
        w2, phi = la.eigh(b["K_ll"].toarray(), b["M_ll"].toarray())
    else:
        n = 8
        while True:
            w2, phi = spla.eigsh(b["K_ll"], k=min(n, n_l - 2), M=b["M_ll"], sigma=0.0, which="LM",
                                 v0=np.ones(n_l))
            order = np.argsort(w2)
            w2, phi = w2[order], phi[:, order]
            if w2[-1] > omega_max**2 or n >= min(64, n_l - 2):
                break
            n *= 2
    w = np.sqrt(np.maximum(w2, 0.0))
    keep = w <= omega_max
    return w[keep], np.ascontiguousarray(phi[:, keep][cond.perm])
