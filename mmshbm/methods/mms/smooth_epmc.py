"""Damped nonlinear modes (EPMC) of models with nonlinear elements (no stops).

The extended periodic motion concept of :mod:`mmshbm.methods.mms.epmc` on the element
path: the autonomous system with the negative mass-proportional damping −ξM,

    M q'' + (C − ξ M) q' + K q + Σ w φ(wᵀ q_e) = 0,

condensed per harmonic onto the elements' DOFs and the amplitude DOF with
S_k = K − (kΩ)²M + ikΩ(C − ξM) (:mod:`~mmshbm.methods.mms.set_condense`), the elements
by AFT in the full basis (:func:`~mmshbm.methods.mms.smooth_forced.harmonic_balance`
without a load). Unknowns u = [x, ξ, Ω] (scaled), equations the n_s (2H+1) balances and
the phase anchor (the sine coefficient of the amplitude DOF's fundamental is zero). The
modal damping ratio is ξ/(2Ω); for mass-proportional damping C = αM the mode is the
conservative backbone with ξ = α exactly.
"""

from __future__ import annotations

import numpy as np

from ... import _validate as check
from ...core.measures import mean_energy
from ...core.problem import BackboneProblemBase, OneEvaluation
from ...harmonic.harmonics import check_harmonics
from ...model.model import Model
from .element_aft import ElementForces, series_peak
from .epmc import fundamental_share
from .set_condense import SetCondensation
from .smooth import element_length, element_set
from .smooth_forced import harmonic_balance

__all__ = ["ElementEPMCProblem"]


class ElementEPMCProblem(OneEvaluation, BackboneProblemBase):
    """The damped nonlinear mode of a model with elements (module docstring).

    Parameters
    ----------
    model : Model
        With elements and damping, no stops, no friction.
    harmonics : int
        H >= 1.
    n_samples : int, optional
        AFT samples N >= 2H+1.
    mode : int
        The linear mode (1-based) the branch starts from.
    """

    method = "epmc"
    setting_names = ("H", "N", "mode")

    def __init__(self, model: Model, harmonics: int = 5, n_samples: int | None = None, mode: int = 1):
        if not isinstance(model, Model):
            raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
        if not model.elements:
            raise ValueError("the model has no elements: use EPMCProblem")
        if model.contacts or model.friction:
            raise NotImplementedError("EPMC takes elements only on models without stops or friction contacts")
        if model.damping is None:
            raise ValueError("EPMC needs a damped model (model.with_damping(...)); the conservative "
                             "backbone is method 'mmshbm'")
        self.model = model
        self.H, self.N = check_harmonics(harmonics, n_samples)
        self.mode = check.integer("mode", mode, minimum=1)
        if self.mode > len(model.l):
            raise ValueError(f"mode must be <= the number of DOFs with mass ({len(model.l)}), "
                             f"got {self.mode}")
        self.set_dofs, _ = element_set(model)
        s = self.set_dofs
        self.n_s = len(s)
        self.cond = SetCondensation(model, s)
        D0 = self.cond.dynamic_stiffness(0.0, 0, derivative=False)[0][0]
        self.aft = ElementForces(model.elements, s, self.H, self.N, cosine_only=False)
        self.amplitude_dof = int(model.amplitude_dof)
        self._amp = list(s).index(self.amplitude_dof)
        freqs, modes = model.linear_modes(self.mode)
        phi = modes[:, -1]
        ref = phi[self.amplitude_dof]
        if abs(ref) < 1e-12 * np.max(np.abs(phi)):
            raise ValueError(f"linear mode {self.mode} does not move the amplitude DOF {self.amplitude_dof}")
        self.mode_frequency = float(freqs[-1])
        self.omega_ref = 2 * np.pi * self.mode_frequency
        self.mode_shape = phi[s] / abs(ref)
        self.mode_xi = float(phi @ (model.damping @ phi))  # 2ζω of the mass-normalised mode
        shape = np.abs(self.mode_shape)
        length = element_length(model, D0, s)
        xscale_dof = length * np.maximum(shape, 1e-3 * shape.max())
        n_b = 2 * self.H + 1
        self.n_x = n_b * self.n_s
        self.xscale = np.tile(xscale_dof, n_b)
        self.rowscale = np.tile(np.abs(D0) @ xscale_dof, n_b)
        self.colscale = np.concatenate([self.xscale, [self.omega_ref, self.omega_ref]])
        self.n_unknowns = self.n_x + 2
        self._anchor_col = 2 * self.n_s + self._amp  # the sine of harmonic 1 of the amplitude DOF
        self._cached = (None, None)
        self.evaluations = 0

    # ------------------------------------------------------------------ unknowns
    def unpack(self, u: np.ndarray) -> tuple[np.ndarray, float, float]:
        """Scaled unknowns -> (x (2H+1, n_s), ξ (1/s), Ω (rad/s))."""
        if np.shape(u) != (self.n_unknowns,):
            raise ValueError(f"u must have shape ({self.n_unknowns},), got {np.shape(u)}")
        y = np.asarray(u, dtype=float) * self.colscale
        return y[:-2].reshape(2 * self.H + 1, self.n_s), float(y[-2]), float(y[-1])

    def pack(self, x: np.ndarray, xi: float, omega: float) -> np.ndarray:
        return np.concatenate([np.asarray(x, dtype=float).ravel(), [xi, omega]]) / self.colscale

    def linear_mode_point(self, amplitude: float) -> np.ndarray:
        """The linear mode with amplitude ``amplitude`` (m) at the amplitude DOF, ξ = φᵀCφ,
        Ω = ω_mode."""
        x = np.zeros((2 * self.H + 1, self.n_s))
        x[1] = check.positive("amplitude", amplitude) * self.mode_shape
        return self.pack(x, self.mode_xi, self.omega_ref)

    def initial_tangent(self) -> np.ndarray:
        """Growing amplitude at constant ξ and Ω."""
        t = self.linear_mode_point(1.0)
        t[-2:] = 0.0
        return t / np.linalg.norm(t)

    def frequency_of(self, u: np.ndarray) -> float:
        return float(u[-1] * self.colscale[-1]) / (2 * np.pi)

    # ------------------------------------------------------------------ residual
    def _condensed(self, omega: float, xi: float, derivative: bool):
        last, kept = self._cached
        if last == (omega, xi) and (kept[1] is not None or not derivative):
            return kept
        D, dD = self.cond.dynamic_stiffness(omega, self.H, derivative=derivative, damped=True, xi=xi)
        kept = (D, dD, self.cond.dD_dxi if derivative else None)
        self._cached = ((omega, xi), kept)
        return kept

    def _evaluate(self, u: np.ndarray, jacobian: bool):
        """Scaled residual (n_x + 1,) and, if asked, its Jacobian (n_x + 1, n_x + 2)."""
        self.evaluations += 1
        x, xi, omega = self.unpack(u)
        D, dD, dD_xi = self._condensed(omega, xi, jacobian)
        params = [(dD_xi, None), (dD, None)] if jacobian else []
        Rx, Jx, dR = harmonic_balance(self.aft, x, D, None, params, jacobian)
        R = np.empty(self.n_x + 1)
        R[:-1] = Rx.ravel() / self.rowscale
        R[-1] = u[self._anchor_col]
        if not jacobian:
            return R
        J = np.zeros((self.n_x + 1, self.n_x + 2))
        J[:-1, :-2] = Jx.reshape(self.n_x, self.n_x) * self.xscale[None, :]
        J[:-1, -2] = dR[0].ravel() * self.omega_ref
        J[:-1, -1] = dR[1].ravel() * self.omega_ref
        J[:-1] /= self.rowscale[:, None]
        J[-1, self._anchor_col] = 1.0
        return R, J

    # ------------------------------------------------------------------ results
    def coefficients(self, u: np.ndarray) -> np.ndarray:
        """NLvib-ordered coefficients (n_dof, 2H+1) of every DOF."""
        x, xi, omega = self.unpack(u)
        cond = self.cond
        X = cond.recover(omega, self.H, damped=True, xi=xi)
        Q = np.zeros((self.model.n_dof, 2 * self.H + 1))
        Q[cond.s] = x.T
        if cond.n_o:
            Q[cond.o, 0] = -(X[0] @ x[0]).real
            for k in range(1, self.H + 1):
                q_o = -X[k] @ (x[2 * k - 1] - 1j * x[2 * k])
                Q[cond.o, 2 * k - 1], Q[cond.o, 2 * k] = q_o.real, -q_o.imag
        return Q

    def monitor(self, u: np.ndarray) -> dict:
        """frequency (Hz), amplitude (m), energy (J, period mean), contact_force_max (0),
        damping_ratio (ξ/(2Ω)), xi (1/s), fundamental_share."""
        x, xi, omega = self.unpack(u)
        Q = self.coefficients(u)
        return {"frequency": omega / (2 * np.pi),
                "amplitude": series_peak(Q[self.amplitude_dof], 0.0, max(512, 8 * self.N)),
                "energy": mean_energy(self.model, Q, omega) + self.aft.mean_potential(x),
                "contact_force_max": 0.0, "damping_ratio": xi / (2 * omega), "xi": xi,
                "fundamental_share": fundamental_share(self.model.M, Q)}
