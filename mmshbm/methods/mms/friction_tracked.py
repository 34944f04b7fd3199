"""Harmonic 1 of one DOF with mass recovered from the massless DOFs' coefficients, with its
exact derivatives: the amplitude DOF tracked by the friction forced response.

With S_1(Ω) = K_ll + iΩ C_ll − Ω² M_ll (the DOFs with mass, massless DOFs clamped) and
w = S_1⁻¹ e_t (S_1 complex symmetric, so e_tᵀ S_1⁻¹ = wᵀ), the DOF t's harmonic 1 is

    Q̂_t = −z·Û_c + σ(Ω) y,     z = wᵀ K_lc (n_c,),   y = wᵀ F̂_l

(:mod:`mmshbm.methods.mms.condensation.damped_condense`: Q̂_l = Y − Z Q̂_c), and from ∂(S⁻¹) = −S⁻¹ S' S⁻¹ with
S' = i C_ll − 2Ω M_ll: ∂w/∂Ω = −S_1⁻¹ S' w, so ∂z/∂Ω = (∂w/∂Ω)ᵀ K_lc and
∂y/∂Ω = (∂w/∂Ω)ᵀ F̂_l. One dense solve with S_1 per Ω (n_l × n_l; the models the
friction forced response runs have at most a few hundred DOFs with mass; above
:data:`~mmshbm.methods.mms.condensation.damped_condense.DENSE_LIMIT` the caller keeps its own recovery).
"""

from __future__ import annotations

import numpy as np

from ._friction_kernels import _tracked_harmonic

__all__ = ["TrackedHarmonic"]


class TrackedHarmonic:
    """Harmonic 1 of DOF ``row`` (index into ``model.l``) of the DOFs with mass.

    Parameters
    ----------
    blocks : dict
        ``model.blocks`` (K_ll, M_ll, C_ll (or None), K_lc), sparse or dense.
    row : int
        Index of the tracked DOF in ``model.l``.
    force_l : ndarray, complex, shape (n_l,)
        F̂_l, the harmonic load on the DOFs with mass (N).
    """

    def __init__(self, blocks: dict, row: int, force_l: np.ndarray):
        def dense(A):
            return A.toarray() if hasattr(A, "toarray") else np.asarray(A, dtype=float)

        self.K_ll, self.M_ll = dense(blocks["K_ll"]), dense(blocks["M_ll"])
        C = blocks.get("C_ll")
        self.C_ll = np.zeros_like(self.K_ll) if C is None else dense(C)
        self.K_lc = dense(blocks["K_lc"])
        self.K_ll, self.M_ll, self.C_ll = (np.ascontiguousarray(A, dtype=float)
                                           for A in (self.K_ll, self.M_ll, self.C_ll))
        self.force_l = np.asarray(force_l, dtype=complex)
        self.row = int(row)
        e = np.zeros((self.K_ll.shape[0], 1))
        e[row] = 1.0
        self._rhs = np.hstack([e, self.K_lc, self.force_l[:, None]]).astype(complex)
        self._memo: tuple | None = None

    def at(self, omega: float, derivative: bool = False):
        """(z (n_c,), y, ∂z/∂Ω, ∂y/∂Ω) at Ω (rad/s); the derivatives None without
        ``derivative``. Raises numpy.linalg.LinAlgError where S_1 is singular.

        One solve with the right-hand sides [e_t, K_lc, F̂_l]: with S_1 and S′ symmetric,
        z = (S_1⁻¹K_lc)_t, y = (S_1⁻¹F̂_l)_t, and ∂z/∂Ω = −wᵀ S′ S_1⁻¹K_lc,
        ∂y/∂Ω = −wᵀ S′ S_1⁻¹F̂_l (w = S_1⁻¹e_t)."""
        memo = self._memo
        if memo is not None and memo[0] == omega and (memo[1][2] is not None or not derivative):
            return memo[1]
        n = self._rhs.shape[1] - 1
        zy = np.empty(n, dtype=complex)
        dzy = np.empty(n, dtype=complex)
        try:
            _tracked_harmonic(self.K_ll, self.M_ll, self.C_ll, self._rhs, self.row, float(omega), derivative,
                              zy, dzy)
        except np.linalg.LinAlgError as err:
            raise np.linalg.LinAlgError(f"S_1 singular at Ω = {omega:.6g} rad/s: {err}") from None
        z, y = zy[:-1], complex(zy[-1])
        dz, dy = (dzy[:-1], complex(dzy[-1])) if derivative else (None, None)
        out = (z, y, dz, dy)
        self._memo = (omega, out)
        return out
