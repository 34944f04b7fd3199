"""Baseline: classical harmonic balance on all DOFs of a model with elements (no stops).

The harmonic balance of general tools on a structure with smooth elements (a cubic or
polynomial spring, a compliant stop): every DOF is expanded in the cosine-only ansatz of
:mod:`mmshbm.methods.penalty.hbm`, nothing is condensed, and the elements' forces come by
alternating frequency–time (:mod:`mmshbm.methods.mms.element_aft`) on their DOFs:

    (K − (kΩ)² M) Q_k + F_k(Q_e) = 0,       k = 0..H, all n DOFs,

n (H+1) equations in n (H+1) + 1 unknowns (the Q_k and Ω). Its Jacobian is sparse: the
pattern of K and M per harmonic, a dense (H+1)² coupling on each element DOF pair, and the
Ω column −2k²Ω M Q_k. It solves the same truncated equations as the MMS-HBM element path
(:mod:`mmshbm.methods.mms.smooth`, which condenses them exactly onto the elements' DOFs),
with every DOF as an unknown: the cross-check of that condensation. A model with stops is
not taken here (the penalty springs of :mod:`~mmshbm.methods.penalty.hbm` beside elements
are not written yet).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ... import _validate as check
from ...core.problem import BackboneProblemBase, OneEvaluation
from ...harmonic.harmonics import check_harmonics
from ...model.linear_modes import amplitude_mode
from ...model.model import Model
from ..mms.element_aft import ElementForces, series_peak
from ..mms.set_condense import SetCondensation
from ..mms.smooth import element_length

__all__ = ["ElementHBMProblem"]


class ElementHBMProblem(OneEvaluation, BackboneProblemBase):
    """Classical cosine harmonic balance on all DOFs of a model with elements (module
    docstring).

    Parameters
    ----------
    model : Model
        With elements, no stops, no friction.
    harmonics : int
        H >= 1.
    n_samples : int, optional
        AFT samples N >= 2H+1 (default :func:`~mmshbm.harmonic.harmonics.default_n_samples`).
    mode : int
        The linear mode (1-based) the branch starts from.

    Notes
    -----
    Scaled unknowns ``u = [Q_0/s, ..., Q_H/s, Ω/ω_ref]``, Q_k (n_dof,) the cosine
    coefficients of every DOF, s the length of
    :func:`~mmshbm.methods.mms.smooth.element_length` times the linear mode's shape.
    """

    method = "penalty"
    setting_names = ("H", "N", "mode")

    def __init__(self, model: Model, harmonics: int = 5, n_samples: int | None = None, mode: int = 1):
        if not isinstance(model, Model):
            raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
        if not model.elements:
            raise ValueError("the model has no elements: use PenaltyHBMProblem")
        if model.contacts or model.friction:
            raise NotImplementedError("method 'penalty' takes elements only on models without stops or "
                                      "friction contacts: use method 'mmshbm' for elements beside stops")
        self.model = model
        self.H, self.N = check_harmonics(harmonics, n_samples)
        self.mode = check.integer("mode", mode, minimum=1)
        if self.mode > len(model.l):
            raise ValueError(f"mode must be <= the number of DOFs with mass ({len(model.l)}), "
                             f"got {self.mode}")
        self.n = n = model.n_dof
        self.K, self.M = model.K.tocsr(), model.M.tocsr()
        dofs = np.array(sorted({d for e in model.elements for d in e.dofs}), dtype=int)
        self.element_dofs = dofs
        self.aft = ElementForces(model.elements, dofs, self.H, self.N, cosine_only=True)
        self.linear_frequency, self.mode_shape = amplitude_mode(model, self.mode)
        self.omega_ref = 2 * np.pi * self.linear_frequency
        self.amplitude_dof = int(model.amplitude_dof)
        D0 = SetCondensation(model, dofs).dynamic_stiffness(0.0, 0, derivative=False)[0][0]
        length = element_length(model, D0, dofs)
        shape = np.abs(self.mode_shape)
        self.xscale = length * np.maximum(shape, 1e-3 * shape.max())
        self.colscale = np.concatenate([np.tile(self.xscale, self.H + 1), [self.omega_ref]])
        self.rowscale = np.tile(abs(self.K) @ self.xscale, self.H + 1)
        self.n_unknowns = (self.H + 1) * n + 1
        # the element coupling's rows and columns in the unknowns (harmonic-major)
        H1, n_e = self.H + 1, len(dofs)
        index = (np.arange(H1)[:, None] * n + dofs[None, :]).ravel()  # (H1 n_e,) in (k, e) order
        self._element_rows = np.repeat(index, H1 * n_e)
        self._element_cols = np.tile(index, H1 * n_e)
        self._k2 = np.arange(H1, dtype=float) ** 2
        self.evaluations = 0

    # ------------------------------------------------------------------ unknowns
    def unpack(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """Scaled unknowns -> (cosine coefficients Q (H+1, n_dof), Ω rad/s)."""
        if np.shape(u) != (self.n_unknowns,):
            raise ValueError(f"u must have shape ({self.n_unknowns},), got {np.shape(u)}")
        x = np.asarray(u, dtype=float) * self.colscale
        return x[:-1].reshape(self.H + 1, self.n), float(x[-1])

    def pack(self, Q: np.ndarray, omega: float) -> np.ndarray:
        return np.concatenate([np.asarray(Q, dtype=float).ravel(), [omega]]) / self.colscale

    def linear_mode_point(self, amplitude: float) -> np.ndarray:
        Q = np.zeros((self.H + 1, self.n))
        Q[1] = amplitude * self.mode_shape
        return self.pack(Q, self.omega_ref)

    def initial_tangent(self) -> np.ndarray:
        t = self.linear_mode_point(1.0)
        t[-1] = 0.0
        return t / np.linalg.norm(t)

    # ------------------------------------------------------------------ residual
    def _evaluate(self, u: np.ndarray, jacobian: bool):
        """Scaled residual (n (H+1),) and, if asked, the sparse Jacobian (n (H+1), n (H+1) + 1)."""
        self.evaluations += 1
        Q, omega = self.unpack(u)
        MQ = (self.M @ Q.T).T
        R = (self.K @ Q.T).T - (omega**2 * self._k2)[:, None] * MQ
        F, dF = self.aft.evaluate(Q[:, self.element_dofs], jacobian)
        R[:, self.element_dofs] += F
        R = R.ravel() / self.rowscale
        if not jacobian:
            return R
        blocks = sp.block_diag([self.K - (k * omega) ** 2 * self.M for k in range(self.H + 1)], format="csr")
        n_r = self.n_unknowns - 1
        coupling = sp.csr_matrix((dF.ravel(), (self._element_rows, self._element_cols)), shape=(n_r, n_r))
        d_omega = (-2.0 * omega * self._k2[:, None] * MQ).ravel()
        J = sp.hstack([blocks + coupling, sp.csr_matrix(d_omega[:, None])], format="csr")
        J = sp.diags(1.0 / self.rowscale) @ J @ sp.diags(self.colscale)
        return R, J.tocsr()

    # ------------------------------------------------------------------ results
    def coefficients(self, u: np.ndarray) -> np.ndarray:
        """NLvib-ordered coefficients (n_dof, 2H+1) of every DOF (sine terms zero)."""
        Q, _ = self.unpack(u)
        out = np.zeros((self.n, 2 * self.H + 1))
        out[:, 0] = Q[0]
        out[:, 1::2] = Q[1:].T
        return out

    def monitor(self, u: np.ndarray) -> dict:
        """frequency (Hz), amplitude (m, largest |q| of the amplitude DOF), energy (J, the
        potential energy at the turning point τ = 0), contact_force_max (0: no stops)."""
        Q, omega = self.unpack(u)
        q0 = Q.sum(axis=0)
        energy = 0.5 * float(q0 @ (self.K @ q0)) + self.aft.potential(q0[self.element_dofs])
        return {"frequency": omega / (2 * np.pi),
                "amplitude": series_peak(self.coefficients(u)[self.amplitude_dof], 0.0, max(512, 8 * self.N)),
                "energy": energy, "contact_force_max": 0.0}
