"""Harmonic 1 of one DOF with mass recovered from the massless DOFs' coefficients, with its
exact derivatives: the amplitude DOF tracked by the friction forced response.

With S_1(Ω) = K_ll + iΩ C_ll − Ω² M_ll (the DOFs with mass, massless DOFs clamped) and
w = S_1⁻¹ e_t (S_1 complex symmetric, so e_tᵀ S_1⁻¹ = wᵀ), the DOF t's harmonic 1 is

    Q̂_t = −z·Û_c + σ(Ω) y,     z = wᵀ K_lc (n_c,),   y = wᵀ F̂_l

(:mod:`mmshbm.core.damped_condense`: Q̂_l = Y − Z Q̂_c), and from ∂(S⁻¹) = −S⁻¹ S' S⁻¹ with
S' = i C_ll − 2Ω M_ll: ∂w/∂Ω = −S_1⁻¹ S' w, so ∂z/∂Ω = (∂w/∂Ω)ᵀ K_lc and
∂y/∂Ω = (∂w/∂Ω)ᵀ F̂_l. One dense LU of the n_l × n_l matrix S_1 per Ω (the models the
friction forced response runs have at most a few hundred DOFs with mass; above
:data:`~mmshbm.core.damped_condense.DENSE_LIMIT` the caller keeps its own recovery).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as la

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
        self.force_l = np.asarray(force_l, dtype=complex)
        self.e = np.zeros(self.K_ll.shape[0])
        self.e[row] = 1.0
        self._memo: tuple | None = None

    def at(self, omega: float, derivative: bool = False):
        """(z (n_c,), y, ∂z/∂Ω, ∂y/∂Ω) at Ω (rad/s); the derivatives None without
        ``derivative``. Raises numpy.linalg.LinAlgError where S_1 is singular."""
        memo = self._memo
        if memo is not None and memo[0] == omega and (memo[1][2] is not None or not derivative):
            return memo[1]
        S = self.K_ll + 1j * omega * self.C_ll - omega**2 * self.M_ll
        try:
            lu = la.lu_factor(S, check_finite=False)
        except (ValueError, la.LinAlgError) as err:
            raise np.linalg.LinAlgError(f"S_1 singular at Ω = {omega:.6g} rad/s: {err}") from None
        w = la.lu_solve(lu, self.e.astype(complex), check_finite=False)
        z, y = w @ self.K_lc, complex(w @ self.force_l)
        dz = dy = None
        if derivative:
            dS = 1j * self.C_ll - 2.0 * omega * self.M_ll
            dw = -la.lu_solve(lu, dS @ w, check_finite=False)
            dz, dy = dw @ self.K_lc, complex(dw @ self.force_l)
        out = (z, y, dz, dy)
        self._memo = (omega, out)
        return out
