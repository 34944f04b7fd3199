"""What the forced-response and damped-mode (EPMC) MMS-HBM problems share.

Ansatz and unknowns. The massless DOFs ``c`` carry the full cosine and sine series
q_c(τ) = a_0 + Σ_k (a_k cos kτ + b_k sin kτ), τ = Ω t, stored in NLvib's order as one
vector x = [a_0; a_1; b_1; ...; a_H; b_H] of n_c-blocks (``x[m·n_c + i]`` is coefficient m
of the i-th massless DOF in ``model.c`` order). The force the structure needs at the
massless DOFs is, per harmonic (:mod:`mmshbm.core.damped_condense`),
f̂_k = D_k Q̂_k − P̂_k with Q̂_k = a_k − i b_k; in real coefficients F = 𝔇 x − P with
the 2×2 real blocks of the complex D_k = D_r + i D_i,

    [F_cos]   [ D_r  D_i] [a_k]
    [F_sin] = [−D_i  D_r] [b_k] ,       P_cos = Re P̂_k,   P_sin = −Im P̂_k.

Contact law with intervals (the lead's formulation, shared with the conservative
MMS-HBM): for a contact DOF with admissible interval [lo, hi]
(:func:`mmshbm.model.contact.admissible_intervals`), f(τ) the force the structure needs
there, q(τ) its displacement, r > 0 its condensed static contact stiffness and
p = q − f/r,

    R(τ) = f + r [(p − hi)₊ − (lo − p)₊],

whose zeros are exactly the Signorini pairs (q < hi ⇒ f = 0 ...; q = hi ⇔ f = −λ <= 0).
The other massless DOFs: R = f. R is projected on harmonics 0..H; with
φ(p) = proj[(p − hi)₊ − (lo − p)₊] and G = ∂φ/∂p,

    R = F + r φ(x_i − F/r),    ∂R/∂x_i = r G,    ∂R/∂F = I − G.

``_interval_projection`` (default) locates the switching instants (roots of p − hi and
p − lo) and integrates the pieces in closed form, so R is C¹ in x; ``_sampled_projection``
evaluates φ and G by AFT on N samples (a sample switching state is a kink of the
residual). The lead's C¹ projection (``mmshbm.core.contact_projection.project_contact(p,
lo, hi) -> (r, G)``) has the same signature: to switch, set ``self._project =
project_contact`` in :meth:`DampedHBMBase.__init__` (marked ``PROJECTION``).
"""

from __future__ import annotations

import numpy as np

from .. import _validate as check
from ..core.damped_condense import CondensedHarmonics, DampedCondensation
from ..core.harmonics import check_harmonics
from ..model.contact import admissible_intervals
from ..model.model import Model

__all__: list[str] = []


def _sampled_projection(H: int, N: int):
    """``project(p, lo, hi) -> (r, G)`` by sampling on N points.

    p : (2H+1,) NLvib-ordered coefficients of a trigonometric polynomial; lo, hi : bounds
    (±inf allowed). r : (2H+1,) the projection on harmonics 0..H of
    (p − hi)₊ − (lo − p)₊ evaluated at τ_j = 2πj/N; G : (2H+1, 2H+1) its derivative in p
    (the projection of the active indicator times each basis function).
    """
    tau = 2 * np.pi * np.arange(N) / N
    E = np.empty((N, 2 * H + 1))
    E[:, 0] = 1.0
    k = np.arange(1, H + 1)
    E[:, 1::2] = np.cos(np.outer(tau, k))
    E[:, 2::2] = np.sin(np.outer(tau, k))
    P = E.T * (2.0 / N)
    P[0] *= 0.5

    def project(p, lo, hi):
        s = E @ p
        up = s - hi
        down = lo - s
        active_up = up > 0
        active_down = down > 0
        val = np.where(active_up, up, 0.0) - np.where(active_down, down, 0.0)
        act = (active_up | active_down).astype(float)
        return P @ val, (P * act) @ E

    return project


def _interval_projection(H: int, n_grid: int | None = None):
    """``project(p, lo, hi) -> (r, G)`` with the switching instants located: C¹ in p.

    (p − hi)₊ − (lo − p)₊ = (p − hi)·1_A + (p − lo)·1_B with A = {p > hi}, B = {p < lo}.
    The roots of p − hi and p − lo on [0, 2π) are bracketed on a grid of ``n_grid``
    points (default max(64, 16 (2H+1))) and polished by Newton's method (vectorised,
    kept in the bracket); over the resulting intervals the projections are closed-form
    integrals of products of sines and cosines, r = P_A (p − hi e₀) + P_B (p − lo e₀),
    and because the integrand vanishes at the moving limits G = ∂r/∂p = P_A + P_B exactly
    (no boundary terms). A tangential touch between two grid points can be missed; the
    error is then of second order in the missed excursion. The lead's
    ``mmshbm.core.contact_projection.project_contact`` does the same job.
    """
    n = n_grid or max(64, 16 * (2 * H + 1))
    tau = 2 * np.pi * np.arange(n + 1) / n
    E = synthesis_matrix(H, tau)
    k = np.arange(1, H + 1)
    two = np.arange(0, 2 * H + 1)
    norm = np.full(2 * H + 1, 1.0 / np.pi)
    norm[0] = 0.5 / np.pi
    jj, kk = np.meshgrid(np.arange(H + 1), np.arange(H + 1), indexing="ij")
    dif, som = np.abs(jj - kk), jj + kk
    sgn = np.sign(jj - kk)
    cos_rows = np.r_[0, 2 * k - 1]  # index of cos jτ (j = 0: the constant)
    sin_rows = 2 * k

    def evaluate(p, t):
        t = np.asarray(t)
        c, s = np.cos(np.multiply.outer(t, k)), np.sin(np.multiply.outer(t, k))
        val = p[0] + c @ p[1::2] + s @ p[2::2]
        der = (s * -k) @ p[1::2] + (c * k) @ p[2::2]
        return val, der

    def roots(p, bound, y):
        """Roots of p − bound from the grid samples y = p(τ_g) − bound, and the sign of
        p − bound just after each."""
        idx = np.flatnonzero(np.sign(y[:-1]) != np.sign(y[1:]))
        if not len(idx):
            return np.empty(0)
        a, b = tau[idx], tau[idx + 1]
        ya, yb = y[idx], y[idx + 1]
        t = np.where(yb != ya, a - ya * (b - a) / np.where(yb != ya, yb - ya, 1.0), a)
        for _ in range(8):
            v, d = evaluate(p, t)
            step = np.where(d != 0, (v - bound) / np.where(d != 0, d, 1.0), 0.0)
            t_new = np.clip(t - step, a, b)
            if np.all(np.abs(t_new - t) <= 4e-16 * (1 + np.abs(t))):
                t = t_new
                break
            t = t_new
        return t

    def integrals(intervals):
        """Σ over intervals of ∫ cos nτ and ∫ sin nτ, n = 0..2H."""
        Ci = np.zeros(2 * H + 1)
        Si = np.zeros(2 * H + 1)
        for a, b in intervals:
            Ci[0] += b - a
            n_ = two[1:]
            Ci[1:] += (np.sin(n_ * b) - np.sin(n_ * a)) / n_
            Si[1:] += (np.cos(n_ * a) - np.cos(n_ * b)) / n_
        return Ci, Si

    def gram(intervals):
        """P[m, n] = norm_m ∫ b_m b_n over the intervals (NLvib basis)."""
        Ci, Si = integrals(intervals)
        cc = 0.5 * (Ci[dif] + Ci[som])           # ∫ cos jτ cos kτ
        ss = 0.5 * (Ci[dif] - Ci[som])           # ∫ sin jτ sin kτ
        sc = 0.5 * (Si[som] + sgn * Si[dif])     # ∫ sin jτ cos kτ
        G = np.empty((2 * H + 1, 2 * H + 1))
        G[np.ix_(cos_rows, cos_rows)] = cc
        G[np.ix_(sin_rows, sin_rows)] = ss[1:, 1:]
        G[np.ix_(sin_rows, cos_rows)] = sc[1:, :]
        G[np.ix_(cos_rows, sin_rows)] = sc[1:, :].T
        return G * norm[:, None]

    def active_intervals(p, bound, y, above):
        t = roots(p, bound, y)
        cuts = np.concatenate([[0.0], np.sort(t), [2 * np.pi]])
        out = []
        for a, b in zip(cuts[:-1], cuts[1:], strict=True):
            if b <= a:
                continue
            v, _ = evaluate(p, 0.5 * (a + b))
            if (v > bound) if above else (v < bound):
                out.append((a, b))
        return out

    def project(p, lo, hi):
        y = E @ p
        r = np.zeros(2 * H + 1)
        G = np.zeros((2 * H + 1, 2 * H + 1))
        for bound, above in ((hi, True), (lo, False)):
            if not np.isfinite(bound):
                continue
            s = y - bound
            if (above and s.max() <= 0) or (not above and s.min() >= 0):
                # no sample beyond the bound: a dip between samples is of second order
                continue
            intervals = active_intervals(p, bound, s, above)
            if not intervals:
                continue
            P = gram(intervals)
            r += P @ p - bound * P[:, 0]
            G += P
        return r, G

    return project


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


def refined_max(y: np.ndarray) -> float:
    """Largest value of a periodic sampled signal, refined by a parabola through the peak."""
    j = int(np.argmax(y))
    ym, y0, yp = y[j - 1], y[j], y[(j + 1) % len(y)]
    denom = ym - 2 * y0 + yp
    if denom < 0:
        return float(y0 - 0.125 * (yp - ym) ** 2 / denom)
    return float(y0)


class DampedHBMBase:
    """Condensation, contact data, scaling and the contact residual of the damped problems.

    Parameters
    ----------
    model : Model
        Massless contact DOFs required.
    harmonics : int
        H >= 1.
    n_samples : int, optional
        N >= 2H+1 samples of the sampled contact projection (default
        :func:`~mmshbm.core.harmonics.default_n_samples`).
    r : float, optional
        One proximal parameter (N/m) for every contact; default each contact DOF's
        condensed static stiffness 1/(D_0⁻¹)_ii.
    backend : {"auto", "modal", "direct"}
        Solver of the complex condensation (:mod:`mmshbm.core.damped_condense`).
    projection : {"interval", "sampled"}
        The contact projection: switching instants located and the pieces integrated in
        closed form (C¹ residual, default), or sampled on N points (AFT; kinks where a
        sample changes state, on which semismooth Newton can cycle: on the default beam's
        forced response at H = 5 it stalls at 1.4 gaps).
    who : str
        The method's name in error messages.
    """

    def __init__(self, model: Model, harmonics: int, n_samples: int | None, r: float | None, backend: str,
                 who: str, rhs: np.ndarray | None = None, projection: str = "interval"):
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
        self.r = stiff.copy() if r is None else np.full(len(dofs), check.positive("r", r))
        # PROJECTION: the lead's mmshbm.core.contact_projection.project_contact(p, lo, hi) has the
        # signature of both private versions here; to use it: self._project = project_contact
        if projection == "interval":
            self._project = _interval_projection(self.H)
        elif projection == "sampled":
            self._project = _sampled_projection(self.H, self.N)
        else:
            raise ValueError(f"projection must be 'interval' or 'sampled', got {projection!r}")
        self.projection = projection
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
        length = model.gap if model.gap > 0 else 1.0
        shape = np.abs(self.mode_shape_c)
        self.xscale_c = length * np.maximum(shape, 1e-3 * max(shape.max(), 1e-300))
        self.xscale = np.tile(self.xscale_c, self.n_coef)
        fscale = np.abs(self.cond.D0) @ self.xscale_c
        self.rowscale = np.tile(fscale, self.n_coef)
        for j, i in enumerate(self.contact_rows):
            self.rowscale[self._coef_index[i]] = self.r[j] * length
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

    def real_blocks(self, D: np.ndarray) -> np.ndarray:
        """The real (n_x, n_x) matrix 𝔇 of the complex D_k (H+1, n_c, n_c)."""
        n_c, H = self.n_c, self.H
        A = np.zeros((self.n_x, self.n_x))
        A[:n_c, :n_c] = D[0].real
        for k in range(1, H + 1):
            c, s = (2 * k - 1) * n_c, 2 * k * n_c
            Dr, Di = D[k].real, D[k].imag
            A[c:c + n_c, c:c + n_c] = Dr
            A[c:c + n_c, s:s + n_c] = Di
            A[s:s + n_c, c:c + n_c] = -Di
            A[s:s + n_c, s:s + n_c] = Dr
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
        for j, i in enumerate(self.contact_rows):
            idx = self._coef_index[i]
            r = self.r[j]
            p = x[idx] - F[idx] / r
            phi, G = self._project(p, self.lo[j], self.hi[j])
            R[idx] = F[idx] + r * phi
            if Jx is not None:
                A = np.eye(self.n_coef) - G
                Jx[idx] = A @ dF[idx]
                Jx[np.ix_(idx, idx)] += r * G
                if Jp is not None:
                    Jp[idx] = A @ dFp[idx]
        return R, Jx, Jp

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

    def signals(self, Q: np.ndarray, n_samples: int) -> tuple[np.ndarray, np.ndarray]:
        """(τ (n,), q (n_rows, n)) of NLvib-ordered coefficient rows ``Q`` over one period."""
        n_samples = check.integer("n_samples", n_samples, minimum=1)
        tau = 2 * np.pi * np.arange(n_samples) / n_samples
        return tau, np.atleast_2d(Q) @ synthesis_matrix(self.H, tau).T

    def needed_force(self, x: np.ndarray, D: np.ndarray, P_hat: np.ndarray | None) -> np.ndarray:
        """F (n_x,) = 𝔇 x − P for complex D (H+1, n_c, n_c) and first-harmonic P̂ (n_c,)."""
        F = self.real_blocks(D) @ x
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
