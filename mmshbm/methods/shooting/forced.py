"""Baseline: forced responses by time-domain shooting.

The forced system is not autonomous, so shooting needs no phase condition: the
unknowns are the initial state z₀ = (q_l(0), v_l(0)) of the DOFs with mass and Ω (the
continuation parameter), and the 2 n_l equations are z(T; z₀, Ω) − z₀ = 0 with T = 2π/Ω
(a full period: the damped forced orbit has no time symmetry). The massless contact DOF
follows statically (λ = k_c max(0, −h), free gap h = gap + a·q_l, one contact).

Time stepping: the energy-consistent trapezoidal rule with the contact force averaged
along each step (AVF) of :mod:`mmshbm.methods.shooting.conservative`, extended by the damping and the
harmonic force (trapezoidal average of the force samples f(t_k) = Re(σ F̂ e^{2πik/N})),
in the modal coordinates of the open-contact structure, where M = I, K = Λ and, for
modal or Rayleigh damping, C = Γ is diagonal too, so every step costs O(n_l) plus
O(n_l) per tangent column (a dense S⁻¹ for other damping). Order 2 in the step (a
switch inside a step costs O(h²) locally, as in the conservative baseline).

The Jacobian comes from 2 n_l + 1 tangent columns propagated with the step; it is
Φ − I for the monodromy Φ of the discrete map, whose eigenvalues are the Floquet
multipliers (recorded at every point: they cost nothing extra).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as la

from ... import _validate as check
from ...core.measures import check_dof, harmonic_content, mean_energy, refined_max, sample_coefficients
from ...core.problem import ForcedProblemBase, OneEvaluation
from ...model.model import Model
from ..mms.forced import Excitation, harmonic_force
from ._forced_kernels import _forced_integrate

__all__ = ["ShootingForcedProblem"]


class ShootingForcedProblem(OneEvaluation, ForcedProblemBase):
    """Forced shooting (trapezoidal AVF rule) as a continuation problem in (z₀, Ω).

    Parameters
    ----------
    model : Model
        One contact, massless contact DOF.
    force : Excitation or array_like (n_dof,)
    steps_per_period : int
        Time steps N per period (>= 8).
    stability : bool
        Record the multipliers of the discrete map (default True).
    """

    method = "shooting"
    setting_names = ("N",)
    H = 0

    def __init__(self, model: Model, force, steps_per_period: int = 256, stability: bool = True):
        if not isinstance(model, Model):
            raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
        if model.n_contacts != 1:
            raise ValueError(f"forced shooting handles one contact; the model has {model.n_contacts}")
        model.require_massless_contacts("forced shooting")
        self.model = model
        self.N = check.integer("steps_per_period", steps_per_period, minimum=8)
        exc = force if isinstance(force, Excitation) else harmonic_force(model, force)
        if isinstance(force, Excitation):
            harmonic_force(model, force.vector)
        self.excitation = exc
        self.stability = bool(stability)
        b = model.blocks
        freqs, modes = model.linear_modes(len(model.l))
        self.Phi = modes[model.l]  # mass-normalised: Φᵀ M Φ = I
        self.Phi_c = modes[model.c]
        self.w2 = (2 * np.pi * freqs) ** 2
        n = len(model.l)
        self.n_l = n
        C = b["C_ll"]
        Gam = self.Phi.T @ (C @ self.Phi) if C is not None else np.zeros((n, n))
        off = Gam - np.diag(np.diag(Gam))
        self.diag = bool(np.abs(off).max() <= 1e-7 * max(np.abs(np.diag(Gam)).max(), 1e-300))
        self.Gam = np.diag(Gam).copy()[None, :] if self.diag else Gam
        # contact: free gap h = gap + a·q_l, λ = k_c max(0, −h)
        w_c = model.w_c
        K_cc, K_lc = b["K_cc"], b["K_lc"]
        e = la.solve(K_cc, w_c)
        self.contact_stiffness = 1.0 / float(w_c @ e)
        self.a_l = -K_lc @ e
        self.a = self.Phi.T @ self.a_l  # modal
        self.gap = float(model.gap)
        self.F_modal = self.Phi.T @ exc.vector[model.l]  # complex
        self.amplitude_dof = model.amplitude_dof
        self.omega_ref = 2 * np.pi * float(freqs[0])
        phi = modes[:, 0] / abs(modes[model.amplitude_dof, 0])
        length = self.gap if self.gap > 0 else 1.0
        s = length * np.maximum(np.abs(phi[model.l]), 1e-3 * np.abs(phi[model.l]).max())
        self.xscale = np.concatenate([s, s * self.omega_ref])  # positions, velocities
        self.colscale = np.concatenate([self.xscale, [self.omega_ref]])
        self.rowscale = self.xscale
        self.n_unknowns = 2 * n + 1
        self._cache = None

    # ------------------------------------------------------------------ unknowns
    def unpack(self, u):
        y = np.asarray(u, dtype=float) * self.colscale
        return y[:-1], float(y[-1])

    def pack(self, z, omega):
        return np.concatenate([np.asarray(z, dtype=float), [omega]]) / self.colscale

    def linear_response_point(self, frequency: float) -> np.ndarray:
        """The linear steady state (stop ignored) of the discrete map at ``frequency`` (Hz),
        shape (n_unknowns,).

        The map without the contact force is affine in z₀, so one Newton step from z₀ = 0
        solves it exactly (to round-off). It is the continuous linear response at the
        warped frequency Ω̃ = (2/h) tan(Ωh/2), h = 2π/(NΩ), of the trapezoidal rule."""
        omega = 2 * np.pi * check.positive("frequency", frequency)
        z = np.zeros(2 * self.n_l)
        R, J = self._residual(z, omega, True, contact=False)
        z = z - np.linalg.solve(J[:, :-1], R)
        return self.pack(z, omega)

    def initial_tangent(self):
        t = np.zeros(self.n_unknowns)
        t[-1] = 1.0
        return t

    # ------------------------------------------------------------------ integration
    def _matrices(self, h):
        if self._cache is not None and self._cache[0] == h:
            return self._cache[1]
        c1, c5 = 4.0 / h**2, 2.0 / h
        if self.diag:
            S = c1 + c5 * self.Gam[0] + self.w2
            Sinv, P = (1.0 / S)[None, :], (c1 + c5 * self.Gam[0] - self.w2)[None, :]
            z = Sinv[0] * self.a
        else:
            S = c1 * np.eye(self.n_l) + c5 * self.Gam + np.diag(self.w2)
            Sinv = np.linalg.inv(S)
            P = c1 * np.eye(self.n_l) + c5 * self.Gam - np.diag(self.w2)
            z = Sinv @ self.a
        out = (np.ascontiguousarray(Sinv), np.ascontiguousarray(P), z, float(self.a @ z))
        self._cache = (h, out)
        return out

    def _integrate(self, z0, omega, tangents: bool, store: bool = False, contact: bool = True):
        """One period of the map from z₀ at Ω (rad/s): the end state (q, v) and tangents
        (dq, dv) in modal coordinates, and the stored steps (Q, V, λ) when ``store``;
        ``contact=False``: the open structure (no contact force)."""
        if not (np.isfinite(omega) and omega > 0):
            raise ValueError(f"the frequency unknown must be positive, got Ω = {omega!r} rad/s")
        n, N = self.n_l, self.N
        h = 2 * np.pi / omega / N
        Sinv, P, z, alpha = self._matrices(h)
        sig, dsig = self.excitation.scale(omega)
        phase = np.exp(2j * np.pi * np.arange(N + 1) / N)
        G = np.ascontiguousarray((sig * np.outer(phase, self.F_modal)).real)
        q = np.ascontiguousarray(self.Phi.T @ (self.model.blocks["M_ll"] @ z0[:n]))
        v = np.ascontiguousarray(self.Phi.T @ (self.model.blocks["M_ll"] @ z0[n:]))
        m = 2 * n + 1 if tangents else 0
        dq = np.zeros((n, m))
        dv = np.zeros((n, m))
        dh = np.zeros(m)
        dG = np.zeros(m)
        if tangents:
            # columns: initial q_l, v_l (physical, through Φᵀ M) and Ω
            PtM = self.Phi.T @ self.model.blocks["M_ll"].toarray()
            dq[:, :n] = PtM
            dv[:, n:2 * n] = PtM
            dh[-1] = -h / omega
            dG[-1] = dsig / sig
        Q = np.empty((N + 1, n)) if store else np.empty((0, n))
        V = np.empty((N + 1, n)) if store else np.empty((0, n))
        LAM = np.empty(N + 1) if store else np.empty(0)
        kc = self.contact_stiffness if contact else 0.0
        _forced_integrate(Sinv, P, self.Gam, self.diag, self.a, z, alpha, kc, self.gap, h,
                          dh, G, dG, q, v, dq, dv, Q, V, LAM)
        return q, v, dq, dv, (Q, V, LAM)

    def _residual(self, z0, omega, jacobian, contact: bool = True):
        n = self.n_l
        q, v, dq, dv, _ = self._integrate(z0, omega, jacobian, contact=contact)
        zT = np.concatenate([self.Phi @ q, self.Phi @ v])
        R = zT - z0
        if not jacobian:
            return R, None
        J = np.vstack([self.Phi @ dq, self.Phi @ dv])
        J[:, :2 * n] -= np.eye(2 * n)
        return R, J


    def _evaluate(self, u, jacobian: bool):
        """Scaled residual (2 n_l,) and, if asked, its Jacobian (2 n_l, 2 n_l + 1)."""
        z0, omega = self.unpack(u)
        R, J = self._residual(z0, omega, jacobian)
        R = R / self.rowscale
        if not jacobian:
            return R
        return R, J * self.colscale[None, :] / self.rowscale[:, None]

    def floquet_multipliers(self, u) -> np.ndarray:
        """Multipliers of the discrete map's monodromy at ``u``, by decreasing modulus."""
        z0, omega = self.unpack(u)
        _, J = self._residual(z0, omega, True)
        mu = la.eigvals(J[:, :-1] + np.eye(2 * self.n_l))
        return mu[np.argsort(-np.abs(mu), kind="stable")]

    # ------------------------------------------------------------------ results
    def trajectory(self, u):
        """(t (N+1,), q (n_dof, N+1), λ (N+1,)) at the step instants over one period."""
        z0, omega = self.unpack(u)
        _, _, _, _, (Q, V, LAM) = self._integrate(z0, omega, False, store=True)
        ql = self.Phi @ Q.T
        model = self.model
        closed = LAM > 0
        e = la.solve(model.blocks["K_cc"], model.w_c)
        qc = -la.solve(model.blocks["K_cc"], model.blocks["K_lc"].T @ ql) + np.outer(e, LAM)
        q = np.empty((model.n_dof, self.N + 1))
        q[model.l], q[model.c] = ql, qc
        del closed
        return 2 * np.pi / omega * np.arange(self.N + 1) / self.N, q, LAM

    def time_signals(self, u, dofs=None, n_samples: int | None = None):
        """The step samples (t, q) over one period (``n_samples`` is ignored: the N steps)."""
        t, q, _ = self.trajectory(u)
        return t[:-1], (q if dofs is None else q[np.atleast_1d(dofs)])[:, :-1]

    def contact_force(self, u, n_samples: int | None = None):
        t, _, lam = self.trajectory(u)
        return t[:-1], lam[None, :-1]

    def harmonic_content(self, u, dof=None, harmonics: int = 10):
        """|Q_k|, k = 0..harmonics, of ``dof`` (default the amplitude DOF) from the DFT of
        the N step samples over one period; shape (harmonics+1,)."""
        dof = check_dof(dof, self.model.n_dof, self.amplitude_dof)
        _, q, _ = self.trajectory(u)
        return harmonic_content(sample_coefficients(q[dof, :-1], harmonics))

    def monitor(self, u) -> dict:
        """frequency, amplitude (largest |q| at the steps), phase, energy, contact_force_max,
        and the multipliers (floquet_max, stable, floquet)."""
        z0, omega = self.unpack(u)
        t, q, lam = self.trajectory(u)
        qa = q[self.amplitude_dof, :-1]
        Qh = sample_coefficients(q[:, :-1], 10)
        q1 = Qh[self.amplitude_dof, 1] - 1j * Qh[self.amplitude_dof, 2]
        lag = np.angle(self.excitation.reference) - np.angle(q1)
        rec = {"frequency": omega / (2 * np.pi), "amplitude": max(refined_max(qa), refined_max(-qa)),
               "phase": float((lag + 0.5 * np.pi) % (2 * np.pi) - 0.5 * np.pi),
               "energy": mean_energy(self.model, Qh, omega),
               "contact_force_max": refined_max(lam[:-1]) if lam.max() > 0 else 0.0}
        if self.stability:
            mu = self.floquet_multipliers(u)
            rec.update(floquet_max=float(np.abs(mu[0])), stable=float(np.abs(mu[0]) <= 1 + 1e-6), floquet=mu)
        return rec
