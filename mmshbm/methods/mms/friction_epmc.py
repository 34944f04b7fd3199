"""Damped nonlinear modes (EPMC) of structures with Coulomb friction at massless DOFs.

Krack's extended periodic motion concept (:mod:`mmshbm.methods.mms.epmc`): the periodic
solutions of M q'' + (C − ξM) q' + K q = −Σ e_t f_t, with ξ (1/s) an unknown that
compensates viscous and friction dissipation, ξ ∮ q̇ᵀMq̇ dt = ∮ q̇ᵀCq̇ dt + ∮ f_t u̇_t dt;
the modal damping ratio is D = ξ/(2Ω). The friction rows are those of
:class:`~mmshbm.methods.mms.friction_rows.FrictionRows` (default the displacement-level
play form).

Why the first harmonic of the DOFs with mass is kept as an unknown. At small amplitude
the nodes stick: their Fourier coefficients, the only unknowns of a condensed MMS-HBM,
vanish, and the motion of the DOFs with mass is a mode of the structure with the nodes
clamped, Ω = ω_j and ξ = φ_jᵀCφ_j, exactly where S_1(Ω, ξ) = K_ll + iΩ(C − ξM) − Ω²M
is singular (a pole of the condensation). Here harmonic 1 of the DOFs with mass is not
condensed: its coefficients X̂_1 = a_1 − i b_1 are unknowns with the equations
S_1 X̂_1 + K_lc Û_1 = 0, and the force the structure needs at the massless DOFs is
K_cc Û_1 + K_cl X̂_1 for k = 1 and D_k Û_k (dense condensation) for k ≠ 1. The stuck mode
is then a regular point. Unknowns u = [x, a_1, b_1, ξ, Ω] (scaled); equations: the
projected massless rows, the 2 n_l rows of harmonic 1, and the phase anchor b_1 = 0 at the
amplitude DOF (which must carry mass). Dense: meant for models with up to a few hundred
DOFs with mass. The branch starts on the stuck linear mode (the friction DOFs clamped).
"""

from __future__ import annotations

import numpy as np

from ... import _validate as check
from ...core.measures import mean_energy
from ...core.problem import BackboneProblemBase, OneEvaluation
from ...model.model import Model
from .damped import DampedHBMBase
from .friction_rows import FrictionRows, check_friction_model, check_law

__all__ = ["FrictionEPMCProblem", "stuck_mode"]


def stuck_mode(model: Model, mode: int = 1) -> tuple[float, np.ndarray, float]:
    """Linear mode ``mode`` of the structure with its friction DOFs clamped (the other
    massless DOFs condensed): (frequency in Hz, shape (n_dof,) with 1 at the amplitude DOF,
    the amplitude (m) at which the first friction contact reaches its slip force, inf if
    none is loaded)."""
    fixed = [fc.dof for fc in model.friction]
    keep = np.setdiff1d(np.arange(model.n_dof), fixed)
    freqs, phi = Model(model.M[keep][:, keep], model.K[keep][:, keep], ()).linear_modes(mode)
    shape = np.zeros(model.n_dof)
    shape[keep] = phi[:, -1]
    shape /= shape[model.amplitude_dof]
    force = model.K @ shape  # the force each clamped DOF needs per unit amplitude
    # a contact pressed by a unilateral contact's force: its preload while the contact is open
    onset = [fc.mu * (fc.normal_load if fc.normal_contact is None else fc.preload) / abs(force[fc.dof])
             for fc in model.friction if force[fc.dof] != 0]
    return float(freqs[-1]), shape, (min(onset) if onset else np.inf)


class FrictionEPMCProblem(OneEvaluation, FrictionRows, DampedHBMBase, BackboneProblemBase):
    """EPMC of a model with friction contacts (constant normal loads, or pressed by a
    unilateral contact's force: ``normal_contact=`` with ``preload`` > 0), as a continuation
    problem.

    Parameters
    ----------
    model : Model
        Friction contacts with s = μN > 0 (μ·preload > 0 for one pressed by a unilateral
        contact: the branch starts stuck with the contacts open); unilateral contacts
        optional (their rows as in the impact EPMC, the friction rows of
        :mod:`~mmshbm.contact.coulomb_coupled` for ``normal_contact=``), ``amplitude_dof`` a DOF
        with mass; viscous damping optional.
    harmonics : int
        H >= 1.
    n_samples, r, backend, projection
        As :class:`~mmshbm.methods.mms.damped.DampedHBMBase`.
    mode : int
        The linear mode (1-based) of the stuck structure the branch starts from.
    law : {"play", "velocity"}
        The friction rows (:mod:`mmshbm.methods.mms.friction_forced`).

    Notes
    -----
    Monitored per point: frequency (Hz), amplitude (largest |q| of the amplitude DOF, m),
    energy (J), contact_force_max (0), damping_ratio (ξ/(2Ω)), xi (1/s), slip_fraction,
    friction_dissipation (J per period), viscous_dissipation (J per period).
    """

    method = "epmc"

    def __init__(self, model: Model, harmonics: int = 5, n_samples: int | None = None, r: float | None = None,
                 mode: int = 1, backend: str = "auto", projection: str = "exact", law: str = "play"):
        check_friction_model(model, coupled_ok=True, who="the EPMC (damped nonlinear modes)")
        check_law(law, projection)
        if np.any([fc.mu * (fc.normal_load if fc.normal_contact is None else fc.preload) == 0
                   for fc in model.friction]):
            raise ValueError("a friction contact has slip force μN = 0 with its contact open (it slides "
                             "freely, and the branch starts on the mode with the friction DOFs stuck): "
                             "remove it, or give a preload > 0 with normal_contact=")
        amp_dof = model.amplitude_dof
        l_index = np.flatnonzero(model.l == amp_dof)
        if not len(l_index):
            raise ValueError(f"the amplitude DOF {amp_dof} must carry mass (it anchors the phase)")
        super().__init__(model, harmonics, n_samples, r, backend, "MMS-HBM (EPMC with friction)",
                         projection=projection)
        self._init_friction(model, law, projection)
        self.mode = check.integer("mode", mode, minimum=1)
        b = model.blocks
        self.M = b["M_ll"].toarray()
        self.C = b["C_ll"].toarray() if b["C_ll"] is not None else np.zeros_like(self.M)
        self.K_ll, self.K_lc, self.K_cc = b["K_ll"].toarray(), b["K_lc"], b["K_cc"]
        self.n_l = n_l = self.M.shape[0]
        self.amplitude_dof = amp_dof
        self.amp_l = int(l_index[0])
        frequency, shape, onset = stuck_mode(model, self.mode)
        self.stuck_shape = shape
        self.mode_frequency = frequency
        phi_m = shape / np.sqrt(shape @ (model.M @ shape))
        self.mode_xi = float(phi_m @ (model.damping @ phi_m)) if model.damping is not None else 0.0
        self.length = onset if np.isfinite(onset) else 1.0  # scale: where the stuck mode starts to slip
        self._rescale(self.length, 0)
        self.mode_shape_c = shape[model.c]
        xl = self.length * np.maximum(np.abs(shape[model.l]), 1e-3 * np.abs(shape[model.l]).max())
        self.colscale = np.concatenate([self.xscale, xl, xl, [self.omega_ref, self.omega_ref]])
        self.rowscale = np.concatenate([self.rowscale, np.abs(self.K_ll) @ xl, np.abs(self.K_ll) @ xl])
        self.n_unknowns = self.n_x + 2 * n_l + 2
        self._anchor_col = self.n_x + n_l + self.amp_l

    # ------------------------------------------------------------------ unknowns
    def unpack(self, u: np.ndarray):
        """Scaled unknowns -> (x (n_x,), a_1 (n_l,), b_1 (n_l,), ξ (1/s), Ω (rad/s))."""
        if np.shape(u) != (self.n_unknowns,):
            raise ValueError(f"u must have shape ({self.n_unknowns},), got {np.shape(u)}")
        y = np.asarray(u, dtype=float) * self.colscale
        n_x, n_l = self.n_x, self.n_l
        return y[:n_x], y[n_x:n_x + n_l], y[n_x + n_l:n_x + 2 * n_l], float(y[-2]), float(y[-1])

    def pack(self, x, a1, b1, xi: float, omega: float) -> np.ndarray:
        return np.concatenate([x, a1, b1, [xi, omega]]) / self.colscale

    def linear_mode_point(self, amplitude: float) -> np.ndarray:
        """The stuck linear mode with ``amplitude`` (m) at the amplitude DOF (cosine)."""
        amplitude = check.positive("amplitude", amplitude)
        x = np.zeros(self.n_x)
        x[self.n_c:2 * self.n_c] = amplitude * self.stuck_shape[self.model.c]
        return self.pack(x, amplitude * self.stuck_shape[self.model.l], np.zeros(self.n_l), self.mode_xi,
                         2 * np.pi * self.mode_frequency)

    def initial_tangent(self) -> np.ndarray:
        """Growing amplitude at constant ξ and Ω."""
        t = self.linear_mode_point(1.0)
        t[-2:] = 0.0
        return t / np.linalg.norm(t)

    # ------------------------------------------------------------------ condensation
    def _dense(self, omega: float, xi: float, jacobian: bool):
        """Complex D_k (H+1, n_c, n_c) with D_1 = K_cc, and ∂D_k/∂Ω, ∂D_k/∂ξ (None unless asked)."""
        H, n_c = self.H, self.n_c
        D = np.empty((H + 1, n_c, n_c), dtype=complex)
        dW = np.zeros_like(D) if jacobian else None
        dX = np.zeros_like(D) if jacobian else None
        Cx = self.C - xi * self.M
        for k in range(H + 1):
            if k == 1:
                D[1] = self.K_cc
                continue
            S = self.K_ll - (k * omega) ** 2 * self.M + 1j * k * omega * Cx
            Z = np.linalg.solve(S, self.K_lc)
            D[k] = self.K_cc - self.K_lc.T @ Z
            if jacobian:
                dS_w = 1j * k * Cx - 2 * k * k * omega * self.M
                dS_x = -1j * k * omega * self.M
                dW[k] = Z.T @ dS_w @ Z
                dX[k] = Z.T @ dS_x @ Z
        return D, dW, dX

    def _harmonic1_blocks(self, omega: float, xi: float):
        """Real blocks of S_1 and of ∂S_1/∂Ω, ∂S_1/∂ξ (each (2 n_l, 2 n_l))."""
        def blocks(Sr, Si):
            return np.block([[Sr, Si], [-Si, Sr]])

        Cx = self.C - xi * self.M
        return (blocks(self.K_ll - omega**2 * self.M, omega * Cx), blocks(-2 * omega * self.M, Cx),
                blocks(np.zeros_like(self.M), -omega * self.M))

    def _force(self, x, a1, b1, D):
        F = self.real_blocks(D) @ x
        n_c = self.n_c
        F[n_c:2 * n_c] += self.K_lc.T @ a1
        F[2 * n_c:3 * n_c] += self.K_lc.T @ b1
        return F

    # ------------------------------------------------------------------ residual

    def _evaluate(self, u: np.ndarray, jacobian: bool):
        """Scaled residual (n_unknowns − 1,) and, if asked, its Jacobian."""
        x, a1, b1, xi, omega = self.unpack(u)
        n_x, n_l, n_c = self.n_x, self.n_l, self.n_c
        D, dW, dX = self._dense(omega, xi, jacobian)
        F = self._force(x, a1, b1, D)
        S1, dS1_w, dS1_x = self._harmonic1_blocks(omega, xi)
        z = np.concatenate([a1, b1])
        Ul = np.concatenate([self.K_lc @ x[n_c:2 * n_c], self.K_lc @ x[2 * n_c:3 * n_c]])
        R = np.empty(self.n_unknowns - 1)
        R[n_x:n_x + 2 * n_l] = S1 @ z + Ul
        R[-1] = u[self._anchor_col]
        if not jacobian:
            R[:n_x] = self.contact_residual(x, F, None, None)[0]
            R[:-1] /= self.rowscale
            return R
        dF_dx = self.real_blocks(D)
        dFp = np.zeros((n_x, 2 * n_l + 2))
        dFp[n_c:2 * n_c, :n_l] = self.K_lc.T
        dFp[2 * n_c:3 * n_c, n_l:2 * n_l] = self.K_lc.T
        dFp[:, -2] = self.real_blocks(dX) @ x
        dFp[:, -1] = self.real_blocks(dW) @ x
        Rc, Jx, Jp = self.contact_residual(x, F, dF_dx, dFp)
        R[:n_x] = Rc
        J = np.zeros((self.n_unknowns - 1, self.n_unknowns))
        J[:n_x, :n_x] = Jx
        J[:n_x, n_x:] = Jp
        rows = slice(n_x, n_x + 2 * n_l)
        J[rows, n_x:n_x + 2 * n_l] = S1
        for blk in range(2):
            J[n_x + blk * n_l:n_x + (blk + 1) * n_l, (1 + blk) * n_c:(2 + blk) * n_c] = self.K_lc
        J[rows, -2] = dS1_x @ z
        J[rows, -1] = dS1_w @ z
        R[:-1] /= self.rowscale
        J[:-1] /= self.rowscale[:, None]
        J *= self.colscale[None, :]
        J[-1] = 0.0
        J[-1, self._anchor_col] = 1.0
        return R, J

    # ------------------------------------------------------------------ results
    def coefficients(self, u: np.ndarray) -> np.ndarray:
        """NLvib-ordered coefficients of all DOFs, shape (n_dof, 2H+1)."""
        x, a1, b1, xi, omega = self.unpack(u)
        n_c, H = self.n_c, self.H
        Xc = x.reshape(self.n_coef, n_c).T
        Ql = np.empty((self.n_l, self.n_coef))
        Cx = self.C - xi * self.M
        for k in range(H + 1):
            if k == 1:
                Ql[:, 1], Ql[:, 2] = a1, b1
                continue
            S = self.K_ll - (k * omega) ** 2 * self.M + 1j * k * omega * Cx
            Qc = Xc[:, 0] if k == 0 else Xc[:, 2 * k - 1] - 1j * Xc[:, 2 * k]
            q = -np.linalg.solve(S, self.K_lc @ Qc)
            if k == 0:
                Ql[:, 0] = q.real
            else:
                Ql[:, 2 * k - 1], Ql[:, 2 * k] = q.real, -q.imag
        Q = np.empty((self.model.n_dof, self.n_coef))
        Q[self.model.c] = Xc
        Q[self.model.l] = Ql
        return Q

    def monitor(self, u: np.ndarray) -> dict:
        """frequency (Hz), amplitude (m), energy (J), contact_force_max, damping_ratio,
        xi (1/s), slip_fraction, friction_dissipation and viscous_dissipation (J/period)."""
        x, a1, b1, xi, omega = self.unpack(u)
        D, _, _ = self._dense(omega, xi, False)
        F = self._force(x, a1, b1, D)
        Q = self.coefficients(u)
        slip, work = self.slip_and_work(x, F)
        # ∮ q̇ᵀCq̇ dt = Ω ∫ q′ᵀCq′ dτ = π Ω Σ_k k² (a_kᵀCa_k + b_kᵀCb_k)
        Ql = Q[self.model.l]
        k = np.repeat(np.arange(1, self.H + 1), 2)
        visc = np.pi * omega * float(np.einsum("j,ij,ij->", k**2, Ql[:, 1:], self.C @ Ql[:, 1:]))
        return {"frequency": omega / (2 * np.pi), "amplitude": self.amplitude(Q[self.amplitude_dof]),
                "energy": mean_energy(self.model, Q, omega), "contact_force_max": 0.0,
                "damping_ratio": xi / (2 * omega), "xi": xi, "slip_fraction": slip,
                "friction_dissipation": float(work), "viscous_dissipation": visc}
