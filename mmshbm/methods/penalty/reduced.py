"""Baseline 1b: penalty harmonic balance on the contact DOFs, the rest condensed per harmonic.

The fair version of :mod:`mmshbm.methods.penalty.hbm` at scale. Like pyHarm's reduction to
the nonlinear DOFs, the linear structure is condensed exactly, harmonic by harmonic, onto
the massless DOFs ``c`` (which hold every contact DOF), with the *same* condensation
MMS-HBM uses (:func:`~mmshbm.harmonic.condense.make_condensation`: banded/sparse LU or the
modal back end). What is left differs from MMS-HBM only in the contact law:

    D_k(Ω) a_k + Σ_i e_i proj_k f_i(q_i(τ)) = 0,    k = 0..H,
    f_i(q) = k_p (max(0, q − hi_i) − max(0, lo_i − q)),

with [lo_i, hi_i] the admissible interval of contact DOF i
(:func:`~mmshbm.model.contact.admissible_intervals`: one-sided stops, clearances, several
contacts). Because eliminating the DOFs with mass from (K − (kΩ)²M) Q_k + f_k = 0 is exact
(they carry no nonlinear force), every solution of this problem is a solution of the
full-DOF penalty HBM with the same k_p, H and N and vice versa (tested to round-off on
the beam and the oscillator): the reduction changes the cost, not the answer.

Conventions follow :mod:`mmshbm.methods.mms.conservative`: cosine-only ansatz (phase anchored at a
turning point, energy identity removed), unknowns ``u = [a_0/s, ..., a_H/s, Ω/ω_ref]`` with
a_k ∈ R^{n_c} in ``model.c`` order and the same scales, so the arclength means the same in
both. AFT by a cosine table inside one Numba kernel
(:mod:`mmshbm.methods.penalty._reduced_kernels`); dense Jacobian ((H+1) n_c rows).

The default k_p is ``DEFAULT_PENALTY_FACTOR`` (10³) times the stiffest condensed static
contact stiffness k_c,i = 1/(D_0⁻¹)_ii, so that every contact's penetration error is at most
that of the single-contact baseline; N defaults to
:func:`~mmshbm.methods.penalty.defaults.penalty_n_samples`.
"""

from __future__ import annotations

import logging

import numpy as np

from ... import _validate as check
from ...core.measures import amplitude_peak, check_dof, condensed_energy, harmonic_content, refined_max
from ...core.problem import BackboneProblemBase, OneEvaluation
from ...harmonic.condense import make_condensation
from ...harmonic.harmonics import check_harmonics
from ...model.contact import admissible_intervals
from ...model.model import Model
from ._reduced_kernels import _penalty_reduced_residual
from .defaults import DEFAULT_PENALTY_FACTOR, penalty_n_samples

__all__ = ["ReducedPenaltyHBMProblem"]

log = logging.getLogger(__name__)


class ReducedPenaltyHBMProblem(OneEvaluation, BackboneProblemBase):
    """Penalty HBM condensed onto the massless (contact) DOFs, as a continuation problem.

    Parameters
    ----------
    model : Model
        The structure; every contact DOF must be massless (as for MMS-HBM).
    harmonics : int
        Highest harmonic H >= 1.
    n_samples : int, optional
        Time samples per period N >= 2H+1 (default
        :func:`~mmshbm.methods.penalty.defaults.penalty_n_samples`).
    penalty_stiffness : float, optional
        k_p (N/m), > 0; default 10³ × the stiffest condensed contact stiffness.
    mode : int
        Which linear mode (1-based) the branch starts from.
    backend : {"auto", "banded", "splu", "modal"}
        Condensation back end (:func:`~mmshbm.harmonic.condense.make_condensation`).

    Attributes
    ----------
    H, N : int
    n_unknowns : int
        n_c (H+1) + 1.
    penalty_stiffness, contact_stiffness : float
        k_p and the stiffest k_c,i (N/m).
    method : str
        ``"penalty-reduced"``.
    """

    method = "penalty-reduced"
    setting_names = ("H", "N", "mode", "penalty_stiffness")

    def __init__(self, model: Model, harmonics: int = 5, n_samples: int | None = None,
                 penalty_stiffness: float | None = None, mode: int = 1, backend: str = "auto"):
        if not isinstance(model, Model):
            raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
        model.require_massless_contacts("penalty HBM on the condensed contact DOFs ('penalty-reduced')")
        self.model = model
        self.H = check_harmonics(harmonics)[0]
        self.mode = check.integer("mode", mode, minimum=1)
        if self.mode > len(model.l):
            raise ValueError(f"mode must be <= the number of DOFs with mass ({len(model.l)}), "
                             f"got {self.mode}")
        self.amplitude_dof = model.amplitude_dof  # ValueError with several contacts and none named
        self.cond = make_condensation(model, backend, harmonics=self.H, mode=self.mode)
        c = model.c
        self.n_c = len(c)
        dofs, self.lo, self.hi = admissible_intervals(model.contacts)
        self.ci = np.searchsorted(c, dofs).astype(np.int64)
        compliance = np.diag(np.linalg.inv(self.cond.D0))[self.ci]
        self.contact_stiffness = float(np.max(1.0 / compliance))
        if penalty_stiffness is None:
            self.penalty_stiffness = DEFAULT_PENALTY_FACTOR * self.contact_stiffness
        else:
            self.penalty_stiffness = check.positive("penalty_stiffness", penalty_stiffness)
        if n_samples is None:
            n_samples = penalty_n_samples(self.H, self.penalty_stiffness / self.contact_stiffness)
        self.N = check_harmonics(self.H, n_samples)[1]
        log.debug("reduced penalty HBM: %d condensed DOFs, k_p = %.4g N/m, N = %d", self.n_c,
                  self.penalty_stiffness, self.N)
        one_sided = model.n_contacts == 1 and self.amplitude_dof == model.contacts[0].dof
        self._away_side = float(model.contacts[0].side) if one_sided else 0.0
        self._init_mode(c)
        self.n_unknowns = (self.H + 1) * self.n_c + 1
        tau = 2 * np.pi * np.arange(self.N) / self.N
        self._C = np.ascontiguousarray(np.cos(np.outer(np.arange(self.H + 1), tau)))
        self._q = np.empty(self.N)
        self._s = np.empty(self.N)
        self._P = np.empty((self.H + 1, self.H + 1))
        self._cached = (None, None, None)
        n_fine = max(512, 8 * self.N)
        self._tau_fine = 2 * np.pi * np.arange(n_fine) / n_fine
        self._cos_fine = np.cos(np.outer(np.arange(self.H + 1), self._tau_fine))

    def _init_mode(self, c: np.ndarray) -> None:
        """Linear mode ``self.mode`` scaled to a unit swing of the amplitude DOF, and the scales."""
        freqs, modes = self.model.linear_modes(self.mode)
        self.linear_frequency = float(freqs[-1])
        self.omega_ref = 2 * np.pi * self.linear_frequency
        phi = modes[:, -1]
        swing = phi[self.amplitude_dof]
        if abs(swing) < 1e-12 * np.max(np.abs(phi)):
            raise ValueError(f"linear mode {self.mode} does not move the amplitude DOF {self.amplitude_dof}")
        if not np.any(np.abs(phi[c[self.ci]]) > 1e-12 * np.max(np.abs(phi))):
            raise ValueError(f"linear mode {self.mode} does not move the contact DOFs: no impact")
        self.mode_shape_c = phi[c] / abs(swing)
        length = self.model.gap if self.model.gap > 0 else 1.0
        shape = np.abs(self.mode_shape_c)
        self.xscale = length * np.maximum(shape, 1e-3 * shape.max())
        self.colscale = np.concatenate([np.tile(self.xscale, self.H + 1), [self.omega_ref]])
        fscale = np.abs(self.cond.D0) @ self.xscale
        self.rowscale = np.tile(fscale, self.H + 1)

    # ------------------------------------------------------------------ unknowns
    def unpack(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """Scaled unknowns -> (cosine coefficients a (H+1, n_c) in m/rad, Ω in rad/s)."""
        if np.shape(u) != (self.n_unknowns,):
            raise ValueError(f"u must have shape ({self.n_unknowns},), got {np.shape(u)}")
        x = u * self.colscale
        return x[:-1].reshape(self.H + 1, self.n_c), float(x[-1])

    def pack(self, a: np.ndarray, omega: float) -> np.ndarray:
        """(a (H+1, n_c), Ω) -> scaled unknowns."""
        return np.concatenate([np.asarray(a, dtype=float).ravel(), [omega]]) / self.colscale

    def linear_mode_point(self, amplitude: float) -> np.ndarray:
        """Scaled unknowns of the linear mode whose amplitude DOF swings ``amplitude`` (m)."""
        a = np.zeros((self.H + 1, self.n_c))
        a[1] = amplitude * self.mode_shape_c
        return self.pack(a, self.omega_ref)

    def initial_tangent(self) -> np.ndarray:
        """Unit tangent of the linear branch (growing amplitude, constant Ω)."""
        t = self.linear_mode_point(1.0)
        t[-1] = 0.0
        return t / np.linalg.norm(t)

    # ------------------------------------------------------------------ residual
    def _condensed(self, omega: float, derivative: bool):
        last, D, dD = self._cached
        if last == omega and (dD is not None or not derivative):
            return D, dD
        if derivative:
            D, dD = self.cond.dynamic_stiffness(omega, self.H, derivative=True)
        else:
            D, dD = self.cond.dynamic_stiffness(omega, self.H, derivative=False), None
        self._cached = (omega, D, dD)
        return D, dD


    def _evaluate(self, u: np.ndarray, jacobian: bool):
        """Scaled residual ((H+1) n_c,) and, if asked, its dense Jacobian ((H+1) n_c, n_unknowns)."""
        a, omega = self.unpack(u)
        D, dD = self._condensed(omega, jacobian)
        R = np.empty(self.n_unknowns - 1)
        J = np.empty((self.n_unknowns - 1, self.n_unknowns)) if jacobian else np.empty((0, 0))
        _penalty_reduced_residual(D, D if dD is None else dD, np.ascontiguousarray(a), self.ci, self.lo,
                                  self.hi, self.penalty_stiffness, self._C, self.rowscale, self.colscale,
                                  jacobian, R, J, self._q, self._s, self._P)
        return (R, J) if jacobian else R

    # ------------------------------------------------------------------ results
    def _penalty_force(self, q: np.ndarray, i: int) -> np.ndarray:
        """Magnitude (N) of the penalty force of contact DOF i for samples q."""
        return self.penalty_stiffness * (np.maximum(0.0, q - self.hi[i]) + np.maximum(0.0, self.lo[i] - q))

    def contact_signals(self, u: np.ndarray, tau: np.ndarray | None = None):
        """Contact DOF displacements (n_i, n_tau) (m) and penalty force magnitudes (n_i, n_tau)
        (N), one row per contact DOF (:func:`admissible_intervals` order). Returns
        (tau, q, lam); ``tau`` defaults to a fine grid over one period."""
        a, _ = self.unpack(u)
        if tau is None:
            tau, C = self._tau_fine, self._cos_fine
        else:
            tau = np.asarray(tau, dtype=float)
            C = np.cos(np.outer(np.arange(self.H + 1), tau))
        q = a[:, self.ci].T @ C
        lam = np.array([self._penalty_force(q[i], i) for i in range(len(self.ci))])
        return tau, q, lam

    def coefficients(self, u: np.ndarray) -> np.ndarray:
        """NLvib-ordered coefficients of all DOFs, shape (n_dof, 2H+1) (sines are zero)."""
        a, omega = self.unpack(u)
        Qc = np.zeros((self.n_c, 2 * self.H + 1))
        Qc[:, 0] = a[0]
        Qc[:, 1::2] = a[1:].T
        Q = np.zeros((self.model.n_dof, 2 * self.H + 1))
        Q[self.model.c] = Qc
        Q[self.model.l] = self.cond.recover(omega, Qc)
        return Q

    def time_signals(self, u: np.ndarray, dofs=None, n_samples: int = 256):
        """(t (n_samples,) in s, q (n_dofs, n_samples)) over one period for ``dofs``
        (all DOFs when None)."""
        n_samples = check.integer("n_samples", n_samples, minimum=1)
        _, omega = self.unpack(u)
        Q = self.coefficients(u)
        if dofs is not None:
            dofs = np.atleast_1d(np.asarray(dofs))
            if dofs.dtype.kind not in "iu" or np.any((dofs < -self.model.n_dof) | (dofs >= self.model.n_dof)):
                raise ValueError(f"dofs must be integer indices in [0, {self.model.n_dof - 1}], got {dofs}")
            Q = Q[dofs]
        tau = 2 * np.pi * np.arange(n_samples) / n_samples
        q = Q[:, :1] + Q[:, 1::2] @ np.cos(np.outer(np.arange(1, self.H + 1), tau))
        return tau / omega, q

    def contact_force(self, u: np.ndarray, n_samples: int = 256):
        """(t (n_samples,) in s, λ (n_samples,) in N): the sum of the contacts' force
        magnitudes over one period."""
        n_samples = check.integer("n_samples", n_samples, minimum=1)
        _, omega = self.unpack(u)
        tau = 2 * np.pi * np.arange(n_samples) / n_samples
        _, _, lam = self.contact_signals(u, tau)
        return tau / omega, lam.sum(axis=0)

    def harmonic_content(self, u: np.ndarray, dof: int | None = None) -> np.ndarray:
        """|Q_k| for k = 0..H of ``dof`` (default the amplitude DOF); shape (H+1,)."""
        dof = check_dof(dof, self.model.n_dof, self.amplitude_dof)
        return harmonic_content(self.coefficients(u)[dof])

    def _amplitude_signal(self, a: np.ndarray, omega: float) -> np.ndarray:
        """The amplitude DOF's motion on the fine grid."""
        c = self.model.c
        i = int(np.searchsorted(c, self.amplitude_dof))
        if i < len(c) and c[i] == self.amplitude_dof:
            return a[:, i] @ self._cos_fine
        Qc = np.zeros((self.n_c, 2 * self.H + 1))
        Qc[:, 0] = a[0]
        Qc[:, 1::2] = a[1:].T
        row = int(np.searchsorted(self.model.l, self.amplitude_dof))
        return _cosines(self.cond.recover(omega, Qc)[row]) @ self._cos_fine

    def monitor(self, u: np.ndarray) -> dict:
        """frequency (Hz), amplitude (m: for a single one-sided contact measured at its DOF the
        largest excursion away from the stop, else the largest |q| of the amplitude DOF),
        energy (J: structure plus penalty springs, period averages) and contact_force_max
        (N: the largest force of any contact)."""
        a, omega = self.unpack(u)
        D, dD = self._condensed(omega, True)
        if hasattr(self.cond, "check_range"):  # modal: a converged point beyond the truncation warns
            self.cond.check_range(omega, self.H)
        q = self._amplitude_signal(a, omega)
        amplitude = amplitude_peak(q, self._away_side)
        _, qc, lam = self.contact_signals(u)
        spring = 0.5 / self.penalty_stiffness * float(np.sum(np.mean(lam**2, axis=1)))
        return {
            "frequency": omega / (2 * np.pi),
            "amplitude": amplitude,
            "energy": condensed_energy(D, dD, a, omega) + spring,
            "contact_force_max": max(refined_max(row) for row in lam),
        }


def _cosines(Q: np.ndarray) -> np.ndarray:
    """Cosine coefficients [c_0, c_1, ..., c_H] of NLvib-ordered coefficients (last axis 2H+1)."""
    return np.concatenate([Q[..., :1], Q[..., 1::2]], axis=-1)
