"""The MMS-HBM residual and its semi-analytic Jacobian (Schreyer, Peter & Leine).

Unknowns: the Fourier coefficients of the massless DOFs q_c and the fundamental frequency
Ω. The linear structure is condensed per harmonic (:mod:`mmshbm.core.condense`):
F_k = D_k(Ω) a_k is the force the structure needs at the massless DOFs. The massless
DOFs are static, so at each of them that force comes from the stops alone:

    massless DOF without a stop:   F_k,i = 0,
    contact DOF (interval [lo, hi]):  proj_k[ f + r ((p − hi)₊ − (lo − p)₊) ] = 0,
                                      p = q − f/r,

the proximal form of the Signorini law on the interval of positions its stop(s) allow
(:mod:`mmshbm.core.contact_kernels`; one stop: [−inf, gap] or [−gap, inf], a clearance:
[−gap₋, gap₊]), whose zeros are exactly the complementarity pairs for any r > 0. Newton
iterates only in these numbers, however many DOFs the FE model has.

Projection. ``projection="exact"`` (default) locates the switching instants (zeros of the
degree-H trigonometric polynomial p − θ) and integrates each smooth piece in closed form:
the residual is C¹ in the unknowns and the sample count N only brackets zeros.
``projection="sampled"`` is the alternating frequency-time projection on N samples of
mmshbm 0.1 (a sample that switches is a kink: the branch has corners).

Autonomy and conservation. A time shift of a periodic solution is a solution, and for
a conservative system the anchored square system is degenerate along the whole family
(the energy-balance harmonic equation is implied by the others). mmshbm removes both at
once with a *cosine-only (time-symmetric) ansatz*: q_c(τ) = Σ_k a_k cos kτ. The system
is reversible (no damping, massless contact: no restitution), so the nonlinear modes
continued from the linear modes are symmetric about a turning point, where all
velocities vanish; putting that point at τ = 0 anchors the phase (only the discrete
half-period shift remains), and the residual of an even q_c is even, so its sine
projections vanish identically: the energy-balance identity, which lives in the sine
projections, drops out of the equations. What remains is (H+1)·n_c equations in
(H+1)·n_c + 1 unknowns with full row rank along the family: a regular one-parameter
branch that pseudo-arclength continuation follows with a well-conditioned bordered
Jacobian. The price: non-symmetric orbits are outside the ansatz.

All vectors handed to the continuation are scaled: coefficients by the first mode's
massless-DOF shape times the gap, Ω by the linear frequency, residual rows by the force
those scales produce.
"""

from __future__ import annotations

import math

import numpy as np

from .. import _validate as check
from ..core.condense import make_condensation
from ..core.contact_kernels import _mmshbm_eval, _mmshbm_monitor_multi
from ..core.harmonics import check_harmonics
from ..core.modal_energy import kinetic_energy_shares
from ..model.contact import admissible_intervals
from ..model.model import Model

__all__ = ["MMSHBMProblem"]

_PROJECTIONS = ("exact", "sampled")


class MMSHBMProblem:
    """MMS-HBM on a :class:`Model`, as a continuation problem.

    Parameters
    ----------
    model : Model
        The structure; every contact DOF must be massless.
    harmonics : int
        Highest harmonic H >= 1.
    n_samples : int, optional
        Time samples per period N >= 2H+1 (default :func:`default_n_samples`): the
        sampled projection's rule, the exact projection's bracketing grid.
    r : float or sequence of float, optional
        Proximal parameter (N/m), one for all contact DOFs or one each. Default: each
        contact DOF's condensed static stiffness (e_iᵀ D_0⁻¹ e_i)⁻¹, so that both
        branches of the proximal map carry comparable numbers. The solution of the
        complementarity problem does not depend on it; Newton's conditioning does.
    mode : int
        Which linear mode (1-based) the branch starts from.
    backend : {"auto", "banded", "splu", "modal"}
        Linear solver of the condensation (:func:`~mmshbm.core.condense.make_condensation`).
    projection : {"exact", "sampled"}
        Harmonic projection of the contact law (see the module docstring).

    Notes
    -----
    The scaled unknown vector is ``u = [a_0/s, a_1/s, ..., a_H/s, Ω/ω_ref]`` with
    a_k ∈ R^{n_c} (``model.c`` order) and ``s`` the per-DOF length scale ``xscale``.
    """

    method = "mmshbm"

    def __init__(self, model: Model, harmonics: int = 5, n_samples: int | None = None,
                 r=None, mode: int = 1, backend: str = "auto", projection: str = "exact"):
        if not isinstance(model, Model):
            raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
        model.require_massless_contacts("MMS-HBM")
        self.model = model
        self.H, self.N = check_harmonics(harmonics, n_samples)
        self.mode = check.integer("mode", mode, minimum=1)
        if self.mode > len(model.l):
            raise ValueError(f"mode must be <= the number of DOFs with mass ({len(model.l)}), "
                             f"got {self.mode}")
        if projection not in _PROJECTIONS:
            raise ValueError(f"projection must be one of {_PROJECTIONS}, got {projection!r}")
        self.projection = projection
        self.cond = make_condensation(model, backend, harmonics=self.H, mode=self.mode)
        self.n_c = len(model.c)
        c_list = model.c.tolist()
        dofs, lo, hi = admissible_intervals(model.contacts)
        self.contact_dofs = dofs
        self.cdof = np.array([c_list.index(d) for d in dofs], dtype=np.int64)
        self.lo, self.hi = lo, hi
        D0inv = np.linalg.inv(self.cond.D0)
        self.contact_stiffness_each = 1.0 / np.diag(D0inv)[self.cdof]
        if r is None:
            self.r_each = self.contact_stiffness_each.copy()
        else:
            r_arr = np.atleast_1d(np.asarray(r, dtype=float))
            if r_arr.ndim != 1 or len(r_arr) not in (1, len(dofs)):
                raise ValueError(f"r must be a number or one per contact DOF ({len(dofs)}), got {r!r}")
            for v in r_arr:
                check.positive("r", float(v))
            self.r_each = np.broadcast_to(r_arr, (len(dofs),)).astype(float).copy()
        # the 0.1 names of a single contact
        self.contact_stiffness = float(self.contact_stiffness_each[0])
        self.r = float(self.r_each[0])
        self.gap = model.gap

        freqs, modes = model.linear_modes(self.mode)
        self.linear_frequency = float(freqs[-1])
        self.omega_ref = 2 * np.pi * self.linear_frequency
        phi = modes[:, -1]
        self.amplitude_dof = model.amplitude_dof
        ref = phi[self.amplitude_dof]
        if abs(ref) < 1e-12 * np.max(np.abs(phi)):
            raise ValueError(f"linear mode {self.mode} does not move the amplitude DOF {self.amplitude_dof}")
        # unit motion of the amplitude DOF at τ = 0 (linear_modes orients the modes so that
        # the first contact DOF moves toward its stop)
        self.mode_shape_c = phi[model.c] / abs(ref)
        contact_motion = np.abs(self.mode_shape_c[self.cdof]).max()
        if contact_motion < 1e-12 * np.abs(phi).max():
            raise ValueError(f"linear mode {self.mode} does not move any contact DOF: no impact")
        # amplitude: excursion away from the stop of a single one-sided contact, else |q|
        single = len(model.contacts) == 1 and model.contacts[0].dof == self.amplitude_dof
        self._amp_sign = float(-model.contacts[0].side) if single else 0.0
        self._amp_in_c = self.amplitude_dof in c_list
        self._amp_index = c_list.index(self.amplitude_dof) if self._amp_in_c else -1

        length = self.gap if self.gap > 0 else 1.0
        shape = np.abs(self.mode_shape_c)
        self.xscale = length * np.maximum(shape, 1e-3 * shape.max())
        self.colscale = np.concatenate([np.tile(self.xscale, self.H + 1), [self.omega_ref]])
        fscale = np.abs(self.cond.D0) @ self.xscale
        fscale[self.cdof] = self.contact_stiffness_each * length
        self.rowscale = np.tile(fscale, self.H + 1)
        self.n_unknowns = (self.H + 1) * self.n_c + 1

        H, N = self.H, self.N
        self._tau = 2 * np.pi * np.arange(N) / N
        self._cos_table = np.cos(np.outer(np.arange(2 * H + 1), self._tau))
        self._sin_table = np.sin(np.outer(np.arange(H + 1), self._tau))
        self._work = (np.empty((H + 1, self.n_c)), np.empty((H + 1, self.n_c)), np.empty(H + 1),
                      np.zeros(H + 1), np.empty(H + 1), np.empty(N), np.empty(N), np.empty(2 * N + 2),
                      np.empty(2 * H + 1), np.empty(2 * H + 1), np.empty(2 * H + 1), np.empty((H + 1, H + 1)))
        self._J_dummy = np.empty((1, 1))
        # the condensed stiffness of the last Ω (the monitor of a converged point reuses
        # the one of Newton's last evaluation)
        self._cached = (None, None, None)
        # fine grid for amplitude and peak force
        n_fine = max(512, 8 * N)
        self._tau_fine = 2 * np.pi * np.arange(n_fine) / n_fine
        self._cos_fine = np.cos(np.outer(np.arange(H + 1), self._tau_fine))
        self._modal = None  # open-contact modes for the energy shares (built on first use)

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

    def linear_point(self, amplitude: float) -> np.ndarray:
        """Scaled unknowns of the linear mode whose amplitude DOF swings ``amplitude``."""
        a = np.zeros((self.H + 1, self.n_c))
        a[1] = amplitude * self.mode_shape_c
        return self.pack(a, self.omega_ref)

    def initial_tangent(self) -> np.ndarray:
        """Unit tangent of the linear branch (growing amplitude, constant Ω)."""
        t = self.linear_point(1.0)
        t[-1] = 0.0
        return t / np.linalg.norm(t)

    # ------------------------------------------------------------------ residual
    def _condensed(self, omega: float, derivative: bool):
        """(D, dD) of :meth:`Condensation.dynamic_stiffness` at Ω (dD None unless
        ``derivative``), reusing the last result when Ω is the same number."""
        last, D, dD = self._cached
        if last == omega and (dD is not None or not derivative):
            return D, dD
        if derivative:
            D, dD = self.cond.dynamic_stiffness(omega, self.H, derivative=True)
        else:
            D, dD = self.cond.dynamic_stiffness(omega, self.H, derivative=False), None
        self._cached = (omega, D, dD)
        return D, dD

    def evaluate(self, u: np.ndarray, jacobian: bool = True):
        """Scaled residual ((H+1) n_c,) and, if asked, its Jacobian ((H+1) n_c, (H+1) n_c + 1)."""
        a, omega = self.unpack(u)
        D, dD = self._condensed(omega, jacobian)
        R = np.empty(self.n_unknowns - 1)
        J = np.empty((self.n_unknowns - 1, self.n_unknowns)) if jacobian else self._J_dummy
        _mmshbm_eval(D, D if dD is None else dD, np.ascontiguousarray(a), self.cdof, self.lo, self.hi,
                     self.r_each, self.projection == "exact", self._cos_table, self._sin_table, self._tau,
                     self.rowscale, self.colscale, jacobian, R, J, *self._work)
        return (R, J) if jacobian else R

    # ------------------------------------------------------------------ results
    def _force_series(self, a: np.ndarray, omega: float) -> np.ndarray:
        """Cosine coefficients (H+1, n_k) of the stop force λ at each contact DOF: −f where
        the DOF has an upper stop, +f where it has only a lower one (in a clearance λ is
        positive at the upper stop and negative at the lower one)."""
        D, _ = self._condensed(omega, False)
        F = np.einsum("kij,kj->ki", D, a)[:, self.cdof]
        return np.where(np.isfinite(self.hi)[None, :], -F, F)

    def contact_signals(self, u: np.ndarray, tau: np.ndarray | None = None):
        """Contact DOF displacement q(τ) (m) and stop force λ(τ) (N) on a grid.

        Returns (tau, q, lam): with one contact DOF ``q`` and ``lam`` have the shape of
        ``tau``; with several, shape (n_contact_dofs, len(tau)) in the order of
        ``contact_dofs``. ``tau`` defaults to a fine grid over one period. λ is the
        truncated series of the force the structure needs (−f at an upper stop, +f at a
        lower one).
        """
        a, omega = self.unpack(u)
        lam_k = self._force_series(a, omega)
        if tau is None:
            tau, C = self._tau_fine, self._cos_fine
        else:
            tau = np.asarray(tau, dtype=float)
            C = np.cos(np.outer(np.arange(self.H + 1), tau))
        q = a[:, self.cdof].T @ C
        lam = lam_k.T @ C
        if len(self.cdof) == 1:
            return tau, q[0], lam[0]
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
        a, omega = self.unpack(u)
        Q = self.coefficients(u)
        if dofs is not None:
            dofs = np.atleast_1d(np.asarray(dofs))
            if dofs.dtype.kind not in "iu" or np.any((dofs < -self.model.n_dof) | (dofs >= self.model.n_dof)):
                raise ValueError(f"dofs must be integer indices in [0, {self.model.n_dof - 1}], got {dofs}")
            Q = Q[dofs]
        tau = 2 * np.pi * np.arange(n_samples) / n_samples
        k = np.arange(1, self.H + 1)
        q = Q[:, :1] + Q[:, 1::2] @ np.cos(np.outer(k, tau)) + Q[:, 2::2] @ np.sin(np.outer(k, tau))
        return tau / omega, q

    def contact_force(self, u: np.ndarray, n_samples: int = 256):
        """(t (n_samples,) in s, λ in N) over one period (shape (n_samples,) with one
        contact DOF, (n_contact_dofs, n_samples) with several)."""
        n_samples = check.integer("n_samples", n_samples, minimum=1)
        a, omega = self.unpack(u)
        tau = 2 * np.pi * np.arange(n_samples) / n_samples
        _, _, lam = self.contact_signals(u, tau)
        return tau / omega, lam

    def harmonic_content(self, u: np.ndarray, dof: int | None = None) -> np.ndarray:
        """|Q_k| for k = 0..H of ``dof`` (default the amplitude DOF); shape (H+1,)."""
        dof = self.amplitude_dof if dof is None else check.integer("dof", dof)
        if not 0 <= dof < self.model.n_dof:
            raise ValueError(f"dof must be in [0, {self.model.n_dof - 1}], got {dof}")
        Q = self.coefficients(u)[dof]
        return np.concatenate([[abs(Q[0])], np.hypot(Q[1::2], Q[2::2])])

    def _amplitude_row(self, a: np.ndarray, omega: float) -> np.ndarray:
        """Cosine coefficients (H+1,) of the amplitude DOF's motion."""
        if self._amp_in_c:
            return np.ascontiguousarray(a[:, self._amp_index])
        Qc = np.zeros((self.n_c, 2 * self.H + 1))
        Qc[:, 0] = a[0]
        Qc[:, 1::2] = a[1:].T
        Ql = self.cond.recover(omega, Qc)
        row = Ql[int(np.searchsorted(self.model.l, self.amplitude_dof))]
        return np.concatenate([[row[0]], row[1::2]])

    def amplitude_and_gradient(self, u: np.ndarray) -> tuple[float, np.ndarray]:
        """The amplitude (m) and its gradient with respect to the scaled unknowns.

        The amplitude is the largest value of a smooth periodic function over τ, so its
        derivative is that of the function at the maximiser (envelope theorem), located
        on the fine grid and refined by Newton on q′(τ) = 0.
        """
        a, omega = self.unpack(u)
        row = self._amplitude_row(a, omega)
        sign = self._amp_sign
        q = row @ self._cos_fine
        y = sign * q if sign != 0.0 else np.abs(q)
        tau = self._tau_fine[int(np.argmax(y))]
        k = np.arange(self.H + 1)
        for _ in range(8):  # Newton on q'(τ) = 0 at the peak
            d1 = -(k * row) @ np.sin(k * tau)
            d2 = -(k * k * row) @ np.cos(k * tau)
            if d2 == 0.0:
                break
            step = d1 / d2
            tau -= step
            if abs(step) < 1e-14:
                break
        value = row @ np.cos(k * tau)
        s = sign if sign != 0.0 else math.copysign(1.0, value)
        grad = np.zeros(self.n_unknowns)
        if self._amp_in_c:
            grad[self._amp_index:-1:self.n_c] = s * np.cos(k * tau)
        else:  # finite differences through the recovery (amplitude DOF with mass)
            h = 1e-7
            for i in range(self.n_unknowns):
                e = np.zeros(self.n_unknowns)
                e[i] = h
                ap, om_p = self.unpack(u + e)
                am, om_m = self.unpack(u - e)
                diff = self._amplitude_row(ap, om_p) - self._amplitude_row(am, om_m)
                grad[i] = s * (diff @ np.cos(k * tau)) / (2 * h)
            return float(s * value), grad
        grad[-1] = 0.0
        return float(s * value), grad * self.colscale

    # ------------------------------------------------------------------ modal energy
    def _modal_basis(self):
        """Open-contact modes tracked for the energy shares: those below (H + 1) times the
        first clamped-contact frequency (an upper bound of Ω on the backbone), at least the
        starting mode and the next, at most 30."""
        if self._modal is None:
            model = self.model
            n_l = len(model.l)
            f_track = (self.H + 1) * self._upper_frequency()
            n = min(n_l, 30, max(self.mode + 1, 2))
            freqs, _ = model.linear_modes(min(n_l, 30))
            n = max(n, int(np.searchsorted(freqs, f_track)))
            n = min(n, n_l, 30)
            freqs, modes = model.linear_modes(n)
            Phi = modes[model.l]
            M_ll = model.blocks["M_ll"]
            self._modal = (freqs, Phi, np.ascontiguousarray((M_ll @ Phi).T), M_ll)
        return self._modal

    def _upper_frequency(self) -> float:
        """First eigenfrequency (Hz) of the structure with its massless DOFs clamped."""
        import scipy.linalg as la

        b = self.model.blocks
        if len(self.model.l) <= 600:
            w2 = la.eigh(b["K_ll"].toarray(), b["M_ll"].toarray(), eigvals_only=True, subset_by_index=(0, 0))
            return float(np.sqrt(max(w2[0], 0.0)) / (2 * np.pi))
        import scipy.sparse.linalg as spla

        w2 = spla.eigsh(b["K_ll"], k=1, M=b["M_ll"], sigma=0.0, which="LM", v0=np.ones(len(self.model.l)))[0]
        return float(np.sqrt(max(w2[0], 0.0)) / (2 * np.pi))

    @property
    def tracked_frequencies(self) -> np.ndarray:
        """Open-contact linear frequencies (Hz) of the modes in ``records["modal_shares"]``."""
        return self._modal_basis()[0]

    def modal_shares(self, u: np.ndarray) -> np.ndarray:
        """Period-mean kinetic energy share of each tracked open-contact mode j (rows) in
        each harmonic k (columns), shape (n_tracked, H+1)
        (:func:`~mmshbm.core.modal_energy.kinetic_energy_shares`)."""
        a, omega = self.unpack(u)
        freqs, Phi, MPhiT, M_ll = self._modal_basis()
        Qc = np.zeros((self.n_c, 2 * self.H + 1))
        Qc[:, 0] = a[0]
        Qc[:, 1::2] = a[1:].T
        Ql = self.cond.recover(omega, Qc)
        shares, _ = kinetic_energy_shares(Phi, MPhiT, Ql, omega, M_ll)
        return shares

    def monitor(self, u: np.ndarray) -> dict:
        """The per-point quantities of a backbone: frequency (Hz), amplitude (m), energy
        (J), contact_force_max (N), mode_share (kinetic energy share of the starting mode)
        and modal_shares (:meth:`modal_shares`)."""
        a, omega = self.unpack(u)
        D, dD = self._condensed(omega, True)
        out = np.empty(3)
        n_fine = self._cos_fine.shape[1]
        a = np.ascontiguousarray(a)
        _mmshbm_monitor_multi(D, dD, a, self.cdof, self.lo, self.hi, self.r_each, omega,
                              self._amplitude_row(a, omega), self._amp_sign, self._cos_fine, np.empty(n_fine),
                              np.empty(n_fine), out)
        shares = self.modal_shares(u)
        return {
            "frequency": omega / (2 * np.pi),
            "amplitude": float(out[0]),
            "energy": float(out[1]),
            "contact_force_max": float(out[2]),
            "mode_share": float(shares[self.mode - 1].sum()),
            "modal_shares": shares,
        }


def _condensed_energy(D: np.ndarray, dD: np.ndarray, a: np.ndarray, omega: float) -> float:
    """Period average of kinetic + potential energy (J) from the massless DOFs alone.

    With q_l,k = −Z_k a_k the mass-carrying DOFs satisfy their equations exactly, so
    q_kᵀ(K − (kΩ)²M)q_k = a_kᵀ D_k a_k and q_kᵀ M q_k = a_kᵀ Z_kᵀ M Z_k a_k
    = −a_kᵀ ∂D_k/∂Ω a_k / (2k²Ω). Parseval on the cosine motion then gives
    E = ½ a_0ᵀD_0 a_0 + ¼ Σ_{k>=1} (a_kᵀ D_k a_k − Ω a_kᵀ ∂D_k/∂Ω a_k), the same number as
    :func:`_mean_energy` on the recovered coefficients (up to round-off) without
    recovering any DOF with mass. D, dD: (H+1, n_c, n_c); a: (H+1, n_c).
    """
    quad = np.einsum("ki,kij,kj->k", a, D, a)
    quad_m = np.einsum("ki,kij,kj->k", a[1:], dD[1:], a[1:])
    return float(0.5 * quad[0] + 0.25 * (quad[1:].sum() - omega * quad_m.sum()))


def _refined_max(y: np.ndarray) -> float:
    """Largest value of a periodic sampled signal, refined by a parabola through the peak."""
    j = int(np.argmax(y))
    ym, y0, yp = y[j - 1], y[j], y[(j + 1) % len(y)]
    denom = ym - 2 * y0 + yp
    if denom < 0:
        return float(y0 - 0.125 * (yp - ym) ** 2 / denom)
    return float(y0)


def _mean_energy(model: Model, Q: np.ndarray, omega: float) -> float:
    """Period average of kinetic + potential energy (J) of the motion with NLvib-ordered
    coefficients Q (n_dof, 2H+1) at Ω (Parseval). A harmonic-balance solution conserves
    energy only up to truncation; its period average is the natural single number."""
    H = (Q.shape[1] - 1) // 2
    KQ = np.einsum("ij,ij->j", Q, model.K @ Q)  # qᵀKq per column
    MQ = np.einsum("ij,ij->j", Q, model.M @ Q)
    k = np.repeat(np.arange(1, H + 1), 2)
    V = 0.5 * KQ[0] + 0.25 * KQ[1:].sum()
    T = 0.25 * omega**2 * (k**2 * MQ[1:]).sum()
    return float(V + T)
