"""What the forced-response and damped-mode (EPMC) MMS-HBM problems share.

Ansatz and unknowns. The massless DOFs ``c`` carry the full cosine and sine series
q_c(τ) = a_0 + Σ_k (a_k cos kτ + b_k sin kτ), τ = Ω t, stored in NLvib's order as one
vector x = [a_0; a_1; b_1; ...; a_H; b_H] of n_c-blocks (``x[m·n_c + i]`` is coefficient m
of the i-th massless DOF in ``model.c`` order). The force the structure needs at the
massless DOFs is, per harmonic (:mod:`mmshbm.methods.mms.condensation.damped_condense`),
f̂_k = D_k Q̂_k − P̂_k with Q̂_k = a_k − i b_k; in real coefficients F = 𝔇 x − P with
the 2×2 real blocks of the complex D_k = D_r + i D_i,

    [F_cos]   [ D_r  D_i] [a_k]
    [F_sin] = [−D_i  D_r] [b_k] ,       P_cos = Re P̂_k,   P_sin = −Im P̂_k.

Contact law with intervals (the formulation of the conservative MMS-HBM): for a contact
DOF with admissible interval [lo, hi] (:func:`mmshbm.model.contact.admissible_intervals`),
f(τ) the force the structure needs there, q(τ) its displacement, r > 0 its condensed
static contact stiffness and p = q − f/r,

    R(τ) = f + r [(p − hi)₊ − (lo − p)₊],

whose zeros are exactly the Signorini pairs (q < hi ⇒ f = 0 ...; q = hi ⇔ f = −λ <= 0).
The other massless DOFs: R = f. R is projected on harmonics 0..H; with
φ(p) = proj[(p − hi)₊ − (lo − p)₊] and G = ∂φ/∂p,

    R = F + r φ(x_i − F/r),    ∂R/∂x_i = r G,    ∂R/∂F = I − G.

The projection is :func:`mmshbm.contact.unilateral.project_contact`: by default
exact (the switching instants, roots of p − hi and p − lo, located and the pieces integrated
in closed form, so R is C¹ in x), or sampled by AFT on N samples (``projection="sampled"``; a
sample switching state is a kink of the residual).
"""

from __future__ import annotations

import numpy as np

from ... import _validate as check
from ...contact.projection import sample_tables
from ...contact.unilateral import contact_projection
from ...core.measures import refined_max
from ...core.problem import ContinuationProblemBase
from ...harmonic.harmonics import check_harmonics
from ...model.contact import admissible_intervals
from ...model.model import Model
from .condensation.damped_condense import CondensedHarmonics, DampedCondensation
from .contact_kernels import _contact_rows, _damped_residual
from .proximal import proximal_parameter

__all__: list[str] = []


def _projection_grid(projection: str, H: int, N: int) -> tuple[bool, int]:
    """(exact, samples per period) of the contact projection: 16·(2H+1) for the exact one
    (its bracketing grid, as :func:`~mmshbm.contact.unilateral.project_contact`), N sampled."""
    return projection == "exact", (16 * (2 * H + 1) if projection == "exact" else N)


def synthesis_matrix(H: int, tau: np.ndarray) -> np.ndarray:
    """(n_t, 2H+1) matrix whose rows evaluate NLvib-ordered coefficients at ``tau``."""
    tau = np.asarray(tau, dtype=float)
    E = np.empty((len(tau), 2 * H + 1))
    E[:, 0] = 1.0
    k = np.arange(1, H + 1)
    E[:, 1::2] = np.cos(np.outer(tau, k))
    E[:, 2::2] = np.sin(np.outer(tau, k))
    return E


def fine_samples(coeffs: np.ndarray, n: int) -> np.ndarray:
    """Samples at τ_j = 2πj/n (j = 0..n-1) of trigonometric polynomials with NLvib-ordered
    coefficients ``coeffs`` (..., 2H+1), n > 2H, by an inverse real FFT (no dense synthesis
    matrix: cheaper, and no multithreaded BLAS call)."""
    coeffs = np.asarray(coeffs, dtype=float)
    H = (coeffs.shape[-1] - 1) // 2
    spec = np.zeros(coeffs.shape[:-1] + (n // 2 + 1,), dtype=complex)
    spec[..., 0] = coeffs[..., 0]
    spec[..., 1:H + 1] = 0.5 * (coeffs[..., 1::2] - 1j * coeffs[..., 2::2])
    return np.fft.irfft(spec, n=n, axis=-1) * n


class DampedHBMBase(ContinuationProblemBase):
    """Condensation, contact data, scaling and the contact residual of the damped problems.

    Parameters
    ----------
    model : Model
        Massless contact DOFs required.
    harmonics : int
        H >= 1.
    n_samples : int, optional
        N >= 2H+1 samples of the sampled contact projection (default
        :func:`~mmshbm.harmonic.harmonics.default_n_samples`).
    r : float, optional
        One proximal parameter (N/m) for every contact; default each contact DOF's
        condensed static stiffness 1/(D_0⁻¹)_ii.
    backend : {"auto", "modal", "direct"}
        Solver of the complex condensation (:mod:`mmshbm.methods.mms.condensation.damped_condense`).
    projection : {"exact", "sampled"}
        The contact projection: switching instants located and the pieces integrated in
        closed form (C¹ residual, default), or sampled on N points (AFT; kinks where a
        sample changes state, on which semismooth Newton can cycle: on the default beam's
        forced response at H = 5 it stalls at 1.4 gaps).
    who : str
        The method's name in error messages.
    """

    #: ``mode``: the linear mode a damped backbone starts from (the EPMC problems set it)
    setting_names = ("H", "N", "r", "mode")

    def __init__(self, model: Model, harmonics: int, n_samples: int | None, r: float | None, backend: str,
                 who: str, rhs: np.ndarray | None = None, projection: str = "exact"):
        if not isinstance(model, Model):
            raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
        model.require_massless_contacts(who)
        self.model = model
        self.H, self.N = check_harmonics(harmonics, n_samples)
        self.cond = DampedCondensation(model, rhs, backend)
        c = model.c
        self.n_c = len(c)
        self.n_coef = 2 * self.H + 1
        self.n_x = self.n_c * self.n_coef
        dofs, lo, hi = admissible_intervals(model.contacts)
        self.contact_rows = np.searchsorted(c, dofs)
        self.lo, self.hi = lo, hi
        flex = np.linalg.inv(self.cond.D0)
        stiff = 1.0 / np.diag(flex)[self.contact_rows]
        self.contact_stiffness = stiff
        self.r = proximal_parameter(r, stiff, model, self.cond.D0, self.contact_rows, self.H)
        self._project = contact_projection(projection, self.H, self.N)
        self.projection = projection
        self._exact, n_grid = _projection_grid(projection, self.H, self.N)
        self._tables = sample_tables(self.H, n_grid)
        self._rows = np.ascontiguousarray(self.contact_rows, dtype=np.int64)
        self._coef_index = [np.arange(self.n_coef) * self.n_c + i for i in range(self.n_c)]
        # scales: the first open mode's shape on the massless DOFs, the gap as length
        freqs, modes = model.linear_modes(1)
        self.linear_frequency = float(freqs[0])
        self.omega_ref = 2 * np.pi * self.linear_frequency
        phi_c = modes[c, 0]
        amp_dof = self._amplitude_dof_or_none()
        ref = abs(modes[amp_dof, 0]) if amp_dof is not None else np.max(np.abs(phi_c))
        if not ref > 0:
            ref = np.max(np.abs(modes[:, 0]))
        self.mode_shape_c = phi_c / ref
        self.scale_unknowns(model.gap if model.gap > 0 else 1.0)
        k = np.arange(1, self.H + 1)
        self._n_fine = max(512, 2 ** int(np.ceil(np.log2(16 * (2 * self.H + 1)))))
        self._k = k
        self._cache: tuple | None = None

    # ------------------------------------------------------------------ helpers
    def _amplitude_dof_or_none(self) -> int | None:
        try:
            return self.model.amplitude_dof
        except ValueError:
            return None

    def _condensed(self, omega: float, xi: float = 0.0, derivative: bool = False, xi_derivative: bool = False,
                   recover: bool = False) -> CondensedHarmonics:
        """The condensation at (Ω, ξ), reused while (Ω, ξ) are the same numbers and it holds
        what is asked (derivatives, recovery)."""
        key = (omega, xi)
        if self._cache is not None and self._cache[0] == key:
            ch = self._cache[1]
            if ((not derivative or ch.dD_domega is not None) and (not xi_derivative or ch.dD_dxi is not None)
                    and (not recover or ch.Z is not None)):
                return ch
            derivative = derivative or ch.dD_domega is not None
            xi_derivative = xi_derivative or ch.dD_dxi is not None
            recover = recover or ch.Z is not None
        ch = self.cond.evaluate(omega, self.H, xi, derivative, xi_derivative, recover)
        self._cache = (key, ch)
        return ch

    def scale_unknowns(self, length: float) -> None:
        """Unknowns in units of ``length`` (m) times the first mode's shape (xscale), rows in
        the forces that moves (rowscale; a contact row in its proximal parameter r times
        ``length``)."""
        shape = np.abs(self.mode_shape_c)
        self.xscale_c = length * np.maximum(shape, 1e-3 * max(shape.max(), 1e-300))
        self.xscale = np.tile(self.xscale_c, self.n_coef)
        fscale = np.abs(self.cond.D0) @ self.xscale_c
        self.rowscale = np.tile(fscale, self.n_coef)
        for j, i in enumerate(self.contact_rows):
            self.rowscale[self._coef_index[i]] = self.r[j] * length

    def real_blocks(self, D: np.ndarray) -> np.ndarray:
        """The real (n_x, n_x) matrix 𝔇 of the complex D_k (H+1, n_c, n_c)."""
        n_c, H = self.n_c, self.H
        A = np.zeros((self.n_x, self.n_x))
        A4 = A.reshape(self.n_coef, n_c, self.n_coef, n_c)  # A4[a, i, b, j] = A[a n_c + i, b n_c + j]
        A4[0, :, 0, :] = D[0].real
        cos, sin = np.arange(1, 2 * H + 1, 2), np.arange(2, 2 * H + 2, 2)
        Dr, Di = D[1:].real, D[1:].imag
        A4[cos, :, cos, :] = Dr
        A4[cos, :, sin, :] = Di
        A4[sin, :, cos, :] = -Di
        A4[sin, :, sin, :] = Dr
        return A

    def first_harmonic_vector(self, v: np.ndarray) -> np.ndarray:
        """Real (n_x,) vector of a complex first-harmonic amplitude v̂ (n_c,): cos = Re, sin = −Im."""
        out = np.zeros(self.n_x)
        out[self.n_c:2 * self.n_c] = v.real
        out[2 * self.n_c:3 * self.n_c] = -v.imag
        return out

    def contact_residual(self, x: np.ndarray, F: np.ndarray, dF: np.ndarray | None, dFp: np.ndarray | None):
        """R (n_x,), and if ``dF`` is given ∂R/∂x (n_x, n_x) and ∂R/∂params (n_x, n_p).

        ``F`` (n_x,) is the force the structure needs, ``dF`` = ∂F/∂x, ``dFp`` = ∂F/∂params.
        """
        R = F.copy()
        Jx = None if dF is None else dF.copy()
        Jp = None if dFp is None else dFp.copy()
        if len(self._rows) == 0:
            return R, Jx, Jp
        tau, cos_t, sin_t = self._tables
        G = np.empty((len(self._rows), self.n_coef, self.n_coef))
        _contact_rows(np.ascontiguousarray(x, dtype=float), np.ascontiguousarray(F, dtype=float), self._rows,
                      self.n_c, self.lo, self.hi, self.r, self._exact, cos_t, sin_t, tau, R, G)
        if Jx is not None:
            for j, i in enumerate(self.contact_rows):
                idx = self._coef_index[i]
                A = np.eye(self.n_coef) - G[j]
                Jx[idx] = A @ dF[idx]
                Jx[np.ix_(idx, idx)] += self.r[j] * G[j]
                if Jp is not None:
                    Jp[idx] = A @ dFp[idx]
        return R, Jx, Jp

    def fused_residual(self, D: np.ndarray, x: np.ndarray, load: np.ndarray | None,
                       dD: np.ndarray | None = None, dload: np.ndarray | None = None):
        """:meth:`contact_residual` of F = 𝔇 x − load in one compiled pass (no dense 𝔇 formed
        for the residual): R (n_x,) and, with the derivatives ``dD`` (n_p, H+1, n_c, n_c) of
        the D_k in the parameters and ``dload`` (n_x, n_p) of the load, ∂R/∂x (n_x, n_x) and
        ∂R/∂params (n_x, n_p); else None, None."""
        n_x = self.n_x
        load = np.zeros(n_x) if load is None else np.ascontiguousarray(load, dtype=float)
        jacobian = dD is not None
        if jacobian:
            dD = np.ascontiguousarray(dD, dtype=complex)
            n_p = dD.shape[0]
            dload = np.zeros((n_x, n_p)) if dload is None else np.ascontiguousarray(dload, dtype=float)
            Jx, Jp = np.empty((n_x, n_x)), np.empty((n_x, n_p))
        else:
            dD = np.zeros((0,) + D.shape, dtype=complex)
            dload, Jx, Jp = np.zeros((n_x, 0)), np.empty((0, 0)), np.empty((0, 0))
        R = np.empty(n_x)
        tau, cos_t, sin_t = self._tables
        _damped_residual(np.ascontiguousarray(D, dtype=complex), dD, np.ascontiguousarray(x, dtype=float),
                         load, dload, self._rows, self.lo, self.hi, self.r, self._exact, cos_t, sin_t, tau,
                         jacobian, R, Jx, Jp)
        return (R, Jx, Jp) if jacobian else (R, None, None)

    def residual_from_blocks(self, D: np.ndarray, x: np.ndarray, load: np.ndarray | None,
                             dD: np.ndarray | None = None, dload: np.ndarray | None = None):
        """:meth:`fused_residual` in NumPy: F = 𝔇 x − load formed and passed to
        :meth:`contact_residual`, for subclasses whose contact rows are not the compiled
        unilateral ones (friction rows); same arguments and results."""
        Dx = self.real_blocks(D)
        F = Dx @ x - (0.0 if load is None else load)
        if dD is None:
            return self.contact_residual(x, F, None, None)[0], None, None
        dFp = np.column_stack([self.real_blocks(dD[p]) @ x for p in range(dD.shape[0])])
        if dload is not None:
            dFp = dFp - dload
        return self.contact_residual(x, F, Dx, dFp)

    def full_coefficients(self, x: np.ndarray, ch: CondensedHarmonics, force_l: np.ndarray | None
                          ) -> np.ndarray:
        """NLvib-ordered coefficients of all DOFs, shape (n_dof, 2H+1), from the massless DOFs'
        ``x`` and the condensation ``ch`` (with recovery); ``force_l`` (n_l,) the particular
        response S_1⁻¹ B̂ of the DOFs with mass to the first-harmonic load (None: unforced)."""
        n_c = self.n_c
        Xc = x.reshape(self.n_coef, n_c).T  # (n_c, 2H+1)
        Qc_hat = Xc[:, 1::2] - 1j * Xc[:, 2::2]  # (n_c, H)
        Ql = np.empty((self.cond.n_l, self.n_coef))
        Ql[:, 0] = -(ch.Z[0].real @ Xc[:, 0])
        Ql_hat = -np.einsum("kij,jk->ik", ch.Z[1:], Qc_hat)
        if force_l is not None:
            Ql_hat[:, 0] += force_l
        Ql[:, 1::2] = Ql_hat.real
        Ql[:, 2::2] = -Ql_hat.imag
        Q = np.empty((self.model.n_dof, self.n_coef))
        Q[self.model.c] = Xc
        Q[self.model.l] = Ql
        return Q

    def angular_frequency(self, u: np.ndarray) -> float:
        """Ω (rad/s) of the scaled unknowns ``u`` (each problem knows where it keeps Ω)."""
        raise NotImplementedError(f"{type(self).__name__} does not say where its frequency is")

    def time_signals(self, u: np.ndarray, dofs=None, n_samples: int = 256):
        """(t (n_samples,) s, q (n_dofs, n_samples)) over one period (all DOFs when None)."""
        omega = self.angular_frequency(u)
        Q = self.coefficients(u)
        if dofs is not None:
            dofs = np.atleast_1d(np.asarray(dofs))
            if dofs.dtype.kind not in "iu" or np.any((dofs < 0) | (dofs >= self.model.n_dof)):
                raise ValueError(f"dofs must be integer indices in [0, {self.model.n_dof - 1}], got {dofs}")
            Q = Q[dofs]
        tau, q = self.signals(Q, n_samples)
        return tau / omega, q

    def signals(self, Q: np.ndarray, n_samples: int) -> tuple[np.ndarray, np.ndarray]:
        """(τ (n,), q (n_rows, n)) of NLvib-ordered coefficient rows ``Q`` over one period."""
        n_samples = check.integer("n_samples", n_samples, minimum=1)
        tau = 2 * np.pi * np.arange(n_samples) / n_samples
        return tau, np.atleast_2d(Q) @ synthesis_matrix(self.H, tau).T

    def needed_force(self, x: np.ndarray, D: np.ndarray, P_hat: np.ndarray | None) -> np.ndarray:
        """F (n_x,) = 𝔇 x − P for complex D (H+1, n_c, n_c) and first-harmonic P̂ (n_c,) (𝔇 x
        harmonic by harmonic, 𝔇 not formed)."""
        from .forced_operator import condensed_product

        F = condensed_product(D, np.asarray(x, dtype=float))
        if P_hat is not None:
            F -= self.first_harmonic_vector(P_hat)
        return F

    def contact_force_max(self, x: np.ndarray, F: np.ndarray) -> float:
        """Largest force (N) any stop exerts over the period: the peak of the degree-H force
        signal −f (+f for a stop on the − side) over the stretch where the proximal argument
        p = q − f/r is beyond the stop; exactly 0 when it never is (no contact: the force
        signal is then round-off)."""
        best = 0.0
        for j, i in enumerate(self.contact_rows):
            idx = self._coef_index[i]
            f, q = fine_samples(np.vstack([F[idx], x[idx]]), self._n_fine)
            p = q - f / self.r[j]
            if np.isfinite(self.hi[j]) and np.any(p > self.hi[j]):
                best = max(best, refined_max(-f))
            if np.isfinite(self.lo[j]) and np.any(p < self.lo[j]):
                best = max(best, refined_max(f))
        return max(best, 0.0)

    def amplitude(self, q_coeffs: np.ndarray) -> float:
        """The amplitude of the amplitude DOF's coefficients (2H+1,): for the contact DOF of a
        single-contact model the largest excursion away from the stop (the backbone
        convention), otherwise the largest |q| over the period (m)."""
        q = fine_samples(q_coeffs, self._n_fine)
        contacts = self.model.contacts
        if len(contacts) == 1 and self.model.amplitude_dof == contacts[0].dof and self._away_convention:
            return refined_max(-contacts[0].side * q)
        return max(refined_max(q), refined_max(-q))

    _away_convention = True
