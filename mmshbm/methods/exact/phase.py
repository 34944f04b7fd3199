"""One phase of the exact reference: the closed-form linear dynamics of a set of closed
contacts (see :mod:`mmshbm.methods.exact`), and the tolerances of its event search."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as la

__all__ = ["Phase"]

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
    """The closed-form linear dynamics of one contact state (a set of closed contacts).

    ``q_l(t) = q_static + modes @ (α cos(ω t) + β sin(ω t))`` with modal coordinates
    ``η = modes_inv @ (q_l - q_static)``. The phase holds while every one of its
    switching functions ``u_j = switch_offset[j] + switch_grad[j] · q_l`` is > 0: the gap
    g_N (m) of each open contact and the force λ (N) of each closed one.

    Attributes
    ----------
    name : {"open", "closed"}
        "open" when no contact is closed.
    active : tuple of int
        Indices (into ``model.contacts``) of the closed contacts, ascending.
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
    switch_grad : ndarray, shape (n_contacts, n_l)
    switch_offset : ndarray, shape (n_contacts,)
        One switching function per contact (in ``model.contacts`` order): its gap if it
        is open in this phase, its force if it is closed.
    switch_modal : ndarray, shape (n_contacts, n_l)
        ``switch_grad @ modes``: the switching functions' modal coefficients c_j.
    switch_static : ndarray, shape (n_contacts,)
        The switching functions at ``q_static``.
    """

    name: str
    active: tuple
    omega: np.ndarray
    modes: np.ndarray
    modes_inv: np.ndarray
    q_static: np.ndarray
    recover: np.ndarray
    recover_offset: np.ndarray
    switch_grad: np.ndarray
    switch_offset: np.ndarray
    switch_modal: np.ndarray = field(init=False)
    switch_static: np.ndarray = field(init=False)

    def __post_init__(self):
        object.__setattr__(self, "switch_modal", self.switch_grad @ self.modes)
        object.__setattr__(self, "switch_static", self.switch_offset + self.switch_grad @ self.q_static)
        pairs = list(zip(self.switch_grad, self.switch_offset, strict=True))
        # magnitudes that set the round-off of u: |offset| + |grad|·|q_static| + Σ_j |grad|·|φ_j| |η_j|
        absg = np.abs(self.switch_grad)
        qs = np.abs(self.q_static)
        object.__setattr__(self, "_abs_static", np.array([abs(o) + float(np.abs(g) @ qs) for g, o in pairs]))
        object.__setattr__(self, "_abs_modal", np.array([g @ np.abs(self.modes) for g in absg]))

    @property
    def n_switch(self) -> int:
        """Number of switching functions (= contacts)."""
        return len(self.switch_offset)

    def switch_scale(self, alpha: np.ndarray, beta: np.ndarray, j: int = 0) -> float:
        """Magnitude of the terms that sum to switching function ``j`` for the modal state
        (α, β): its round-off is a few ulps of this."""
        return self._abs_static[j] + float(self._abs_modal[j] @ np.hypot(alpha, beta))

    def switch_values(self, q_l) -> np.ndarray:
        """The switching functions at ``q_l`` (n_l,) or (n_l, n_t): shape (n_contacts,) or
        (n_contacts, n_t)."""
        q_l = np.asarray(q_l, dtype=float)
        return self.switch_offset.reshape((-1,) + (1,) * (q_l.ndim - 1)) + self.switch_grad @ q_l

    @classmethod
    def build(cls, name, active, M_ll, F_phase, q_static, recover, recover_offset, switch_grad,
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
        return cls(name, tuple(active), 1.0 / np.sqrt(mu), Phi, Phi.T @ M_ll,
                   np.asarray(q_static, dtype=float), recover, recover_offset,
                   np.atleast_2d(np.asarray(switch_grad, dtype=float)),
                   np.atleast_1d(np.asarray(switch_offset, dtype=float)))

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
