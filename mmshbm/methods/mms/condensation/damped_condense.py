"""Complex condensation of a damped structure onto its massless DOFs, per harmonic.

For the motion q(τ) = Re Σ_k Q̂_k e^{ikτ} (τ = Ω t; NLvib's coefficients give
Q̂_k = c_k − i s_k) the DOFs with mass obey, harmonic by harmonic,

    S_k Q̂_l,k + K_lc Q̂_c,k = B̂_k,     S_k(Ω, ξ) = K_ll + ikΩ (C_ll − ξ M_ll) − (kΩ)² M_ll,

with B̂_k the external force on them (here on the first harmonic only). ξ is the
negative mass-proportional damping of the extended periodic motion concept (EPMC,
Krack 2015); 0 for a forced response. So

    Q̂_l,k = Y_k − Z_k Q̂_c,k,      Z_k = S_k⁻¹ K_lc,   Y_k = S_k⁻¹ B̂_k,

and the force the structure needs at the massless DOFs, f_c = K_cl q_l + K_cc q_c, is

    f̂_c,k = D_k Q̂_c,k − P̂_k,      D_k = K_cc − K_cl Z_k,      P̂_k = −K_cl Y_k = −Z_kᵀ B̂_k

(S_k is complex *symmetric*, so K_cl S_k⁻¹ = Z_kᵀ with the plain transpose). P̂_k is the
external load condensed onto the massless DOFs. With ∂S_k/∂Ω = ik(C_ll − ξM_ll) −
2k²Ω M_ll and ∂S_k/∂ξ = −ikΩ M_ll (from ∂(S⁻¹) = −S⁻¹ ∂S S⁻¹):

    ∂D_k/∂Ω = Z_kᵀ (∂S_k/∂Ω) Z_k,   ∂P̂_k/∂Ω = Z_kᵀ (∂S_k/∂Ω) Y_k,   and the same in ξ.

Without damping and with ξ = 0 this is :class:`mmshbm.harmonic.condense.Condensation`'s D_k.

Two back ends, identical in exact arithmetic (tests compare them):

``"modal"`` (default when C is diagonal in the open-contact modes, as the damping of
    ``Model.with_damping`` is, the model has at most :data:`DENSE_LIMIT` DOFs with mass
    and the modal evaluation costs fewer operations than the direct one, see
    :func:`modal_is_cheaper`). With all n_l mass-normalised open modes φ_j (massless entries following
    statically), γ_j = φ_jᵀ C φ_j − ξ and d_j(ω) = 1/(ω_j² − ω² + iωγ_j), the receptance
    of the whole model is exactly

        H(ω) = (K + iωC − ω²M)⁻¹ = Σ_j φ_j φ_jᵀ d_j(ω) + E_c K_cc⁻¹ E_cᵀ

    (multiply by K − ω²M + iωC: Φ_lΦ_lᵀ = M_ll⁻¹ and φ_c = −K_cc⁻¹K_cl φ_l give the
    identity). By the Schur complement D_k = H_cc(kΩ)⁻¹, and P̂_1 = D_1 H_cl(Ω) B̂ (the
    force f needed for Q̂_c given the load). Where a harmonic sits on an open mode d_j
    blows up (the linear EPMC sits exactly there: γ_1 = 0), so the mode j nearest kΩ is
    taken out of the sum by a rank-one (Woodbury) update, which stays regular:
    D_k = B − (Bφ)(Bφ)ᵀ/g with A = K_cc⁻¹ + Σ_{m≠j} φ_m d_m φ_mᵀ, B = A⁻¹, φ = φ_c,j and
    g = 1/d_j + φᵀBφ. Cost O(n_l n_c²) per harmonic; derivatives from
    ∂(1/d_j)/∂Ω = k(−2ω + iγ_j), ∂(1/d_j)/∂ξ = −iω.
``"direct"`` (any C): S_k factored per harmonic; dense (batched LAPACK) up to
    :data:`DENSE_LIMIT` DOFs with mass, SuperLU above.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ....harmonic.condense import SingularDynamicStiffness
from ....model.model import Model
from ._damped_modal_kernels import _damped_modal

__all__ = ["DampedCondensation", "CondensedHarmonics", "DENSE_LIMIT", "modal_is_cheaper"]

#: largest number of DOFs with mass solved densely (modal back end, dense direct solves)
DENSE_LIMIT = 400
#: C counts as modal when its off-diagonal modal entries are below this share of the diagonal
_MODAL_RTOL = 1e-7


def modal_is_cheaper(n_l: int, n_c: int, damped: bool) -> bool:
    """Whether one evaluation (D_k and ∂D_k/∂Ω, one harmonic) costs fewer complex
    multiply-adds with the modal back end than with the dense direct one.

    Counted from the two evaluations (leading terms, n_m = n_l open modes):

    * modal: A = K_cc⁻¹ + Σ_m φ_m d_m φ_mᵀ (n_l n_c²), its inverse by Gauss–Jordan (n_c³),
      ∂A the same sum (n_l n_c²) and ∂B = −B ∂A B (2 n_c³): 2 n_l n_c² + 3 n_c³;
    * direct: the LU of S_k (n_l³/3), the solves for the n_c columns of K_lc (2 n_l² n_c),
      D_k = K_cc − K_lcᵀ Z_k (n_l n_c²), M Z_k and Z_kᵀ M Z_k (n_l² n_c + n_l n_c²), and
      with damping C Z_k and Z_kᵀ C Z_k once more:
      n_l³/3 + (3 + δ) n_l² n_c + (2 + δ) n_l n_c², δ = 1 damped, else 0.

    The modal back end's n_c³ terms grow with the massless DOFs it solves per frequency,
    the direct one's with the DOFs with mass: in r = n_c / n_l the modal one is cheaper
    for 3 r³ − δ r² − (3 + δ) r − 1/3 < 0, i.e. up to n_c ≈ 1.37 n_l damped (1.06 n_l
    undamped). A structure with a few contacts (the beam: n_c = 2, n_l = 40) keeps the
    modal back end, an interface model (a lap joint's 21 DOFs with mass and hundreds of
    slip DOFs) takes the direct one.
    """
    n_l, n_c, delta = float(n_l), float(n_c), 1.0 if damped else 0.0
    modal = 2.0 * n_l * n_c**2 + 3.0 * n_c**3
    direct = n_l**3 / 3.0 + (3.0 + delta) * n_l**2 * n_c + (2.0 + delta) * n_l * n_c**2
    return modal <= direct


@dataclass(frozen=True, eq=False)
class CondensedHarmonics:
    """The condensation at one (Ω, ξ), harmonics k = 0..H.

    Attributes
    ----------
    omega, xi : float
        Ω (rad/s) and ξ (1/s).
    D : ndarray, complex, shape (H+1, n_c, n_c)
        D_k (N/m, N·m/rad).
    dD_domega, dD_dxi : ndarray, complex, shape (H+1, n_c, n_c), or None
        ∂D_k/∂Ω (N·s/m) and ∂D_k/∂ξ; None unless asked.
    P : ndarray, complex, shape (n_c, m)
        P̂_1 = −K_cl S_1⁻¹ B for the condensation's right-hand sides B (n_l, m).
    dP_domega, dP_dxi : ndarray, complex, shape (n_c, m), or None
    Z : ndarray, complex, shape (H+1, n_l, n_c), or None
        S_k⁻¹ K_lc (``model.l`` order), when recovery was asked.
    Y : ndarray, complex, shape (n_l, m), or None
        S_1⁻¹ B, when recovery was asked.
    """

    omega: float
    xi: float
    D: np.ndarray
    dD_domega: np.ndarray | None
    dD_dxi: np.ndarray | None
    P: np.ndarray
    dP_domega: np.ndarray | None
    dP_dxi: np.ndarray | None
    Z: np.ndarray | None
    Y: np.ndarray | None


class DampedCondensation:
    """Per-harmonic complex condensation of a (damped) :class:`Model`.

    Parameters
    ----------
    model : Model
        The structure (damping optional: ``model.blocks["C_ll"]``).
    rhs : ndarray, shape (n_l, m), optional
        Loads on the DOFs with mass (``model.l`` order) at the first harmonic, complex
        allowed; their condensed loads P̂ are computed at every evaluation.
    backend : {"auto", "modal", "direct"}
        ``"auto"``: modal when C is diagonal in the open modes, n_l <= DENSE_LIMIT and
        :func:`modal_is_cheaper`; else direct.
    """

    def __init__(self, model: Model, rhs: np.ndarray | None = None, backend: str = "auto"):
        if not isinstance(model, Model):
            raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
        if backend not in ("auto", "modal", "direct"):
            raise ValueError(f"backend must be 'auto', 'modal' or 'direct', got {backend!r}")
        b = model.blocks
        self.model = model
        self.n_l, self.n_c = b["K_ll"].shape[0], b["K_cc"].shape[0]
        n_l = self.n_l
        self.B = np.zeros((n_l, 0), dtype=complex) if rhs is None else \
            np.asarray(rhs, dtype=complex).reshape(n_l, -1)
        self.K_lc = np.asarray(b["K_lc"], dtype=float)
        self.K_cc = np.asarray(b["K_cc"], dtype=float)
        C = b["C_ll"] if b["C_ll"] is not None else sp.csc_matrix(b["K_ll"].shape)
        self.damped = C.nnz > 0
        small = n_l <= DENSE_LIMIT
        if small:
            self.Z0 = la.solve(b["K_ll"].toarray(), self.K_lc, assume_a="pos")
        else:
            self.Z0 = spla.splu(b["K_ll"].tocsc()).solve(self.K_lc)
        self.D0 = self.K_cc - self.K_lc.T @ self.Z0
        self.P0 = -self.Z0.T @ self.B  # static condensed load (not used by the harmonics >= 1)
        modal = None
        if backend == "modal" and small or backend == "auto" and small and \
                modal_is_cheaper(n_l, self.n_c, self.damped):
            modal = self._modal_setup(model, C)
        if backend == "modal" and modal is None:
            raise ValueError("backend 'modal' needs a damping matrix that is diagonal in the open-contact "
                             "modes (modal or Rayleigh, Model.with_damping) and at most "
                             f"{DENSE_LIMIT} DOFs with mass")
        self.backend = "modal" if modal is not None else "direct"
        if self.backend == "direct":
            if small:
                self.K_ll, self.M_ll, self.C_ll = b["K_ll"].toarray(), b["M_ll"].toarray(), C.toarray()
            else:
                self.K_ll, self.M_ll, self.C_ll = b["K_ll"].tocsc(), b["M_ll"].tocsc(), sp.csc_matrix(C)
            self._dense = small

    # ------------------------------------------------------------------ modal set-up
    def _modal_setup(self, model: Model, C) -> bool | None:
        """Modal data, or None when C is not diagonal in the open modes."""
        freqs, modes = model.linear_modes(self.n_l)
        l, c = model.l, model.c
        Phi_l, Phi_c = modes[l], modes[c]
        gamma = np.einsum("ij,ij->j", Phi_l, C @ Phi_l)
        if self.damped:
            CPhi = Phi_l.T @ (C @ Phi_l)
            off = CPhi - np.diag(np.diag(CPhi))
            if np.abs(off).max() > _MODAL_RTOL * max(np.abs(np.diag(CPhi)).max(), 1e-300):
                return None
        self._Phi_l, self._Phi_c = Phi_l, Phi_c
        self._w2, self._gamma = (2 * np.pi * freqs) ** 2, gamma
        self._beta = Phi_l.T @ self.B  # modal loads (n_modes, m)
        self._Kcc_inv = la.inv(self.K_cc)
        self._Phi_c_contiguous = np.ascontiguousarray(Phi_c, dtype=float)
        self._beta_contiguous = np.ascontiguousarray(self._beta, dtype=complex)
        self._w2 = np.ascontiguousarray(self._w2, dtype=float)
        self._gamma = np.ascontiguousarray(gamma, dtype=float)
        return True

    # ------------------------------------------------------------------ evaluation
    def evaluate(self, omega: float, harmonics: int, xi: float = 0.0, derivative: bool = True,
                 xi_derivative: bool = False, recover: bool = False) -> CondensedHarmonics:
        """D_k, P̂_1 (and derivatives, and Z_k, Y for the recovery) for k = 0..H at (Ω, ξ).

        Raises
        ------
        SingularDynamicStiffness
            When S_k is singular (undamped, kΩ on an eigenfrequency of the structure
            with its massless DOFs clamped).
        """
        if not (math.isfinite(omega) and math.isfinite(xi)):
            raise ValueError(f"omega and xi must be finite, got {omega!r}, {xi!r}")
        H = int(harmonics)
        if H < 1:
            raise ValueError(f"harmonics must be >= 1, got {H}")
        with np.errstate(over="ignore", invalid="ignore"):  # a wild Newton iterate: non-finite -> failed step
            if self.backend == "modal":
                return self._evaluate_modal(omega, H, xi, derivative, xi_derivative, recover)
            return self._evaluate_direct(omega, H, xi, derivative, xi_derivative, recover)

    def _evaluate_modal(self, omega, H, xi, derivative, xi_derivative, recover):
        """The receptance form with the nearest mode of each harmonic taken out by a rank-one
        update (module docstring): D_k = B − (Bφ)(Bφ)ᵀ/g, B = A⁻¹, A = K_cc⁻¹ + Σ_{m≠j}
        φ_m d_m φ_mᵀ, g = 1/d_j + φᵀBφ, with φ = φ_c,j of the mode j nearest kΩ: regular
        even where d_j is infinite (a harmonic on an undamped open mode, the linear EPMC).
        Without the recovery, the compiled kernel
        (:mod:`mmshbm.methods.mms.condensation._damped_modal_kernels`)."""
        if not recover:
            return self._evaluate_modal_compiled(omega, H, xi, derivative, xi_derivative)
        k = np.arange(1, H + 1, dtype=float)
        w = k * omega
        gamma = self._gamma - xi
        inv_d = self._w2[None, :] - (w**2)[:, None] + 1j * w[:, None] * gamma[None, :]  # (H, n_m)
        j = np.argmin(np.abs(inv_d) / self._w2[None, :], axis=1)
        rows = np.arange(H)
        inv_dj = inv_d[rows, j].copy()
        inv_d[rows, j] = 1.0
        d = 1.0 / inv_d
        d[rows, j] = 0.0  # far modes only
        Pc = self._Phi_c
        A = self._Kcc_inv[None] + np.einsum("im,km,jm->kij", Pc, d, Pc)
        try:
            B = np.linalg.inv(A)
        except np.linalg.LinAlgError:
            raise SingularDynamicStiffness(f"condensation singular at Ω = {omega:.6g} rad/s") from None
        phi = Pc[:, j].T  # (H, n_c)
        Bphi = np.einsum("kij,kj->ki", B, phi)
        g = inv_dj + np.einsum("ki,ki->k", phi, Bphi)
        if np.any(g == 0):
            raise SingularDynamicStiffness(f"condensation singular at Ω = {omega:.6g} rad/s")
        n_c = self.n_c
        D = np.empty((H + 1, n_c, n_c), dtype=complex)
        D[0] = self.D0
        D[1:] = B - np.einsum("ki,kj->kij", Bphi, Bphi) / g[:, None, None]
        beta = self._beta
        h_far = Pc @ (d[0][:, None] * beta)  # (n_c, m)
        beta_j = beta[j[0]]  # (m,)
        P = D[1] @ h_far + np.outer(Bphi[0], beta_j) / g[0]

        def derivatives(dd_far, d_inv_j):
            """dD (H+1, n_c, n_c) and dP (n_c, m) for the derivatives dd of the far d's and
            of 1/d_j."""
            dA = np.einsum("im,km,jm->kij", Pc, dd_far, Pc)
            dB = -B @ dA @ B
            dBphi = np.einsum("kij,kj->ki", dB, phi)
            dg = d_inv_j + np.einsum("ki,ki->k", phi, dBphi)
            out = np.zeros_like(D)
            out[1:] = (dB - (np.einsum("ki,kj->kij", dBphi, Bphi) + np.einsum("ki,kj->kij", Bphi, dBphi))
                       / g[:, None, None] + np.einsum("ki,kj->kij", Bphi, Bphi) * (dg / g**2)[:, None, None])
            dh = Pc @ (dd_far[0][:, None] * beta)
            dP = out[1] @ h_far + D[1] @ dh + (np.outer(dBphi[0], beta_j) * g[0] - np.outer(Bphi[0], beta_j)
                                               * dg[0]) / g[0] ** 2
            return out, dP

        dD = dDx = dP = dPx = None
        if derivative:
            # ∂(1/d)/∂Ω = k(−2ω + iγ), ∂d/∂Ω = −d² ∂(1/d)/∂Ω
            dinv = k[:, None] * (-2 * w[:, None] + 1j * gamma[None, :])
            dD, dP = derivatives(-d**2 * dinv, dinv[rows, j])
        if xi_derivative:
            dinv = np.broadcast_to(-1j * w[:, None], d.shape)
            dDx, dPx = derivatives(-d**2 * dinv, dinv[rows, j])
        Z = Y = None
        if recover:
            Pl = self._Phi_l
            Z = np.empty((H + 1, self.n_l, n_c), dtype=complex)
            Z[0] = self.Z0
            # H_lc D = Σ_far φ_l d φ_cᵀ D + φ_l,j (Bφ)ᵀ/g
            far = np.einsum("im,km,jm->kij", Pl, d, Pc) @ D[1:]
            Z[1:] = -(far + np.einsum("ik,kj->kij", Pl[:, j], Bphi / g[:, None]))
            resid = beta - Pc.T @ P  # β_m − φ_c,mᵀ P̂ (n_m, m)
            Y = Pl @ (d[0][:, None] * resid) + np.outer(Pl[:, j[0]], beta_j - Bphi[0] @ h_far) / g[0]
        return CondensedHarmonics(float(omega), float(xi), D, dD, dDx, P, dP, dPx, Z, Y)

    def _evaluate_modal_compiled(self, omega, H, xi, derivative, xi_derivative):
        n_c, m = self.n_c, self.B.shape[1]
        shape = (H + 1, n_c, n_c)
        D = np.empty(shape, dtype=complex)
        dD = np.empty(shape, dtype=complex) if derivative else np.empty((0, 0, 0), dtype=complex)
        dDx = np.empty(shape, dtype=complex) if xi_derivative else np.empty((0, 0, 0), dtype=complex)
        P, dP, dPx = (np.empty((n_c, m), dtype=complex) for _ in range(3))
        status = _damped_modal(float(omega), float(xi), H, self._w2, self._gamma, self._Phi_c_contiguous,
                               self._Kcc_inv, self.D0, self._beta_contiguous, derivative, xi_derivative,
                               D, dD, dDx, P, dP, dPx)
        if status:
            raise SingularDynamicStiffness(f"condensation singular at Ω = {omega:.6g} rad/s")
        return CondensedHarmonics(float(omega), float(xi), D, dD if derivative else None,
                                  dDx if xi_derivative else None, P, dP if derivative else None,
                                  dPx if xi_derivative else None, None, None)

    def _evaluate_direct(self, omega, H, xi, derivative, xi_derivative, recover):
        n_l, n_c = self.n_l, self.n_c
        B = self.B
        m = B.shape[1]
        k = np.arange(1, H + 1, dtype=float)
        Z = np.empty((H + 1, n_l, n_c), dtype=complex)
        Z[0] = self.Z0
        if self._dense:
            Cx = self.C_ll - xi * self.M_ll
            S = (self.K_ll[None] + (1j * k * omega)[:, None, None] * Cx[None]
                 - ((k * omega) ** 2)[:, None, None] * self.M_ll[None])
            rhs_all = np.empty((H, n_l, n_c + m), dtype=complex)
            rhs_all[:, :, :n_c] = self.K_lc
            rhs_all[:, :, n_c:] = B
            try:
                X = np.linalg.solve(S, rhs_all)
            except np.linalg.LinAlgError:
                raise SingularDynamicStiffness(
                    f"S_k is singular at Ω = {omega:.6g} rad/s, ξ = {xi:.6g} 1/s: a harmonic of Ω sits on an "
                    "undamped eigenfrequency of the structure with its massless DOFs clamped") from None
            if not np.all(np.isfinite(X)):
                raise SingularDynamicStiffness(f"S_k is numerically singular at Ω = {omega:.6g} rad/s")
            Z[1:] = X[:, :, :n_c]
            Y = X[0, :, n_c:]
        else:
            Y = None
            for kk in range(1, H + 1):
                S = (self.K_ll + (1j * kk * omega) * (self.C_ll - xi * self.M_ll)
                     - (kk * omega) ** 2 * self.M_ll).tocsc()
                try:
                    lu = spla.splu(S)
                except RuntimeError as err:
                    raise SingularDynamicStiffness(
                        f"S_{kk} is singular at Ω = {omega:.6g} rad/s: {err}") from None
                Kc = self.K_lc.astype(complex)
                X = lu.solve(np.hstack([Kc, B]) if kk == 1 else Kc)
                Z[kk] = X[:, :n_c]
                if kk == 1:
                    Y = X[:, n_c:]
        D = np.empty((H + 1, n_c, n_c), dtype=complex)
        D[0] = self.D0
        D[1:] = self.K_cc[None] - np.matmul(self.K_lc.T[None], Z[1:])
        P = -self.K_lc.T @ Y
        dD = dDx = dP = dPx = None
        if derivative or xi_derivative:
            Zk = Z[1:]
            ZtMZ = np.matmul(Zk.transpose(0, 2, 1), _times(self.M_ll, Zk))
            ZtCZ = np.matmul(Zk.transpose(0, 2, 1), _times(self.C_ll, Zk)) if self.damped else 0.0 * ZtMZ
            kk = k[:, None, None]
            MY = _times(self.M_ll, Y)
            CY = _times(self.C_ll, Y) if self.damped else 0.0 * MY
            if derivative:
                dD = np.zeros_like(D)
                dD[1:] = 1j * kk * (ZtCZ - xi * ZtMZ) - 2.0 * kk**2 * omega * ZtMZ
                dP = Z[1].T @ (1j * (CY - xi * MY) - 2.0 * omega * MY)
            if xi_derivative:
                dDx = np.zeros_like(D)
                dDx[1:] = -1j * kk * omega * ZtMZ
                dPx = Z[1].T @ (-1j * omega * MY)
        return CondensedHarmonics(float(omega), float(xi), D, dD, dDx, P, dP, dPx,
                                  Z if recover else None, Y if recover else None)


def _times(A, X: np.ndarray) -> np.ndarray:
    """A @ X for a dense or sparse (n, n) A and X of shape (n, m) or (H, n, m)."""
    if isinstance(A, np.ndarray):
        return np.matmul(A, X)
    if X.ndim == 2:
        return A @ X
    return np.stack([A @ x for x in X])
