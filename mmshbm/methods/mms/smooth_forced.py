"""MMS-HBM forced responses of models with nonlinear elements (no rigid stops).

The damped structure under a harmonic excitation with elements,

    M q'' + C q' + K q + Σ w φ(wᵀ q_e) = Re(σ(Ω) F̂ e^{iΩt}),

is condensed per harmonic onto the set s of the elements' DOFs and the amplitude DOF
(:mod:`~mmshbm.methods.mms.set_condense`, the damped dynamic stiffness
S_k = K − (kΩ)²M + ikΩC, the load condensed to P_1 = T_1ᵀ F̂). With the coefficients
x = [c_0, c_1, s_1, ..., c_H, s_H] of every DOF of the set (q = Re Σ Q_k e^{ikτ},
Q_k = c_k − i s_k) the balance of harmonic k is

    Re Z_k + F^c_k = 0,   −Im Z_k + F^s_k = 0,    Z_k = D_k(Ω) Q_k − δ_k1 σ P_1,

F the elements' force coefficients by AFT in the full basis
(:mod:`~mmshbm.methods.mms.element_aft`): n_s (2H+1) equations in as many unknowns and
Ω, continued by pseudo-arclength through the folds of the resonance peak.

Stability (``stability``): the Floquet multipliers of the orbit from the monodromy of the
variational equation M y'' + C y' + K_t(t) y = 0 on the DOFs with mass, K_t the
tangent stiffness with the elements' φ'(δ(t)) and the massless DOFs condensed statically
at each instant, integrated by the classical Runge–Kutta rule on 4 N steps per period.
"""

from __future__ import annotations

import numpy as np

from ... import _validate as check
from ...core.measures import mean_energy
from ...core.problem import ForcedProblemBase, OneEvaluation
from ...harmonic.harmonics import check_harmonics
from ...model.model import Model
from .element_aft import ElementForces, series_peak
from .forced import Excitation, harmonic_force
from .set_condense import SetCondensation
from .smooth import element_length, element_set

__all__ = ["ElementForcedProblem", "harmonic_balance"]

#: Runge–Kutta steps per sample of the AFT grid in the monodromy
_STEPS_PER_SAMPLE = 4
#: stability "auto": at most this many DOFs with mass
_AUTO_STABILITY_DOFS = 50


def harmonic_balance(aft: ElementForces, x: np.ndarray, D: np.ndarray, load, parameters=(), jacobian=True):
    """The balance of every harmonic on the condensed set, in the full basis (module docstring).

    Parameters
    ----------
    aft : ElementForces
        The elements' AFT (full basis).
    x : ndarray (2H+1, n_s)
        NLvib-ordered coefficients of the set's DOFs.
    D : ndarray (H+1, n_s, n_s), complex
        The condensed dynamic stiffness.
    load : ndarray (n_s,), complex, or None
        The condensed load of harmonic 1 (already times σ(Ω)).
    parameters : sequence of (∂D/∂p (H+1, n_s, n_s), ∂load/∂p (n_s,) or None)
        One per parameter p whose column is asked.

    Returns
    -------
    R : ndarray (2H+1, n_s)
        Re Z_k + F^c_k and −Im Z_k + F^s_k (F^c_0 + D_0 c_0 for k = 0).
    J : ndarray (2H+1, n_s, 2H+1, n_s) or None
        ∂R/∂x.
    dR : list of ndarray (2H+1, n_s)
        ∂R/∂p for each of ``parameters``.
    """
    H, n_s = len(D) - 1, x.shape[1]
    R, dF = aft.evaluate(x, jacobian)
    R = R.copy()
    R[0] += (D[0] @ x[0]).real
    J = dF if jacobian else None
    if jacobian:
        J[0, :, 0, :] += D[0].real
    dR = [np.zeros((2 * H + 1, n_s)) for _ in parameters]
    for (dD, _), out in zip(parameters, dR, strict=True):
        out[0] = (dD[0] @ x[0]).real
    for k in range(1, H + 1):
        Q = x[2 * k - 1] - 1j * x[2 * k]
        Z = D[k] @ Q
        if k == 1 and load is not None:
            Z = Z - load
        R[2 * k - 1] += Z.real
        R[2 * k] -= Z.imag
        if jacobian:
            J[2 * k - 1, :, 2 * k - 1, :] += D[k].real
            J[2 * k - 1, :, 2 * k, :] += D[k].imag
            J[2 * k, :, 2 * k - 1, :] -= D[k].imag
            J[2 * k, :, 2 * k, :] += D[k].real
        for (dD, dload), out in zip(parameters, dR, strict=True):
            dZ = dD[k] @ Q
            if k == 1 and dload is not None:
                dZ = dZ - dload
            out[2 * k - 1], out[2 * k] = dZ.real, -dZ.imag
    return R, J, dR


class ElementForcedProblem(OneEvaluation, ForcedProblemBase):
    """The forced response of a model with elements (module docstring), a continuation
    problem in (x, Ω).

    Parameters
    ----------
    model : Model
        With elements, damped (``model.damping``), no stops and no friction.
    force : Excitation or array_like (n_dof,)
        :func:`~mmshbm.methods.mms.forced.harmonic_force` or
        :func:`~mmshbm.methods.mms.forced.base_excitation`.
    harmonics : int
        H >= 1.
    n_samples : int, optional
        AFT samples per period N >= 2H+1 (default
        :func:`~mmshbm.harmonic.harmonics.default_n_samples`).
    stability : bool or "auto"
        Floquet multipliers at every point; "auto": with at most 50 DOFs with mass.

    Notes
    -----
    Scaled unknowns ``u = [x / xscale, Ω / ω_ref]``, ω_ref the first linear frequency.
    Monitored: frequency (Hz), amplitude (largest |q| of the amplitude DOF, m), phase (rad,
    lag of its fundamental behind the excitation), energy (J, period mean of kinetic and
    potential energy, the elements' included), contact_force_max (0: no stops), and with
    stability ``floquet_max``, ``stable`` and ``floquet``.
    """

    method = "mmshbm"
    setting_names = ("H", "N")

    def __init__(self, model: Model, force, harmonics: int = 5, n_samples: int | None = None,
                 stability: bool | str = "auto"):
        if not isinstance(model, Model):
            raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
        if not model.elements:
            raise ValueError("the model has no elements: use ForcedResponseProblem (frequency_response does)")
        if model.contacts or model.friction:
            raise NotImplementedError("forced responses of models with elements take no stops or friction "
                                      "contacts yet (make the stop a CompliantStop element)")
        excitation = force if isinstance(force, Excitation) else harmonic_force(model, force)
        if isinstance(force, Excitation):
            harmonic_force(model, force.vector)  # validate the length and the massless DOFs
        self.model, self.excitation = model, excitation
        self.H, self.N = check_harmonics(harmonics, n_samples)
        if not (isinstance(stability, bool) or stability == "auto"):
            raise ValueError(f"stability must be True, False or 'auto', got {stability!r}")
        self.stability = len(model.l) <= _AUTO_STABILITY_DOFS if stability == "auto" else bool(stability)
        self.set_dofs, _ = element_set(model)
        s = self.set_dofs
        self.n_s = len(s)
        self.cond = SetCondensation(model, s)
        D0 = self.cond.dynamic_stiffness(0.0, 0, derivative=False)[0][0]
        self.aft = ElementForces(model.elements, s, self.H, self.N, cosine_only=False)
        self.amplitude_dof = int(model.amplitude_dof)
        self._amp = list(s).index(self.amplitude_dof)

        freqs, modes = model.linear_modes(1)
        self.linear_frequency = float(freqs[0])
        self.omega_ref = 2 * np.pi * self.linear_frequency
        phi = modes[s, 0]
        shape = np.abs(phi) / max(np.abs(phi).max(), 1e-300)
        length = element_length(model, D0, s)
        self.xscale_dof = length * np.maximum(shape, 1e-3)
        n_b = 2 * self.H + 1
        self.n_x = n_b * self.n_s
        self.xscale = np.tile(self.xscale_dof, n_b)
        self.rowscale = np.tile(np.abs(D0) @ self.xscale_dof, n_b)
        self.colscale = np.concatenate([self.xscale, [self.omega_ref]])
        self.n_unknowns = self.n_x + 1
        self._cached = (None, None)
        self._floquet_setup = None
        #: residual (+ Jacobian) evaluations so far
        self.evaluations = 0

    # ------------------------------------------------------------------ unknowns
    def unpack(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """Scaled unknowns -> (x (2H+1, n_s) NLvib-ordered coefficients of the set's DOFs, Ω rad/s)."""
        if np.shape(u) != (self.n_unknowns,):
            raise ValueError(f"u must have shape ({self.n_unknowns},), got {np.shape(u)}")
        y = np.asarray(u, dtype=float) * self.colscale
        return y[:-1].reshape(2 * self.H + 1, self.n_s), float(y[-1])

    def pack(self, x: np.ndarray, omega: float) -> np.ndarray:
        return np.concatenate([np.asarray(x, dtype=float).ravel(), [omega]]) / self.colscale

    def linear_response_point(self, frequency: float) -> np.ndarray:
        """Scaled unknowns of the linear response (elements left out) at ``frequency`` (Hz)."""
        omega = 2 * np.pi * check.positive("frequency", frequency)
        D, P = self._condensed(omega, False)[:2]
        Q = np.linalg.solve(D[1], P)
        x = np.zeros((2 * self.H + 1, self.n_s))
        x[1], x[2] = Q.real, -Q.imag
        return self.pack(x, omega)

    def start_point(self, frequency: float, max_iter: int = 40) -> np.ndarray:
        """The response at ``frequency`` (Hz) by Newton at fixed Ω from the linear one (the
        linear response itself when Newton does not converge: the continuation's first
        corrector then tries)."""
        u = self.linear_response_point(frequency)
        for _ in range(max_iter):
            R, J = self._evaluate(u, True)
            if not np.all(np.isfinite(R)):
                break
            if np.abs(R).max() < 1e-12:
                return u
            try:
                u = u - np.concatenate([np.linalg.solve(J[:, :-1], R), [0.0]])
            except np.linalg.LinAlgError:
                break
        return self.linear_response_point(frequency)

    def initial_tangent(self, u: np.ndarray | None = None) -> np.ndarray:
        """Increasing Ω."""
        t = np.zeros(self.n_unknowns)
        t[-1] = 1.0
        return t

    def frequency_of(self, u: np.ndarray) -> float:
        return float(u[-1] * self.colscale[-1]) / (2 * np.pi)

    # ------------------------------------------------------------------ residual
    def _condensed(self, omega: float, derivative: bool):
        """(D (H+1, n_s, n_s) complex, σP_1 (n_s,), ∂D/∂Ω, ∂(σP_1)/∂Ω) at Ω."""
        last, kept = self._cached
        if last == omega and (kept[2] is not None or not derivative):
            return kept
        D, dD = self.cond.dynamic_stiffness(omega, self.H, derivative=derivative, damped=True)
        P, dP, _ = self.cond.condensed_load(omega, 1, self.excitation.vector, self.H)
        sigma, dsigma = self.excitation.scale(omega)
        kept = (D, sigma * P, dD, (sigma * dP + dsigma * P) if derivative else None)
        self._cached = (omega, kept)
        return kept

    def _evaluate(self, u: np.ndarray, jacobian: bool):
        """Scaled residual (n_x,) and, if asked, its Jacobian (n_x, n_x + 1)."""
        self.evaluations += 1
        x, omega = self.unpack(u)
        D, P, dD, dP = self._condensed(omega, jacobian)
        R, J, dR = harmonic_balance(self.aft, x, D, P, [(dD, dP)] if jacobian else [], jacobian)
        R = R.ravel() / self.rowscale
        if not jacobian:
            return R
        dW = dR[0]
        Jm = np.empty((self.n_x, self.n_x + 1))
        Jm[:, :-1] = J.reshape(self.n_x, self.n_x) * self.xscale[None, :]
        Jm[:, -1] = dW.ravel() * self.omega_ref
        Jm /= self.rowscale[:, None]
        return R, Jm

    # ------------------------------------------------------------------ results
    def coefficients(self, u: np.ndarray) -> np.ndarray:
        """NLvib-ordered coefficients (n_dof, 2H+1) of every DOF."""
        x, omega = self.unpack(u)
        return self._coefficients(x, omega)

    def _coefficients(self, x: np.ndarray, omega: float) -> np.ndarray:
        cond = self.cond
        X = cond.recover(omega, self.H, damped=True)
        Q = np.zeros((self.model.n_dof, 2 * self.H + 1))
        Q[cond.s] = x.T
        if cond.n_o:
            sigma, _ = self.excitation.scale(omega)
            Y = cond.condensed_load(omega, 1, self.excitation.vector, self.H)[2]
            Q[cond.o, 0] = -(X[0] @ x[0]).real
            for k in range(1, self.H + 1):
                q_o = -X[k] @ (x[2 * k - 1] - 1j * x[2 * k]) + (sigma * Y if k == 1 else 0.0)
                Q[cond.o, 2 * k - 1], Q[cond.o, 2 * k] = q_o.real, -q_o.imag
        return Q

    def phase(self, q_coeffs: np.ndarray) -> float:
        """Lag (rad) of the fundamental of ``q_coeffs`` behind the excitation, in [−π/2, 3π/2)."""
        q1 = q_coeffs[1] - 1j * q_coeffs[2]
        lag = np.angle(self.excitation.reference) - np.angle(q1)
        return float((lag + 0.5 * np.pi) % (2 * np.pi) - 0.5 * np.pi)

    def monitor(self, u: np.ndarray) -> dict:
        """frequency (Hz), amplitude (m), phase (rad), energy (J), contact_force_max (0), and
        with stability floquet_max, stable (1.0/0.0) and floquet (multipliers)."""
        x, omega = self.unpack(u)
        Q = self._coefficients(x, omega)
        q = Q[self.amplitude_dof]
        energy = mean_energy(self.model, Q, omega) + self.aft.mean_potential(x)
        rec = {"frequency": omega / (2 * np.pi), "amplitude": series_peak(q, 0.0, max(512, 8 * self.N)),
               "phase": self.phase(q), "energy": energy, "contact_force_max": 0.0}
        if self.stability:
            mu = self.floquet_multipliers(u)
            rec["floquet_max"] = float(np.abs(mu[0]))
            rec["stable"] = float(np.abs(mu[0]) <= 1.0 + 1e-6)
            rec["floquet"] = mu
        return rec

    # ------------------------------------------------------------------ stability
    def floquet_multipliers(self, u: np.ndarray) -> np.ndarray:
        """Floquet multipliers (2 n_l,) of the orbit at ``u``, sorted by decreasing modulus
        (module docstring)."""
        x, omega = self.unpack(u)
        model = self.model
        if self._floquet_setup is None:
            l, c = model.l, model.c
            K = model.K.toarray()
            M_ll = model.M.toarray()[np.ix_(l, l)]
            C_ll = (model.damping.toarray()[np.ix_(l, l)] if model.damping is not None
                    else np.zeros((len(l), len(l))))
            self._floquet_setup = (l, c, K, np.linalg.inv(M_ll), C_ll)
        l, c, K, Minv, C_ll = self._floquet_setup
        n_l = len(l)
        k = np.arange(1, self.H + 1)

        def tangent(t):
            """A(τ) of y' = A y, y = [y_l, y_l'] in τ = Ωt (time scaled by 1/Ω)."""
            basis = np.concatenate([[1.0], np.column_stack([np.cos(k * t), np.sin(k * t)]).ravel()])
            q_s = basis @ x
            Kt = K.copy()
            for element, pos in zip(self.aft.elements, self.aft.positions, strict=True):
                _, df = element.sampled(q_s[pos][:, None])
                dofs = list(element.dofs)
                Kt[np.ix_(dofs, dofs)] += df[:, :, 0]
            K_eff = Kt[np.ix_(l, l)]
            if len(c):
                K_eff = K_eff - Kt[np.ix_(l, c)] @ np.linalg.solve(Kt[np.ix_(c, c)], Kt[np.ix_(c, l)])
            A = np.zeros((2 * n_l, 2 * n_l))
            A[:n_l, n_l:] = np.eye(n_l) / omega
            A[n_l:, :n_l] = -Minv @ K_eff / omega
            A[n_l:, n_l:] = -Minv @ C_ll / omega
            return A

        n_steps = _STEPS_PER_SAMPLE * self.N
        h = 2 * np.pi / n_steps
        Phi = np.eye(2 * n_l)
        A0 = tangent(0.0)
        for i in range(n_steps):
            t = i * h
            Am, A1 = tangent(t + 0.5 * h), tangent(t + h)
            k1 = A0 @ Phi
            k2 = Am @ (Phi + 0.5 * h * k1)
            k3 = Am @ (Phi + 0.5 * h * k2)
            k4 = A1 @ (Phi + h * k3)
            Phi = Phi + (h / 6.0) * (k1 + 2 * k2 + 2 * k3 + k4)
            A0 = A1
        mu = np.linalg.eigvals(Phi)
        return mu[np.argsort(-np.abs(mu))]
