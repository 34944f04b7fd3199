"""Phase resonance by MMS-HBM: the forced responses whose fundamental lags the force by 90°.

The phase-locked-loop test of experimental nonlinear modal analysis drives the structure and adjusts the
excitation frequency until the response's fundamental lags the force by π/2; raising the
force level traces the *phase-resonance backbone*, which for light damping approximates
the nonlinear mode (Peeters et al. 2011). Here it is the one-parameter family of forced
responses (:class:`~mmshbm.methods.mms.forced.ForcedResponseProblem`) with the force scaled
by an unknown σ and one more equation, the phase condition on the amplitude DOF's
fundamental q̂_1 = a_1 − i b_1 against the force reference ρ e^{iθ},

    Re(q̂_1 e^{−iθ}) = a_1 cos θ − b_1 sin θ = 0,

started in the linear regime (Ω = ω_1 corrected by Newton, small σ) with the lag +90°
(b_1 cos θ + a_1 sin θ > 0), which continuation keeps. Unknowns u = [x, σ, Ω] (scaled);
the amplitude DOF must be one of the massless DOFs (its coefficients are unknowns; for
the beam the tip). Monitored: the forced response's quantities (amplitude with the
backbone convention, so that it compares with ``mmshbm.backbone``) and ``force``, the
amplitude (N) of the largest force entry, σ |F̂|_max σ(Ω).
"""

from __future__ import annotations

import numpy as np

from ... import _validate as check
from ...core.problem import BackboneProblemBase
from ...model.model import Model
from .forced import Excitation, ForcedResponseProblem, harmonic_force

__all__ = ["PhaseResonanceProblem"]


class PhaseResonanceProblem(ForcedResponseProblem, BackboneProblemBase):
    """Phase-resonance backbone as a continuation problem in (x, σ, Ω).

    Parameters
    ----------
    model : Model
        Damped; the amplitude DOF massless.
    force : Excitation, its JSON dict, or array_like (n_dof,)
        The force pattern F̂ (its level is the unknown σ).
    harmonics, n_samples, r, backend, projection
        As for :class:`~mmshbm.methods.mms.forced.ForcedResponseProblem`.
    """

    method = "phase_resonance"
    _away_convention = True

    def __init__(self, model: Model, force=None, harmonics: int = 5, n_samples: int | None = None,
                 r: float | None = None, backend: str = "auto", projection: str = "exact"):
        if force is None:
            raise ValueError("phase resonance needs the force pattern: force=...")
        if isinstance(force, dict):
            force = Excitation.from_json(force)
        if not isinstance(force, Excitation):
            force = harmonic_force(model, force)
        super().__init__(model, force, harmonics, n_samples, r, backend, stability=False,
                         projection=projection)
        c = model.c
        i = int(np.searchsorted(c, self.amplitude_dof))
        if not (i < len(c) and c[i] == self.amplitude_dof):
            raise ValueError(f"the amplitude DOF {self.amplitude_dof} carries mass: phase resonance here "
                             "needs a massless amplitude DOF (model.with_amplitude_dof)")
        theta = float(np.angle(self.excitation.reference))
        self._row = np.zeros(self.n_x)
        self._row[self.n_c + i] = np.cos(theta)
        self._row[2 * self.n_c + i] = -np.sin(theta)
        self._amp_index = i
        # σ scale: the force level that drives the linear resonance to one gap
        lin = ForcedResponseProblem(model, force, harmonics, n_samples, r, backend, stability=False,
                                    projection=projection)
        x1, _ = lin.unpack(lin.linear_response_point(self.linear_frequency))
        q1 = np.hypot(x1[self.n_c + i], x1[2 * self.n_c + i])
        length = model.gap if model.gap > 0 else 1.0
        self.sigma_ref = length / q1
        self.colscale = np.concatenate([self.xscale, [self.sigma_ref, self.omega_ref]])
        self.n_unknowns = self.n_x + 2
        self._xrow = self._row * self.xscale / np.abs(self._row @ self.xscale + 1e-300)

    # ------------------------------------------------------------------ unknowns
    def unpack(self, u):
        """Scaled unknowns -> (x (n_x,), σ, Ω)."""
        if np.shape(u) != (self.n_unknowns,):
            raise ValueError(f"u must have shape ({self.n_unknowns},), got {np.shape(u)}")
        y = np.asarray(u, dtype=float) * self.colscale
        return y[:-2], float(y[-2]), float(y[-1])

    def _state(self, u):
        x, sigma, omega = self.unpack(u)
        return x, omega, sigma

    def pack3(self, x, sigma, omega):
        return np.concatenate([np.asarray(x, dtype=float), [sigma, omega]]) / self.colscale

    def linear_mode_point(self, amplitude: float) -> np.ndarray:
        """The linear response at ω_1 scaled to ``amplitude`` (m) at the amplitude DOF (the
        phase condition is met by the first Newton correction)."""
        amplitude = check.positive("amplitude", amplitude)
        omega = self.omega_ref
        ch = self._condensed(omega)
        s, _ = self.excitation.scale(omega)
        Qc = np.linalg.solve(ch.D[1], s * ch.P[:, 0])
        sigma = amplitude / abs(Qc[self._amp_index])
        x = np.zeros(self.n_x)
        x[self.n_c:2 * self.n_c] = sigma * Qc.real
        x[2 * self.n_c:3 * self.n_c] = -sigma * Qc.imag
        return self.pack3(x, sigma, omega)

    def linear_point(self, amplitude: float) -> np.ndarray:
        """Alias of :meth:`linear_mode_point` (the start of a backbone, not a frequency)."""
        return self.linear_mode_point(amplitude)

    def initial_tangent(self):
        """Growing force level and response at fixed Ω."""
        t = self.linear_mode_point(1.0)
        t[-1] = 0.0
        return t / np.linalg.norm(t)

    # ------------------------------------------------------------------ residual
    def _evaluate(self, u, jacobian: bool):
        """Scaled residual (n_x + 1,) and, if asked, the Jacobian (n_x + 1, n_x + 2)."""
        x, sigma, omega = self.unpack(u)
        R, Jx, Jw, Js = self.residual_parts(x, omega, sigma, jacobian)
        out = np.empty(self.n_x + 1)
        out[:-1] = R / self.rowscale
        out[-1] = self._row @ x / self.xscale[self.n_c + self._amp_index]
        if not jacobian:
            return out
        J = np.zeros((self.n_x + 1, self.n_x + 2))
        J[:-1, :-2] = Jx * self.xscale[None, :]
        J[:-1, -2] = Js * self.sigma_ref
        J[:-1, -1] = Jw * self.omega_ref
        J[:-1] /= self.rowscale[:, None]
        J[-1, :-2] = self._row * self.xscale / self.xscale[self.n_c + self._amp_index]
        return out, J

    def monitor(self, u) -> dict:
        """The forced response's records plus ``force`` (N) and ``force_scale`` σ."""
        x, sigma, omega = self.unpack(u)
        rec = self._record(x, omega, sigma)
        s, _ = self.excitation.scale(omega)
        rec["force"] = float(sigma * s * np.abs(self.excitation.vector).max())
        rec["force_scale"] = sigma
        return rec
