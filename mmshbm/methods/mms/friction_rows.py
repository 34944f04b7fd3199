"""The friction rows of MMS-HBM's problems with Coulomb friction at massless DOFs: the law's
residual and Jacobian per friction DOF in its play or velocity form, compiled where the
slip forces are constant, and the input checks of friction models. The forms, the full-stick
convention and impact with friction: :mod:`mmshbm.methods.mms.friction_forced`.
"""

from __future__ import annotations

import numpy as np

from ...contact.coulomb import _sample_basis, derivative_matrix, project_coulomb, project_coulomb_play
from ...model.model import Model

__all__ = ["FrictionRows", "check_friction_model", "check_law"]

_EMPTY = np.empty((0, 0))

def check_law(law: str, projection: str) -> None:
    """Raise ValueError for an unknown ``law`` or the play law with a sampled projection."""
    if law not in ("play", "velocity"):
        raise ValueError(f"law must be 'play' or 'velocity', got {law!r}")
    if law == "play" and projection != "exact":
        raise ValueError("law='play' is projected exactly only: pass projection='exact'")


def check_friction_model(model: Model, coupled_ok: bool = False, who: str = "this method") -> None:
    """Raise unless ``model`` has friction contacts this module solves: constant loads, and
    with ``coupled_ok`` also loads coupled to a unilateral contact (``normal_contact=``)."""
    if not isinstance(model, Model):
        raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
    if not model.friction:
        raise ValueError("the model has no friction contact")
    coupled = [fc.dof for fc in model.friction if fc.normal_contact is not None]
    if coupled and not coupled_ok:
        raise NotImplementedError(f"friction coupled to a unilateral contact's force (normal_contact=, "
                                  f"DOFs {coupled}) is not yet solved by {who}: give a constant "
                                  "normal_load, or use MMS-HBM (the forced response or the EPMC)")


class FrictionRows:
    """The friction rows shared by the forced-response and EPMC problems with friction
    (mixed in before a :class:`~mmshbm.methods.mms.damped.DampedHBMBase` subclass): the
    law of every friction contact replaces the rows F_t = 0 of its massless DOF."""

    def _init_friction(self, model: Model, law: str, projection: str) -> None:
        c = model.c
        self.friction_rows = np.searchsorted(c, [fc.dof for fc in model.friction])
        # constant loads: s = μN; coupled loads: μ·preload here, the contact's force added in
        # the law (``coupling``: (contact row, side·stop position, μ, preload) or None)
        self.slip_force = np.array([fc.mu * (fc.preload if fc.normal_contact is not None else fc.normal_load)
                                    for fc in model.friction])
        self.coupling = [None if fc.normal_contact is None else self._coupling(model, fc)
                         for fc in model.friction]
        if law != "play" and any(cp is not None for cp in self.coupling):
            raise NotImplementedError("friction coupled to a unilateral contact (normal_contact=) is "
                                      "solved in the play form only: pass law='play'")
        # the node's stiffness with the DOFs with mass held: then y = u − F_t/ρ = wᵀq_l is the
        # position the free node would take, as smooth as the motion of the DOFs with mass
        flex = np.linalg.inv(model.blocks["K_cc"])
        self.rho = 1.0 / np.diag(flex)[self.friction_rows]
        self._Dt = derivative_matrix(self.H)
        self._exact = projection == "exact"
        self.law = law
        # the play form with constant slip forces runs compiled (:meth:`fused_residual`)
        self._compiled_rows = law == "play" and all(cp is None for cp in self.coupling)
        self._friction_rows64 = np.ascontiguousarray(self.friction_rows, dtype=np.int64)
        self._play_tables = _sample_basis(self.H, 16 * (2 * self.H + 1))

    def _coupling(self, model: Model, fc) -> tuple[int, int, float, float, float]:
        """(index into ``contact_rows``, side, gap, μ, preload) of the unilateral contact that
        presses friction contact ``fc``."""
        ct = model.contacts[fc.normal_contact]
        k = int(np.flatnonzero(self.contact_rows == np.searchsorted(model.c, ct.dof))[0])
        return k, int(ct.side), float(ct.gap), float(fc.mu), float(fc.preload)

    def _rescale(self, length: float, extra_cols: int) -> None:
        """Unknowns in units of ``length`` (m) times the first mode's shape; ``extra_cols``
        parameters (scaled by ω_ref) after them."""
        self.length = length
        self.scale_unknowns(length)
        for j, i in enumerate(self.friction_rows):
            self.rowscale[self._coef_index[i]] = self.rho[j] * length
        self.colscale = np.concatenate([self.xscale, np.full(extra_cols, self.omega_ref)])
        self._jscale = None  # the Jacobian's column scaling, formed again at first use

    def friction_law(self, x: np.ndarray, F: np.ndarray, j: int, jacobian: bool = True):
        """(R (2H+1,), ∂R/∂F_t, ∂R/∂x_t (2H+1, 2H+1), slip fraction) of friction contact j
        (the play form without ``jacobian`` returns None for both derivatives)."""
        idx = self._coef_index[self.friction_rows[j]]
        if self.coupling[j] is not None:
            return self._coupled_law(x, F, j, idx, jacobian)
        if self.law == "play":
            rho = self.rho[j]
            g, Jg, slip = project_coulomb_play(x[idx] - F[idx] / rho, self.slip_force[j], rho,
                                               jacobian=jacobian)
            if Jg is None:
                return F[idx] - g, None, None, slip
            return F[idx] - g, np.eye(len(idx)) + Jg / rho, -Jg, slip
        v = self._Dt @ x[idx]
        Rc, A, B, slip = project_coulomb(-F[idx], v, self.slip_force[j], self.rho[j], self._exact,
                                         None if self._exact else self.N)
        # R = −Rc = F_t + proj[clip(−F_t + ρ u′)]
        return -Rc, A, -B @ self._Dt, slip

    def _coupled_law(self, x, F, j, idx, jacobian):
        """:meth:`friction_law` of a contact pressed by N0 + λ_n(τ): (R, (∂R/∂F_t, ∂R/∂F_n),
        (∂R/∂x_t, ∂R/∂x_n), slip), λ_n = r_n (side·p_n − gap)₊ the proximal force of the
        normal contact, p_n = x_n − F_n/r_n
        (:func:`~mmshbm.contact.coulomb_coupled.project_coulomb_play_coupled`)."""
        from ...contact.coulomb_coupled import project_coulomb_play_coupled

        k, side, gap, mu, preload = self.coupling[j]
        rho, r_n = self.rho[j], self.r[k]
        idx_n = self._coef_index[self.contact_rows[k]]
        z = side * (x[idx_n] - F[idx_n] / r_n)
        g, Jy, Jz, slip = project_coulomb_play_coupled(x[idx] - F[idx] / rho, z, rho, mu, preload, r_n, gap,
                                                       jacobian=jacobian)
        if Jy is None:
            return F[idx] - g, None, None, slip
        eye = np.eye(len(idx))
        return F[idx] - g, (eye + Jy / rho, side * Jz / r_n), (-Jy, -side * Jz), slip

    def fused_residual(self, D, x, load, dD=None, dload=None):
        """The residual with the friction rows: compiled for the play form with constant slip
        forces (the unilateral rows by the fused kernel, which leaves F and its derivatives
        on the friction rows, then the friction rows in place, :meth:`_compiled_friction`);
        otherwise :meth:`residual_from_blocks` (NumPy, :meth:`contact_residual`)."""
        if not self._compiled_rows:
            return self.residual_from_blocks(D, x, load, dD, dload)
        R, Jx, Jp = super().fused_residual(D, x, load, dD, dload)
        self._compiled_friction(x, R, Jx, Jp)
        return R, Jx, Jp

    def _compiled_friction(self, x: np.ndarray, R: np.ndarray, Jx: np.ndarray | None, Jp: np.ndarray | None):
        """In place: the friction rows of R, Jx, Jp, which hold F, ∂F/∂x, ∂F/∂params there
        (:func:`~mmshbm.methods.mms._friction_kernels._friction_rows`; Jp may be None with Jx
        given)."""
        from ._friction_kernels import _friction_rows

        jacobian = Jx is not None
        if jacobian and Jp is None:
            Jp = np.empty((self.n_x, 0))
        tau, cos_t, sin_t = self._play_tables
        _friction_rows(np.ascontiguousarray(x, dtype=float), self._friction_rows64, self.n_c, self.slip_force,
                       self.rho, tau, cos_t, sin_t, jacobian, R, Jx if jacobian else _EMPTY,
                       Jp if jacobian else _EMPTY, np.empty(len(self.friction_rows)))

    def contact_residual(self, x: np.ndarray, F: np.ndarray, dF: np.ndarray | None, dFp: np.ndarray | None):
        """R (n_x,), and with ``dF`` ∂R/∂x and ∂R/∂params, with the friction rows: compiled
        where :meth:`fused_residual` is (set ``_compiled_rows`` False for the NumPy rows,
        :meth:`friction_law`, the reference of the kernel)."""
        R, Jx, Jp = super().contact_residual(x, F, dF, dFp)
        if self._compiled_rows:
            self._compiled_friction(x, R, Jx, Jp)
            return R, Jx, Jp
        for j, i in enumerate(self.friction_rows):
            idx = self._coef_index[i]
            Rt, A, B, slip = self.friction_law(x, F, j, Jx is not None)
            R[idx] = Rt
            if Jx is not None and isinstance(A, tuple):  # coupled: the normal contact's columns too
                idx_n = self._coef_index[self.contact_rows[self.coupling[j][0]]]
                Jx[idx] = A[0] @ dF[idx] + A[1] @ dF[idx_n]
                Jx[np.ix_(idx, idx)] += B[0]
                Jx[np.ix_(idx, idx_n)] += B[1]
                if Jp is not None:
                    Jp[idx] = A[0] @ dFp[idx] + A[1] @ dFp[idx_n]
            elif Jx is not None:
                Jx[idx] = A @ dF[idx]
                Jx[np.ix_(idx, idx)] += B
                if Jp is not None:
                    Jp[idx] = A @ dFp[idx]
            if slip == 0.0 and self.law == "velocity":
                # full stick: the symmetric position, mean friction force zero
                m = idx[0]
                R[m] = F[m]
                if Jx is not None:
                    Jx[m] = dF[m]
                    if Jp is not None:
                        Jp[m] = dFp[m]
        return R, Jx, Jp

    def friction_records(self, x: np.ndarray, omega: float, sigma: float = 1.0) -> dict:
        """``slip_fraction`` (largest over the friction nodes) and ``friction_dissipation``
        (J per period: Σ_t ∫ f_t u_t′ dτ with f_t = −F_t, by Parseval)."""
        slip, work = self.slip_and_work(x, self._needed(x, omega, sigma))
        return {"slip_fraction": slip, "friction_dissipation": work}

    def slip_and_work(self, x: np.ndarray, F: np.ndarray) -> tuple[float, float]:
        """(largest slip fraction over the friction nodes, friction work per period (J)):
        Σ_t ∫ f_t u_t′ dτ with f_t = −F_t, by Parseval, for the force F the structure needs."""
        slip, work = 0.0, 0.0
        for j, i in enumerate(self.friction_rows):
            idx = self._coef_index[i]
            slip = max(slip, self.friction_law(x, F, j, False)[3])
            f, v = -F[idx], self._Dt @ x[idx]
            work += np.pi * (2 * f[0] * v[0] + f[1:] @ v[1:])
        return slip, float(work)
