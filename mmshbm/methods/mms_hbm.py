"""The MMS-HBM residual and its semi-analytic Jacobian (Schreyer, Peter & Leine).

Unknowns: the Fourier coefficients of the massless (contact) DOFs q_c and the
fundamental frequency Ω. The linear structure is condensed per harmonic
(:mod:`mmshbm.core.condense`): F_k = D_k(Ω) a_k is the force the structure needs at the
massless DOFs. Equilibrium of the massless node and the Signorini law with the proximal
point function give, with λ = w_c·f_c and g_N = gap + w_c·q_c,

    contact DOF:   proj_k[ λ(τ) − max(0, λ(τ) − r g_N(τ)) ] = 0,  k = 0..H
    other c DOFs:  F_k,i = 0,

evaluated by alternating frequency-time (inverse FFT, Numba kernel on the samples,
forward FFT). Newton iterates only in these numbers, however many DOFs the FE model has.

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
Jacobian, and Newton converges quadratically away from grazing (tests show it). The
price: non-symmetric orbits (not expected on the backbones of undamped single-contact
structures) are outside the ansatz.

All vectors handed to the continuation are scaled: coefficients by the first mode's
contact-DOF shape times the gap, Ω by the first linear frequency, residual rows by
the force those scales produce.
"""

from __future__ import annotations

import numpy as np

from .. import _validate as check
from ..core.condense import Condensation
from ..core.harmonics import check_harmonics, transform
from ..core.kernels import (
    _cosine_product_matrix,
    _mmshbm_jacobian,
    _mmshbm_monitor,
    _mmshbm_residual,
    _proximal_contact,
)
from ..model.model import Model

__all__ = ["MMSHBMProblem"]


class MMSHBMProblem:
    """MMS-HBM on a :class:`Model`, as a continuation problem.

    Parameters
    ----------
    model : Model
        The structure (at least one massless DOF, the contact DOF among them).
    harmonics : int
        Highest harmonic H >= 1.
    n_samples : int, optional
        Time samples per period N >= 2H+1 (default :func:`default_n_samples`).
    r : float, optional
        Proximal parameter (N/m). Default: the condensed static contact stiffness
        (w_cᵀ D_0⁻¹ w_c)⁻¹, so that both branches of the max carry comparable numbers.
        The solution does not depend on it; Newton's conditioning does.
    mode : int
        Which linear mode (1-based) the branch starts from.
    backend : {"auto", "banded", "splu"}
        Linear solver of the condensation.

    Notes
    -----
    The scaled unknown vector is ``u = [a_0/s, a_1/s, ..., a_H/s, Ω/ω_ref]`` with
    a_k ∈ R^{n_c} (``model.c`` order) and ``s`` the per-DOF length scale ``xscale``.
    """

    method = "mmshbm"

    def __init__(self, model: Model, harmonics: int = 5, n_samples: int | None = None,
                 r: float | None = None, mode: int = 1, backend: str = "auto"):
        if not isinstance(model, Model):
            raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
        model.require_massless_contacts("MMS-HBM")
        self.model = model
        self.H, self.N = check_harmonics(harmonics, n_samples)
        self.mode = check.integer("mode", mode, minimum=1)
        if self.mode > len(model.l):
            raise ValueError(f"mode must be <= the number of DOFs with mass ({len(model.l)}), "
                             f"got {self.mode}")
        self.cond = Condensation(model, backend)
        self.n_c = len(model.c)
        self.ci = model.contact_index
        self.w = np.ascontiguousarray(model.w_c)
        self.gap = model.gap
        compliance = float(self.w @ np.linalg.solve(self.cond.D0, self.w))
        self.contact_stiffness = 1.0 / compliance
        self.r = self.contact_stiffness if r is None else check.positive("r", r)

        freqs, modes = model.linear_modes(self.mode)
        self.linear_frequency = float(freqs[-1])
        self.omega_ref = 2 * np.pi * self.linear_frequency
        phi_c = modes[model.c, -1]
        contact = phi_c[self.ci]
        if abs(contact) < 1e-12 * np.max(np.abs(phi_c)):
            raise ValueError(f"linear mode {self.mode} does not move the contact DOF: no impact")
        # unit contact motion toward the stop at τ = 0 (linear_modes orients the modes that way)
        self.mode_shape_c = phi_c / abs(contact)
        length = self.gap if self.gap > 0 else 1.0
        shape = np.abs(self.mode_shape_c)
        self.xscale = length * np.maximum(shape, 1e-3 * shape.max())
        self.colscale = np.concatenate([np.tile(self.xscale, self.H + 1), [self.omega_ref]])
        fscale = np.abs(self.cond.D0) @ self.xscale
        self.rowscale = np.tile(fscale, self.H + 1)
        self.rowscale[self.ci :: self.n_c] = self.contact_stiffness * length
        self.n_unknowns = (self.H + 1) * self.n_c + 1

        self._J = np.empty((self.n_unknowns - 1, self.n_unknowns))
        self._P = np.empty((self.H + 1, self.H + 1))
        self._R_t = np.empty(self.N)
        self._s_t = np.empty(self.N)
        # Few harmonics: synthesis and projection by a cosine table inside one kernel
        # (one call per evaluation); many: planned FFTs (see _TABLE_LIMIT).
        self._use_table = (2 * self.H + 1) * self.N <= _TABLE_LIMIT
        if self._use_table:
            tau = 2 * np.pi * np.arange(self.N) / self.N
            self._cos_table = np.cos(np.outer(np.arange(2 * self.H + 1), tau))
            self._dF = np.empty((self.H + 1, self.n_c))
            self._lam_t = np.empty(self.N)
            self._g_t = np.empty(self.N)
        # the condensed stiffness of the last Ω (the monitor of a converged point reuses
        # the one of Newton's last evaluation)
        self._cached = (None, None, None)
        # fine grid for amplitude and peak force
        n_fine = max(512, 8 * self.N)
        self._tau_fine = 2 * np.pi * np.arange(n_fine) / n_fine
        self._cos_fine = np.cos(np.outer(np.arange(self.H + 1), self._tau_fine))

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
        """Scaled unknowns of the linear mode whose contact DOF swings ``amplitude`` (m)."""
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
        if self._use_table:
            R = np.empty(self.n_unknowns - 1)
            J = np.empty((self.n_unknowns - 1, self.n_unknowns)) if jacobian else self._J
            _mmshbm_residual(D, D if dD is None else dD, np.ascontiguousarray(a), self.w, self.gap, self.r,
                             self.ci, self._cos_table, self.rowscale, self.colscale, jacobian, R, J,
                             self._P, self._dF, self._lam_t, self._g_t, self._R_t, self._s_t)
            return (R, J) if jacobian else R
        tr2, tr1 = transform(self.H, self.N, 2), transform(self.H, self.N, 1)
        F = np.einsum("kij,kj->ki", D, a)
        lam_k = F @ self.w
        g_k = a @ self.w
        g_k[0] += self.gap
        signals = tr2.cos_to_time(np.vstack([lam_k, g_k]))
        _proximal_contact(signals[0], signals[1], self.r, self._R_t, self._s_t)
        R = F.copy()
        R[:, self.ci] = tr1.time_to_cos(self._R_t[None, :])[0]
        R = R.ravel() / self.rowscale
        if not jacobian:
            return R
        dF = np.einsum("kij,kj->ki", dD, a)
        S = tr1.cosine_spectrum(self._s_t[None, :])[0]
        _cosine_product_matrix(S, self.H, self._P)
        _mmshbm_jacobian(self._P, D, dF, self.w, self.r, self.ci, self._J)
        J = self._J * self.colscale[None, :] / self.rowscale[:, None]
        return R, J

    # ------------------------------------------------------------------ results
    def contact_signals(self, u: np.ndarray, tau: np.ndarray | None = None):
        """Contact DOF displacement q(τ) (m) and contact force λ(τ) (N) on a grid.

        Returns (tau, q_contact, lam); ``tau`` defaults to a fine grid over one period.
        """
        a, omega = self.unpack(u)
        D, _ = self._condensed(omega, False)
        lam_k = np.einsum("kij,kj->ki", D, a) @ self.w
        if tau is None:
            tau, C = self._tau_fine, self._cos_fine
        else:
            tau = np.asarray(tau, dtype=float)
            C = np.cos(np.outer(np.arange(self.H + 1), tau))
        q = a[:, self.ci] @ C
        return tau, q, lam_k @ C

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
        """(t (n_samples,) in s, λ (n_samples,) in N) over one period."""
        n_samples = check.integer("n_samples", n_samples, minimum=1)
        a, omega = self.unpack(u)
        tau = 2 * np.pi * np.arange(n_samples) / n_samples
        _, _, lam = self.contact_signals(u, tau)
        return tau / omega, lam

    def harmonic_content(self, u: np.ndarray, dof: int | None = None) -> np.ndarray:
        """|Q_k| for k = 0..H of ``dof`` (default the contact DOF); shape (H+1,)."""
        dof = self.model.contact_dof if dof is None else check.integer("dof", dof)
        if not 0 <= dof < self.model.n_dof:
            raise ValueError(f"dof must be in [0, {self.model.n_dof - 1}], got {dof}")
        Q = self.coefficients(u)[dof]
        return np.concatenate([[abs(Q[0])], np.hypot(Q[1::2], Q[2::2])])

    def monitor(self, u: np.ndarray) -> dict:
        """The per-point quantities of a backbone: frequency (Hz), amplitude (m),
        energy (J), contact_force_max (N)."""
        a, omega = self.unpack(u)
        D, dD = self._condensed(omega, True)
        out = np.empty(3)
        n_fine = self._cos_fine.shape[1]
        _mmshbm_monitor(D, dD, np.ascontiguousarray(a), self.w, self.ci, omega, float(self.model.stop_side),
                        self._cos_fine, np.empty(n_fine), np.empty(n_fine), out)
        return {
            "frequency": omega / (2 * np.pi),
            "amplitude": float(out[0]),
            "energy": float(out[1]),
            "contact_force_max": float(out[2]),
        }


#: largest (2H+1)·N for which the residual synthesises and projects its samples with a
#: cosine table in the kernel instead of FFTs (measured on the 21-element beam: 7.7 µs
#: against 51 µs at H = 5, N = 128; 30 against 88 µs at H = 15, N = 256; 200 against
#: 94 µs at H = 40, N = 1024)
_TABLE_LIMIT = 20000


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
