"""Baseline 1: classical harmonic balance on all DOFs, the stop as a penalty spring.

This is how general harmonic-balance tools treat contact (docs/design.md §5). Every DOF
of the finite-element model is expanded, and the rigid stop becomes a one-sided spring of
stiffness k_p at the contact DOF:

    (K − (kΩ)² M) Q_k + proj_k(f_nl(q(τ))) = 0,      k = 0..H, all n DOFs,
    f_nl = −W λ,   λ(τ) = k_p max(0, −g_N(τ)),   g_N = gap − stop_side · q[contact_dof],

with ``W = −stop_side e_contact`` (:class:`~mmshbm.model.Model`), i.e. the spring pushes the
contact DOF away from the stop with the force λ >= 0. The massless contact node keeps zero
mass: between impacts it follows the structure statically, as in MMS-HBM.

Several contacts: one spring per contact (its DOF, side and gap; k_p per contact), a
clearance being two springs on one DOF. The residual's row of a contact DOF gets the net
force Σ_i side_i λ_i of its springs, and the Jacobian's harmonic coupling of that DOF is
Σ_i k_p,i P_i (P_i the cosine product matrix of spring i's active set): still one dense
(H+1)² block per distinct contact DOF, the rest the pattern of K and M. Contact DOFs may
carry mass (FE-package models, as NLvib runs them): nothing in the formulation needs a
massless DOF; only the default k_p is then taken from the static stiffness at the
contact, 1/(e_dᵀ K⁻¹ e_d) by a sparse factorisation of K (the same number as the
condensed (w_cᵀ D_0⁻¹ w_c)⁻¹ of a massless contact, which is what 0.1 used and still
uses there). The amplitude is measured at ``model.amplitude_dof``.

Conventions follow :mod:`mmshbm.methods.mms.conservative`:

* Cosine-only (time-symmetric) ansatz q(τ) = Σ_k Q_k cos kτ on every DOF. It anchors the
  phase at a turning point and removes the energy-balance identity of the conservative
  family (it lives in the sine projections, which vanish for an even q), so the n(H+1)
  equations in n(H+1)+1 unknowns (the Q_k of all DOFs and Ω) have full row rank along the
  branch.
* Alternating frequency-time on the contact DOF only: it is the only DOF with a nonlinear
  force. Its cosine series is synthesised on N samples (pyfftw, :func:`~mmshbm.harmonic.harmonics.transform`),
  the penalty force and its active set s_j = [g_N(τ_j) < 0] are evaluated by a Numba kernel,
  and λ is projected back on harmonics 0..H.
* Analytic, sparse Jacobian. Harmonic k's block is K − (kΩ)² M (sparse, the pattern of the
  FE matrices); the penalty couples the harmonics only in the contact DOF's row and column,
  ∂R_{m,c}/∂Q_{k,c} += k_p P_{mk} with P the cosine product matrix of the active set
  (:func:`~mmshbm.contact.projection._cosine_product_matrix`); the Ω column is −2k²Ω M Q_k. The CSR
  pattern is built once; each evaluation only fills its data vector (a Numba kernel), so the
  cost per Jacobian is that of writing its non-zeros, not of scipy sparse arithmetic.
* Scaled unknowns: Q_k,i by gap·max(|φ_i|, 10⁻³ max|φ|)·ρ, with φ the first linear mode
  normalised to a unit contact-DOF swing; Ω by ω_1; row i by the force scale (|K| s)_i. The
  factor ρ = ‖φ/s‖ / ‖φ_c/s_c‖ makes the scaled norm of the linear mode equal to that of
  MMS-HBM's unknowns (the massless DOFs only), so an arclength step means the same change of
  amplitude in both methods; without it the arclength would grow like √n with the DOF
  count, and point counts would compare the scalings, not the methods.

Choice of k_p and its error. Within contact the penalty spring is in series with the
structure, so the contact constraint is violated by a penetration of order λ/k_p and the
closed-contact stiffness seen by a mode is lowered by a relative amount of order
k_eff/k_p, with k_eff the modal stiffness of the constraint (for the one-DOF oscillator
k_eff = k2²/(k1+k2), four times its condensed contact stiffness k_c). The backbone's
relative frequency error is a fraction of that (the closed phase lasts part of the period):

    |f_penalty − f_penalty(∞)| / f  ≈  C · k_c / k_p,     C ≈ 0.1..3 (measured),

on the one-DOF oscillator and the default beam (docs/penalty.md). The default
k_p = 10³ k_c, with k_c = (w_cᵀ D_0⁻¹ w_c)⁻¹ the condensed static contact stiffness,
gives errors ~10⁻⁴..3·10⁻³. Larger k_p is more accurate, but the penalty force becomes a
steeper function of the displacement: its harmonics decay more slowly, its pulses get
shorter (N must grow: :func:`~mmshbm.methods.penalty.defaults.penalty_n_samples`), the
Jacobian's condition number grows like k_p/k_c, and Newton's semismooth iteration has to
resolve an active set within a penetration of only λ/k_p.

The penalty limit is a different truncation. At fixed H, f_penalty(∞) is *not* the
MMS-HBM frequency at the same H: a degree-H contact displacement can only touch the stop,
so k_p max(0, −g_N) tends to impulses, whereas MMS-HBM keeps the massless node on the stop
over the closed phase. The two agree as H grows (one-DOF oscillator at 2 gaps: 3.4·10⁻³
apart at H = 5, 4·10⁻⁴ at H = 10, 6·10⁻⁵ at H = 20; default beam at 1.05 gaps: 3·10⁻²,
1.1·10⁻³, 2.2·10⁻⁴). Penalty HBM needs more harmonics than MMS-HBM for the same accuracy.

Energy. The penalty system conserves the energy of the structure *plus* the spring; the
monitored energy is the period average of the structure's kinetic and potential energy
(as in MMS-HBM) plus the period average of the spring's ½ k_p max(0, −g_N)², which tends
to zero as k_p → ∞ (it is of order λ²/k_p).
"""

from __future__ import annotations

import logging

import numpy as np
import scipy.sparse as sp

from ... import _validate as check
from ...contact.projection import _cosine_product_matrix
from ...contact.table import (
    DEFAULT_PENALTY_FACTOR,
    contact_table,
    penalty_values,
    start_mode,
    static_contact_stiffness,
)
from ...core.measures import amplitude_sign
from ...core.problem import BackboneProblemBase
from ...harmonic.harmonics import check_harmonics, transform
from ...model.model import Model
from ._kernels import _penalty_contacts, _penalty_hbm_jacobian
from .assembly import _jacobian_pattern
from .defaults import penalty_n_samples
from .signals import PenaltySignalsMixin

__all__ = ["PenaltyHBMProblem", "DEFAULT_PENALTY_FACTOR", "penalty_n_samples"]

log = logging.getLogger(__name__)


class PenaltyHBMProblem(PenaltySignalsMixin, BackboneProblemBase):
    """Penalty harmonic balance on all DOFs of a :class:`Model`, as a continuation problem.

    Parameters
    ----------
    model : Model
        The structure; each contact meets its stop through a penalty spring. Contact DOFs
        may carry mass (models as FE packages export them).
    harmonics : int
        Highest harmonic H >= 1.
    n_samples : int, optional
        Time samples per period N >= 2H+1 for the contact DOFs' AFT. Default
        :func:`~mmshbm.methods.penalty.defaults.penalty_n_samples`: MMS-HBM's
        :func:`~mmshbm.harmonic.harmonics.default_n_samples` up to k_p = 10³ k_c, doubled per
        further decade of k_p (the penetration window narrows as k_p grows and must stay
        resolved by the samples).
    penalty_stiffness : float or sequence of float, optional
        k_p (N/m), > 0: one for all contacts or one per contact. Default
        ``DEFAULT_PENALTY_FACTOR`` (10³) times each contact's static stiffness k_c
        (:func:`~mmshbm.contact.table.static_contact_stiffness`: the condensed
        (w_cᵀ D_0⁻¹ w_c)⁻¹ when the contact DOFs are massless, as in 0.1, else
        1/(e_dᵀ K⁻¹ e_d) from a sparse factorisation of K; the same number where both
        apply). The relative frequency error of the backbone scales like k_c/k_p (module
        docstring); larger k_p needs more harmonics and worsens the conditioning.
    mode : int
        Which linear mode (1-based) the branch starts from.

    Attributes
    ----------
    H, N : int
        Harmonics and samples per period.
    n_unknowns : int
        n_dof·(H+1) + 1.
    penalty_stiffness, contact_stiffness : float
        k_p and k_c (N/m) of a single-contact model; with several contacts the largest
        k_p and the smallest k_c (the per-contact values are ``penalty_stiffnesses`` and
        ``contact_stiffnesses``, shape (n_contacts,)).
    method : str
        ``"penalty"``.

    Notes
    -----
    The scaled unknown vector is ``u = [Q_0/s, Q_1/s, ..., Q_H/s, Ω/ω_ref]`` with
    Q_k ∈ R^{n_dof} the cosine coefficients of all DOFs (model order) and ``s`` the per-DOF
    length scale ``xscale``. The residual (n_dof·(H+1),) is ordered the same way and the
    Jacobian is a ``scipy.sparse.csr_matrix`` of shape (n_dof·(H+1), n_dof·(H+1) + 1).
    """

    method = "penalty"
    setting_names = ("H", "N", "mode", "penalty_stiffness")

    def __init__(self, model: Model, harmonics: int = 5, n_samples: int | None = None,
                 penalty_stiffness=None, mode: int = 1):
        if not isinstance(model, Model):
            raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
        self.model = model
        self.H = check_harmonics(harmonics)[0]
        self.mode = check.integer("mode", mode, minimum=1)
        if self.mode > len(model.l):
            raise ValueError(f"mode must be <= the number of DOFs with mass ({len(model.l)}), "
                             f"got {self.mode}")
        self.n = model.n_dof
        self.amplitude_dof = model.amplitude_dof  # ValueError naming it if it is needed and missing
        self._amp_sign = amplitude_sign(model)
        self.contacts = contact_table(model)
        ct = self.contacts
        self.gap = model.gap
        self.K = model.K.tocsr()
        self.M = model.M.tocsr()
        self.contact_stiffnesses = static_contact_stiffness(model)
        self.penalty_stiffnesses = penalty_values(model, penalty_stiffness, self.contact_stiffnesses)
        self.contact_stiffness = float(self.contact_stiffnesses.min())
        self.penalty_stiffness = float(self.penalty_stiffnesses.max())
        # the Jacobian's factor per distinct contact DOF: the largest k_p on it
        self._kp_ref = np.zeros(len(ct.dofs))
        np.maximum.at(self._kp_ref, ct.slot, self.penalty_stiffnesses)
        if n_samples is None:
            ratio = float(np.max(self.penalty_stiffnesses / self.contact_stiffnesses))
            n_samples = penalty_n_samples(self.H, ratio)
        self.N = check_harmonics(self.H, n_samples)[1]
        log.debug("penalty HBM: k_p = %s N/m = %s k_c, N = %d", self.penalty_stiffnesses,
                  self.penalty_stiffnesses / self.contact_stiffnesses, self.N)
        self._init_mode()
        self._init_scales()
        self.n_unknowns = (self.H + 1) * self.n + 1
        self._pattern = _jacobian_pattern(self.K, self.M, self.H, ct.dofs, model.l)
        p = self._pattern
        self._entry_scale = self.colscale[p.indices] / self.rowscale[p.rows]
        n_d = len(ct.dofs)
        self._tr = transform(self.H, self.N, n_d)
        self._P = np.empty((n_d, self.H + 1, self.H + 1))
        self._f_t = np.empty((n_d, self.N))
        self._s_t = np.empty((n_d, self.N))
        self._k2 = np.arange(self.H + 1, dtype=float) ** 2
        n_fine = max(512, 8 * self.N)
        self._tau_fine = 2 * np.pi * np.arange(n_fine) / n_fine
        self._cos_fine = np.cos(np.outer(np.arange(self.H + 1), self._tau_fine))

    @property
    def cd(self) -> int:
        """The contact DOF of a single-contact model (ValueError with several)."""
        return self.model.contact_dof

    @property
    def side(self) -> float:
        """The stop side (±1.0) of a single-contact model (ValueError with several)."""
        return float(self.model.stop_side)

    def _init_mode(self) -> None:
        """Linear mode ``self.mode``: frequency and shape with a unit swing of the
        amplitude DOF."""
        freq, phi = start_mode(self.model, self.mode)
        self.linear_frequency = freq
        self.omega_ref = 2 * np.pi * self.linear_frequency
        amp = phi[self.amplitude_dof]
        if abs(amp) < 1e-12 * np.max(np.abs(phi)):
            raise ValueError(f"linear mode {self.mode} does not move the contact DOF: no impact")
        if np.all(np.abs(phi[self.contacts.dofs]) < 1e-12 * np.max(np.abs(phi))):
            raise ValueError(f"linear mode {self.mode} does not move any contact DOF: no impact")
        # unit motion of the amplitude DOF; the (first moving) contact DOF moves toward its
        # stop at τ = 0 (start_mode / linear_modes orient the modes that way)
        self.mode_shape = phi / abs(amp)

    def _init_scales(self) -> None:
        """Column scales (xscale per DOF, ω_ref) and row scales (force per DOF)."""
        length = self.gap if self.gap > 0 else 1.0
        shape = np.abs(self.mode_shape)
        s = np.maximum(shape, 1e-3 * shape.max())
        # MMS-HBM's unknowns: the massless DOFs; for contact DOFs with mass (no MMS-HBM
        # formulation) the contact DOFs play that part
        c = self.model.c if (self.model.massless_contacts and len(self.model.c)) else self.contacts.dofs
        rho = np.linalg.norm(shape / s) / np.linalg.norm(shape[c] / s[c])
        self.xscale = length * rho * s
        self.colscale = np.concatenate([np.tile(self.xscale, self.H + 1), [self.omega_ref]])
        self.rowscale = np.tile(abs(self.K) @ self.xscale, self.H + 1)

    # ------------------------------------------------------------------ unknowns
    def unpack(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """Scaled unknowns -> (cosine coefficients Q (H+1, n_dof) in m/rad, Ω in rad/s)."""
        x = np.asarray(u, dtype=float) * self.colscale
        return x[:-1].reshape(self.H + 1, self.n), float(x[-1])

    def pack(self, Q: np.ndarray, omega: float) -> np.ndarray:
        """(Q (H+1, n_dof), Ω) -> scaled unknowns, shape (n_unknowns,)."""
        return np.concatenate([np.asarray(Q, dtype=float).ravel(), [omega]]) / self.colscale

    def linear_mode_point(self, amplitude: float) -> np.ndarray:
        """Scaled unknowns of the linear mode whose amplitude DOF swings ``amplitude`` (m),
        the contact DOF moving toward the stop at τ = 0, at Ω = ω of that mode."""
        Q = np.zeros((self.H + 1, self.n))
        Q[1] = amplitude * self.mode_shape
        return self.pack(Q, self.omega_ref)

    def initial_tangent(self) -> np.ndarray:
        """Unit tangent of the linear branch (growing amplitude, constant Ω)."""
        t = self.linear_mode_point(1.0)
        t[-1] = 0.0
        return t / np.linalg.norm(t)

    # ------------------------------------------------------------------ residual
    def _contact_aft(self, Q: np.ndarray) -> np.ndarray:
        """Penalty forces on the samples (fills ``_f_t``, ``_s_t``); returns the cosine
        coefficients (n_d, H+1) (N) of the net force Σ side_i λ_i on each distinct contact
        DOF."""
        ct = self.contacts
        q_t = self._tr.cos_to_time(np.ascontiguousarray(Q[:, ct.dofs].T))
        _penalty_contacts(q_t, ct.slot, ct.gap, ct.side.astype(float), self.penalty_stiffnesses,
                          self._kp_ref, self._f_t, self._s_t)
        return self._tr.time_to_cos(self._f_t)

    def residual(self, u: np.ndarray) -> np.ndarray:
        """Scaled residual R, shape (n_dof·(H+1),): (K − (kΩ)² M) Q_k − Σ_i w_i λ_i,k,
        divided by the row scales (``u``: scaled unknowns, shape (n_unknowns,))."""
        return self._residual_terms(u)[0]

    def residual_and_jacobian(self, u: np.ndarray) -> tuple[np.ndarray, sp.csr_matrix]:
        """(R, J): :meth:`residual` and ∂R/∂u (scaled), a scipy.sparse.csr_matrix of
        shape (n_dof·(H+1), n_unknowns)."""
        R, omega, MQ = self._residual_terms(u)
        return R, self._jacobian(omega, MQ)

    def _residual_terms(self, u: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
        """(R, Ω, M Q): :meth:`residual` and what its Jacobian reuses."""
        Q, omega = self.unpack(u)
        KQ = (self.K @ Q.T).T
        MQ = (self.M @ Q.T).T
        f_k = self._contact_aft(Q)
        R = KQ - (omega**2 * self._k2)[:, None] * MQ
        R[:, self.contacts.dofs] += f_k.T
        return R.ravel() / self.rowscale, omega, MQ

    def _jacobian(self, omega: float, MQ: np.ndarray) -> sp.csr_matrix:
        """Scaled sparse Jacobian from the active sets left in ``_s_t`` by the residual."""
        S = self._tr.cosine_spectrum(self._s_t)
        for d in range(len(S)):
            _cosine_product_matrix(S[d], self.H, self._P[d])
        p = self._pattern
        data = np.empty(len(p.indices))
        _penalty_hbm_jacobian(p.K_data, p.M_data, omega, self._kp_ref, self._P, np.ascontiguousarray(MQ),
                              p.block_pos, p.coupling_pos, p.omega_rows, p.omega_pos, self._entry_scale, data)
        return sp.csr_matrix((data, p.indices, p.indptr), shape=p.shape, copy=False)
