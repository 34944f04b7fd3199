"""The piecewise-linear system of the exact reference: its two phases (open, closed),
each solved in closed form by its own modal decomposition (see :mod:`mmshbm.methods.exact`)."""

from __future__ import annotations

import logging
import weakref
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as la

from ...model.model import Model

__all__ = ["Phase", "PiecewiseLinearSystem"]

logger = logging.getLogger(__name__)

# Modes whose share of a switching function is below this (relative to its scale) are left
# out of the choice of the sampling step (they are kept in every evaluation).
_KEEP_REL = 1e-15
# A minimum of a switching function within this (relative) distance of zero is a grazing
# touch, not a switch.
_GRAZE_REL = 1e-12
# Samples per evaluation chunk of the event search: the first chunk, doubling up to the last.
_CHUNK_FIRST = 32
_CHUNK = 8192
# brentq's smallest allowed relative tolerance
_RTOL = 4 * np.finfo(float).eps



# ============================================================================ phases
@dataclass(frozen=True, eq=False)
class Phase:
    """The closed-form linear dynamics of one contact state.

    ``q_l(t) = q_static + modes @ (α cos(ω t) + β sin(ω t))`` with modal coordinates
    ``η = modes_inv @ (q_l - q_static)``; the switching function is
    ``u = switch_offset + switch_grad · q_l`` (the gap g_N (m) in the open phase, the
    contact force λ (N) in the closed one) and the phase holds while u > 0.

    Attributes
    ----------
    name : {"open", "closed"}
    omega : ndarray, shape (n_l,)
        Natural angular frequencies (rad/s) of the phase, ascending.
    modes : ndarray, shape (n_l, n_l)
        Mass-normalised mode shapes Φ (columns): Φᵀ M_ll Φ = I.
    modes_inv : ndarray, shape (n_l, n_l)
        Φᵀ M_ll, the inverse of Φ.
    q_static : ndarray, shape (n_l,)
        Static equilibrium of the phase (m, rad): zero for the open phase.
    recover, recover_offset : ndarray, shapes (n_c, n_l) and (n_c,)
        The massless DOFs: ``q_c = recover @ q_l + recover_offset``.
    switch_grad : ndarray, shape (n_l,)
    switch_offset : float
    switch_modal : ndarray, shape (n_l,)
        ``switch_grad @ modes``: the switching function's modal coefficients c_j.
    switch_static : float
        The switching function at ``q_static``.
    """

    name: str
    omega: np.ndarray
    modes: np.ndarray
    modes_inv: np.ndarray
    q_static: np.ndarray
    recover: np.ndarray
    recover_offset: np.ndarray
    switch_grad: np.ndarray
    switch_offset: float
    switch_modal: np.ndarray = field(init=False)
    switch_static: float = field(init=False)

    def __post_init__(self):
        object.__setattr__(self, "switch_modal", self.switch_grad @ self.modes)
        object.__setattr__(self, "switch_static",
                           float(self.switch_offset + self.switch_grad @ self.q_static))
        # magnitudes that set the round-off of u: |offset| + |grad|·|q_static| + Σ_j |grad|·|φ_j| |η_j|
        g = np.abs(self.switch_grad)
        object.__setattr__(self, "_abs_static", abs(self.switch_offset) + float(g @ np.abs(self.q_static)))
        object.__setattr__(self, "_abs_modal", g @ np.abs(self.modes))

    def switch_scale(self, alpha: np.ndarray, beta: np.ndarray) -> float:
        """Magnitude of the terms that sum to the switching function for the modal state
        (α, β): its round-off is a few ulps of this."""
        return self._abs_static + float(self._abs_modal @ np.hypot(alpha, beta))

    @classmethod
    def build(cls, name, M_ll, F_phase, q_static, recover, recover_offset, switch_grad,
              switch_offset) -> Phase:
        """Solve the phase's eigenproblem in flexibility form, ``F M φ = ω⁻² φ`` with
        ``F = K_phase⁻¹`` (so that the low modes, which carry the motion, are accurate to
        round-off; see :func:`_accurate_solve`)."""
        A = M_ll @ F_phase @ M_ll
        mu, Phi = la.eigh(0.5 * (A + A.T), M_ll)
        if mu[0] <= 0:
            raise ValueError(f"the {name} phase's stiffness is not positive definite "
                             f"(smallest flexibility eigenvalue {mu[0]:.3e})")
        mu, Phi = mu[::-1], Phi[:, ::-1]
        return cls(name, 1.0 / np.sqrt(mu), Phi, Phi.T @ M_ll, np.asarray(q_static, dtype=float),
                   recover, recover_offset, np.asarray(switch_grad, dtype=float), float(switch_offset))

    def modal_state(self, q_l: np.ndarray, v_l: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Modal coefficients (α, β), each shape (n_l,), of the state (q_l, v_l) at local time 0."""
        alpha = self.modes_inv @ (q_l - self.q_static)
        beta = (self.modes_inv @ v_l) / self.omega
        return alpha, beta

    def state(self, alpha: np.ndarray, beta: np.ndarray, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions, velocities and accelerations of ``q_l`` at local times ``t``.

        ``t`` scalar gives shapes (n_l,); an array of shape (n_t,) gives (n_l, n_t).
        """
        t = np.asarray(t, dtype=float)
        wt = np.multiply.outer(self.omega, t)
        C, S = np.cos(wt), np.sin(wt)
        a = alpha.reshape((-1,) + (1,) * t.ndim)
        b = beta.reshape((-1,) + (1,) * t.ndim)
        w = self.omega.reshape((-1,) + (1,) * t.ndim)
        eta = a * C + b * S
        deta = w * (b * C - a * S)
        q = self.modes @ eta
        q = q + self.q_static.reshape((-1,) + (1,) * t.ndim)
        return q, self.modes @ deta, -(self.modes @ (w**2 * eta))

    def transition(self, tau: float) -> np.ndarray:
        """Transition matrix, shape (2 n_l, 2 n_l), of the state (q_l, v_l) over a duration
        ``tau`` (s): d(q_l, v_l)(tau) / d(q_l, v_l)(0)."""
        C, S = np.cos(self.omega * tau), np.sin(self.omega * tau)
        P, Q = self.modes, self.modes_inv
        qq = (P * C) @ Q
        return np.block([[qq, (P * (S / self.omega)) @ Q], [(P * (-self.omega * S)) @ Q, qq]])


# ============================================================================ system
class PiecewiseLinearSystem:
    """Both phases of a :class:`~mmshbm.model.Model`, precomputed once.

    Parameters
    ----------
    model : Model
        The structure; dense eigen-decompositions of size n_l are computed, so this is
        meant for models up to a few hundred DOFs with mass.

    Attributes
    ----------
    model : Model
    n_l, n_c : int
        Numbers of DOFs with mass and of massless DOFs.
    gap_gradient : ndarray, shape (n_l,)
        ``a`` in the free gap ``h(q_l) = gap + a · q_l`` (m).
    contact_stiffness : float
        ``k_c = 1 / (w_cᵀ K_cc⁻¹ w_c)`` (N/m): λ = k_c max(0, -h).
    open, closed : Phase
    """

    def __init__(self, model: Model):
        if not isinstance(model, Model):
            raise TypeError(f"model must be a mmshbm.Model, got {type(model).__name__}")
        model.require_massless_contacts("the exact reference")
        self.model = model
        b = model.blocks
        M_ll = b["M_ll"].toarray()
        K_lc, K_cc = b["K_lc"], b["K_cc"]
        self.n_l, self.n_c = M_ll.shape[0], K_cc.shape[0]
        self.M_ll = M_ll
        self.K = model.K.tocsr()
        s, ci, gap = model.stop_side, model.contact_index, model.gap
        w_c = model.w_c

        l, n_dof = model.l, model.n_dof
        K_full = self.K.toarray()

        # open phase: q_c = R_o q_l, flexibility K_open⁻¹ = [K⁻¹]_ll
        R_o = -la.solve(K_cc, K_lc.T, assume_a="pos")
        E_l = np.zeros((n_dof, self.n_l))
        E_l[l, np.arange(self.n_l)] = 1.0
        F_open = _accurate_solve(K_full, E_l)[l]
        self.gap_gradient = R_o.T @ w_c
        self.contact_stiffness = float(1.0 / (w_c @ la.solve(K_cc, w_c, assume_a="pos")))
        self.open = Phase.build("open", M_ll, 0.5 * (F_open + F_open.T), np.zeros(self.n_l), R_o,
                                np.zeros(self.n_c), self.gap_gradient, gap)

        # closed phase: contact DOF prescribed at the stop, the other massless DOFs r condensed
        r = np.setdiff1d(np.arange(self.n_c), [ci])
        u_c = s * gap
        R_c = np.zeros((self.n_c, self.n_l))
        r0 = np.zeros(self.n_c)
        r0[ci] = u_c
        if len(r):
            K_rr = K_cc[np.ix_(r, r)]
            R_c[r] = -la.solve(K_rr, K_lc[:, r].T, assume_a="pos")
            r0[r] = -la.solve(K_rr, K_cc[r, ci], assume_a="pos") * u_c
        # K_closed⁻¹ = [K_f⁻¹]_ll with K_f = K without the contact DOF; the static state
        # solves K_f y = -K[f, contact] u_c
        free = np.setdiff1d(np.arange(n_dof), [model.contact_dof])
        l_in_free = np.searchsorted(free, l)
        rhs = np.zeros((len(free), self.n_l + 1))
        rhs[l_in_free, np.arange(self.n_l)] = 1.0
        rhs[:, -1] = -K_full[free, model.contact_dof] * u_c
        Y = _accurate_solve(K_full[np.ix_(free, free)], rhs)[l_in_free]
        F_closed = 0.5 * (Y[:, :-1] + Y[:, :-1].T)
        # λ from the contact DOF's static row: K_ci,l q_l + K_ci,c q_c = w_c[ci] λ = -s λ
        lam_grad = -s * (K_lc[:, ci] + R_c.T @ K_cc[ci])
        lam_offset = -s * float(K_cc[ci] @ r0)
        self.closed = Phase.build("closed", M_ll, F_closed, Y[:, -1], R_c, r0, lam_grad, lam_offset)
        self._omega_ref = float(self.open.omega[0])
        self._K_ld = K_full.astype(np.longdouble)
        self._M_ld = M_ll.astype(np.longdouble)
        # bound on the round-off of velocities synthesised from modes, per unit of |q_l|
        self._velocity_roundoff = np.finfo(float).eps * max(
            float((np.abs(p.modes) * p.omega @ np.abs(p.modes_inv)).sum(axis=1).max())
            for p in (self.open, self.closed))

    @classmethod
    def of(cls, model_or_system) -> PiecewiseLinearSystem:
        """The system of a model (built once per model and cached), or the system itself."""
        if isinstance(model_or_system, PiecewiseLinearSystem):
            return model_or_system
        if not isinstance(model_or_system, Model):
            raise TypeError("expected a mmshbm.Model or a PiecewiseLinearSystem, got "
                            f"{type(model_or_system).__name__}")
        system = _SYSTEMS.get(model_or_system)
        if system is None:
            system = cls(model_or_system)
            _SYSTEMS[model_or_system] = system
        return system

    # ------------------------------------------------------------------ state
    @property
    def amplitude_row(self) -> np.ndarray:
        """Row ``r`` (n_l,) with ``-stop_side * q[contact_dof] = r · q_l`` in the open phase."""
        m = self.model
        return -m.stop_side * self.open.recover[m.contact_index]

    def free_gap(self, q_l) -> np.ndarray:
        """Free gap ``h = gap + a · q_l`` (m); ``q_l`` shape (n_l,) or (n_l, n_t)."""
        q_l = np.asarray(q_l, dtype=float)
        return self.model.gap + self.gap_gradient @ q_l

    def contact_force(self, q_l) -> np.ndarray:
        """Contact force λ = k_c max(0, -h(q_l)) (N); shape () or (n_t,)."""
        return self.contact_stiffness * np.maximum(0.0, -self.free_gap(q_l))

    def state_to_full(self, q_l, v_l=None):
        """All DOFs and the contact force from the DOFs with mass.

        Parameters
        ----------
        q_l : array_like, shape (n_l,) or (n_l, n_t)
            Positions of the DOFs with mass (m, rad).
        v_l : array_like, optional, same shape
            Their velocities; if given the full velocity vector is returned as well.

        Returns
        -------
        q : ndarray, shape (n_dof,) or (n_dof, n_t)
        lam : float or ndarray, shape (n_t,)
            Contact force (N), >= 0.
        v : ndarray, like ``q`` (only if ``v_l`` is given)
            The massless DOFs' velocities follow statically (the contact DOF's is zero
            while the contact is closed).
        """
        q_l = self._check_states("q_l", q_l)
        closed = self.free_gap(q_l) < 0
        q_o = self.open.recover @ q_l
        q_k = self.closed.recover @ q_l + self.closed.recover_offset.reshape((-1,) + (1,) * (q_l.ndim - 1))
        q = np.zeros((self.model.n_dof,) + q_l.shape[1:])
        q[self.model.l] = q_l
        q[self.model.c] = np.where(closed, q_k, q_o)
        lam = np.where(closed, self.closed.switch_offset + self.closed.switch_grad @ q_l, 0.0)
        lam = np.maximum(lam, 0.0)
        if v_l is None:
            return q, lam
        v_l = self._check_states("v_l", v_l, q_l.shape)
        v = np.zeros_like(q)
        v[self.model.l] = v_l
        v[self.model.c] = np.where(closed, self.closed.recover @ v_l, self.open.recover @ v_l)
        return q, lam, v

    def energy(self, q_l, v_l) -> np.ndarray:
        """Total energy ½ v_lᵀ M_ll v_l + ½ qᵀ K q (J), q over all DOFs; shape () or (n_t,).
        It is conserved exactly by the motion."""
        q, _ = self.state_to_full(q_l)
        v_l = self._check_states("v_l", v_l, np.shape(q_l))
        # accumulate in extended precision: qᵀ K q of a stiff graded mesh cancels heavily
        ld = np.longdouble
        kinetic = np.einsum("i...,i...->...", v_l.astype(ld), self._M_ld @ v_l.astype(ld))
        potential = np.einsum("i...,i...->...", q.astype(ld), self._K_ld @ q.astype(ld))
        return (0.5 * (kinetic + potential)).astype(float)

    def initial_phase(self, q_l: np.ndarray, v_l: np.ndarray) -> Phase:
        """The phase a motion starting at (q_l, v_l) begins in: by the sign of the free gap
        h, and on the surface h = 0 by the sign of h' and then h'' (open if all vanish)."""
        h = self.free_gap(q_l)
        a = self.gap_gradient
        scale = abs(self.model.gap) + float(np.abs(a) @ np.abs(q_l))
        if abs(h) > _GRAZE_REL * scale or scale == 0.0:
            return self.open if h >= 0 else self.closed
        dh = a @ v_l
        alpha, beta = self.open.modal_state(q_l, v_l)
        w = self.open.omega
        dscale = float(np.abs(self.open.switch_modal * w) @ np.hypot(alpha, beta))
        if abs(dh) > _GRAZE_REL * dscale:
            return self.open if dh > 0 else self.closed
        ddh = -float(self.open.switch_modal @ (w**2 * alpha))
        return self.closed if ddh < 0 else self.open

    def _check_states(self, name, x, shape=None) -> np.ndarray:
        try:
            x = np.asarray(x, dtype=float)
        except (TypeError, ValueError) as err:
            raise TypeError(f"{name} must be an array of numbers: {err}") from None
        if x.ndim not in (1, 2) or x.shape[0] != self.n_l:
            raise ValueError(f"{name} must have shape ({self.n_l},) or ({self.n_l}, n_t), got {x.shape}")
        if shape is not None and x.shape != tuple(shape):
            raise ValueError(f"{name} must have shape {tuple(shape)}, got {x.shape}")
        if not np.all(np.isfinite(x)):
            raise ValueError(f"{name} has non-finite entries")
        return x

    def __repr__(self) -> str:
        f_o = self.open.omega[0] / (2 * np.pi)
        f_c = self.closed.omega[0] / (2 * np.pi)
        return (f"PiecewiseLinearSystem(n_l={self.n_l}, n_c={self.n_c}, f_open={f_o:.6g} Hz, "
                f"f_closed={f_c:.6g} Hz, k_c={self.contact_stiffness:.6g} N/m)")


def _accurate_solve(K: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``K⁻¹ B`` for a symmetric positive definite ``K`` by Cholesky plus one step of
    iterative refinement with the residual accumulated in extended precision
    (``np.longdouble``).

    Stiffness matrices of graded meshes are ill-conditioned (cond ~ (ω_max/ω_1)²); the
    refinement makes the flexibility, and so the lowest modes, accurate to round-off
    (measured on the 21-element beam against 40-digit mpmath: ω_1 to 2e-15 instead of 9e-10
    for ``eigh(K_open, M)``; the highest modes are accurate to ~2e-10).
    """
    factor = la.cho_factor(K)
    X = la.cho_solve(factor, B)
    R = B.astype(np.longdouble) - K.astype(np.longdouble) @ X.astype(np.longdouble)
    return X + la.cho_solve(factor, R.astype(float))


_SYSTEMS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
