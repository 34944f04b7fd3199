"""Exact (round-off accurate) solutions of the piecewise-linear impact problem.

The structure of :class:`~mmshbm.model.Model`,

    M q'' + K q = W λ,    g_N = gap + w_c · q_c,    0 <= g_N ⊥ λ >= 0,

has massless DOFs ``c`` that follow the DOFs with mass ``l`` statically. Its motion is
piecewise linear with two phases, each a linear ODE in ``q_l`` with constant coefficients:

* **open** (λ = 0): ``q_c = -K_cc⁻¹ K_cl q_l`` and ``M_ll q_l'' + K_open q_l = 0``,
  ``K_open = K_ll - K_lc K_cc⁻¹ K_cl`` (``model.reduced_stiffness``);
* **closed** (g_N = 0): the contact DOF is held at the stop,
  ``q[contact_dof] = stop_side * gap``, the other massless DOFs are condensed statically,
  ``M_ll q_l'' + K_closed q_l = f_closed``, and λ follows from the static equation of
  the contact DOF.

Each phase is solved in closed form by its own modal decomposition (dense generalized
eigenproblem with ``M_ll``, mass-normalised modes, computed once per model):
``q_l(t) = q_static + Σ_j φ_j (α_j cos ω_j t + β_j sin ω_j t)``.

Facts this module relies on (derived here, checked in ``tests/test_exact.py``)
-------------------------------------------------------------------------------
* At fixed ``q_l`` the contact problem of the massless DOFs is a scalar LCP whose
  solution is ``λ = k_c max(0, -h(q_l))`` with the *free gap* ``h(q_l) = gap + a·q_l``
  (the gap the open condensation would give, ``a = -K_lc K_cc⁻¹ w_c``) and the condensed
  contact stiffness ``k_c = 1 / (w_cᵀ K_cc⁻¹ w_c)``. So the contact state is a function of
  ``q_l`` alone (:meth:`PiecewiseLinearSystem.state_to_full`), both switching functions
  (g_N in the open phase, λ in the closed one) vanish on the same hyperplane ``h = 0``,
  and ``K_closed = K_open + k_c a aᵀ``, ``f_closed = -k_c gap a``: the system is a
  *continuous* bilinear oscillator in ``q_l``. Its potential energy is
  ``½ q_lᵀ K_open q_l + ½ k_c min(0, h)²`` (= ½ qᵀ K q over all DOFs).
* Consequently nothing jumps at a switch: positions, velocities *and accelerations* of
  ``q_l`` are continuous (λ = 0 and g_N = 0 at the switching instant); only the third
  derivative jumps. There are no impacts and no impulses.
* Saltation matrix. For a switch at time t_e of the state z = (q_l, v_l) with vector
  fields f⁻ before and f⁺ after, ``S = I + (f⁺ - f⁻) ∇hᵀ / (∇h · f⁻)``. Here
  ``f⁺ - f⁻ = (0, -M_ll⁻¹ k_c h a) = 0`` on ``h = 0``, so **S = I**: the derivative of the
  flow with respect to the initial state is the plain product of the phases' transition
  matrices evaluated at the actual event times (``Trajectory.transition``). The flow is
  C¹ in the initial state even at grazing (only its second derivative blows up there).

Event location
--------------
In a phase the switching function is ``u(t) = u_s + Σ_j c_j (α_j cos ω_j t + β_j sin ω_j t)``
(g_N in the open phase, λ in the closed one; the phase holds while u > 0). It is sampled
on a step of ``1/samples_per_period`` of the shortest period among the modes that take
part (|c_j| |(α_j, β_j)| above 1e-15 of the signal's scale), together with its
derivative. The first sample below ``-1e-12·scale`` brackets the switch; local minima
between samples (sign change of u' from - to +, refined by brentq) catch shallow
crossings that no sample sees. A minimum that dips to within ``1e-12·scale`` of zero is a
*grazing* touch with zero contact force and does not switch (it is recorded as a
``"graze"`` event); the error of ignoring a penetration of that depth is far below
round-off of the trajectory because the vector field is continuous. The crossing is
refined by brentq to ~1e-15 relative in time. A phase that starts on the switching
surface (right after a switch) does not use the sign of u at t = 0: the left bracket of
its own switch is the first sample with u > 0 or, for a short phase, the maximum of u
located from u'.

Symmetric periodic orbits
-------------------------
The system is reversible, so a symmetric periodic orbit has all velocities zero at t = 0
and at t = T/2. :func:`periodic_orbit` solves for ``x = q_l(0)`` and ``T/2`` from
``v_l(T/2; x) = 0`` (n_l equations) and the **amplitude convention**:

    amplitude = -stop_side * q[contact_dof](0),

i.e. t = 0 is the turning point farthest from the stop, and the amplitude is the contact
DOF's excursion away from the stop there (below the gap this is the linear mode's
amplitude). For the orbits of the first-mode family this is the largest excursion away
from the stop over the period; each result also reports the measured maximum
(``max_excursion``) so that this can be checked. The Jacobian is exact:
``∂v_l(T/2)/∂x`` is the velocity-position block of the product of the transition
matrices (saltation = I, see above) and ``∂v_l(T/2)/∂(T/2)`` is the acceleration at T/2.
Newton converges quadratically wherever the number of switches does not change.

What the exact solutions of the beam look like
----------------------------------------------
(docs/exact.md has the numbers.) Single-contact symmetric orbits of the default beam end
within ~1e-4 (relative) of grazing (earlier for the finer tip element); beyond, orbits with
several contacts per period and internal resonances with high modes take over, strongly
unstable, and above ~1e-3 this Newton shooting does not converge from the continuation.
Always check ``converged`` and ``n_contacts``.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import weakref
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as la
from scipy.optimize import brentq

from . import _validate as check
from .model import Model

__all__ = [
    "Event",
    "Phase",
    "PiecewiseLinearSystem",
    "Trajectory",
    "PeriodicOrbit",
    "Backbone",
    "integrate",
    "periodic_orbit",
    "backbone",
]

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


# ============================================================================ event search
def _first_switch(phase: Phase, alpha: np.ndarray, beta: np.ndarray, t_max: float,
                  samples_per_period: int, t_ref: float):
    """First time in (0, t_max] at which the phase's switching function crosses to <= 0.

    Returns
    -------
    t_switch : float or None
        Local time of the switch, or None if the phase lasts beyond ``t_max``.
    grazes : list of (float, float)
        (local time, value of u) of grazing minima passed without switching.
    """
    c = phase.switch_modal
    amp = np.abs(c) * np.hypot(alpha, beta)
    u_s = phase.switch_static
    scale = phase.switch_scale(alpha, beta)
    if t_max <= 0.0 or scale == 0.0:
        return None, []
    keep = amp > _KEEP_REL * scale
    if not keep.any():  # constant switching function
        return (None, []) if u_s > 0 else (0.0, [])
    cc, cs, w = c[keep] * alpha[keep], c[keep] * beta[keep], phase.omega[keep]
    tol = _GRAZE_REL * scale
    xtol = 1e-17 * t_ref

    def u(t):
        return u_s + cc @ np.cos(w * t) + cs @ np.sin(w * t)

    def du(t):
        return (cs * w) @ np.cos(w * t) - (cc * w) @ np.sin(w * t)

    dt = 2 * np.pi / float(w.max()) / samples_per_period
    n_int = max(1, math.ceil(t_max / dt))
    dt = t_max / n_int
    # bound on |u''|: a minimum between two samples lies at most dt²/8·U2 below them
    dip = dt**2 / 8 * float(np.hypot(cc, cs) @ w**2)
    u0 = u(0.0)
    on_surface = abs(u0) <= tol
    if u0 < -tol:
        return 0.0, []  # the phase is not valid at its start (caller's concern)
    grazes = []
    t_pos = None if on_surface else 0.0  # last time known with u > 0
    k0 = 0
    chunk = _CHUNK_FIRST
    while k0 < n_int:
        k1 = min(n_int, k0 + chunk)
        chunk = min(2 * chunk, _CHUNK)
        t = np.arange(k0, k1 + 1) * dt
        t[-1] = min(t[-1], t_max)
        wt = np.multiply.outer(w, t)
        C, S = np.cos(wt), np.sin(wt)
        U = u_s + cc @ C + cs @ S
        D = (cs * w) @ C - (cc * w) @ S
        if k0 == 0 and on_surface:
            U[0] = 0.0  # never a left bracket
        neg = U[1:] < -tol
        lo = np.minimum(U[:-1], U[1:])
        has_min = (D[:-1] < 0) & (D[1:] > 0)
        cand = np.flatnonzero(neg | (has_min & (lo - dip < tol)))
        positive = U > 0
        for i in cand:
            ta, tb = t[i], t[i + 1]
            t_right = None
            if has_min[i]:
                tm = brentq(du, ta, tb, xtol=xtol, rtol=_RTOL)
                um = u(tm)
                if um < -tol:
                    t_right = tm
                elif um <= tol:
                    grazes.append((tm, um))
            if t_right is None and neg[i]:
                t_right = tb
            if t_right is None:
                continue
            # left bracket: a point with u > 0 before t_right
            first = k0 == 0 and i == 0 and on_surface
            t_left = ta if (positive[i] and not first) else None
            if t_left is None and D[i] > 0:  # a maximum between ta and t_right?
                d_right = D[i + 1] if t_right == tb else du(t_right)
                if d_right < 0:
                    tM = brentq(du, ta, t_right, xtol=xtol, rtol=_RTOL)
                    if u(tM) > 0:
                        t_left = tM
            if t_left is None:
                earlier = np.flatnonzero(positive[: i + 1])
                if len(earlier):
                    t_left = t[earlier[-1]]
                elif t_pos is not None:
                    t_left = t_pos
                else:
                    return 0.0, grazes  # never positive: a spurious phase
            t_sw = brentq(u, t_left, t_right, xtol=xtol, rtol=_RTOL)
            return t_sw, grazes
        idx = np.flatnonzero(positive)
        if len(idx):
            t_pos = t[idx[-1]]
        k0 = k1
    return None, grazes


# ============================================================================ trajectories
@dataclass(frozen=True)
class Event:
    """A switch of the contact state, or a grazing touch.

    Attributes
    ----------
    time : float
        Time (s).
    kind : {"close", "open", "graze"}
        ``"close"``: g_N reached 0 (the contact closes); ``"open"``: λ reached 0;
        ``"graze"``: g_N touched 0 tangentially (zero contact force), no switch.
    """

    time: float
    kind: str


@dataclass(frozen=True, eq=False)
class _Segment:
    phase: Phase
    t_start: float
    t_end: float
    alpha: np.ndarray
    beta: np.ndarray


class Trajectory:
    """A motion computed phase by phase in closed form.

    Attributes
    ----------
    system : PiecewiseLinearSystem
    t_end : float
        Final time (s); the trajectory covers [0, t_end].
    events : list of Event
        Switches (and grazing touches) in time order.
    transition : ndarray, shape (2 n_l, 2 n_l) or None
        d(q_l, v_l)(t_end) / d(q_l, v_l)(0), if computed (``sensitivity=True``).
    """

    def __init__(self, system, segments, events, transition):
        self.system = system
        self._segments = segments
        self.events = events
        self.t_end = segments[-1].t_end
        self.transition = transition
        self._starts = np.array([s.t_start for s in segments])

    @property
    def switch_times(self) -> np.ndarray:
        """Times (s) of the switches (no grazes), shape (n_switch,)."""
        return np.array([e.time for e in self.events if e.kind != "graze"])

    @property
    def phases(self) -> list[tuple[str, float, float]]:
        """(phase name, start time, end time) of each phase, in order."""
        return [(s.phase.name, s.t_start, s.t_end) for s in self._segments]

    @property
    def n_contacts(self) -> int:
        """Number of closed phases."""
        return sum(s.phase.name == "closed" for s in self._segments)

    def final_state(self) -> tuple[np.ndarray, np.ndarray]:
        """(q_l, v_l) at ``t_end``, each shape (n_l,)."""
        s = self._segments[-1]
        q, v, _ = s.phase.state(s.alpha, s.beta, s.t_end - s.t_start)
        return q, v

    def final_acceleration(self) -> np.ndarray:
        """q_l'' at ``t_end``, shape (n_l,)."""
        s = self._segments[-1]
        return s.phase.state(s.alpha, s.beta, s.t_end - s.t_start)[2]

    def state_l(self, t) -> tuple[np.ndarray, np.ndarray]:
        """Positions and velocities of the DOFs with mass at times ``t``.

        Parameters
        ----------
        t : array_like, shape (n_t,) or scalar
            Times (s) in [0, t_end].

        Returns
        -------
        q_l, v_l : ndarray, shape (n_l, n_t) (or (n_l,) for scalar t)
        """
        t_arr = np.atleast_1d(np.asarray(t, dtype=float))
        if t_arr.ndim != 1:
            raise ValueError(f"t must be a scalar or 1-D, got shape {t_arr.shape}")
        if not np.all(np.isfinite(t_arr)) or (t_arr.size and (t_arr.min() < 0 or t_arr.max() > self.t_end)):
            raise ValueError(f"t must lie in [0, t_end = {self.t_end!r}], got values in "
                             f"[{t_arr.min()!r}, {t_arr.max()!r}]")
        seg = np.clip(np.searchsorted(self._starts, t_arr, side="right") - 1, 0, len(self._segments) - 1)
        q = np.empty((self.system.n_l, t_arr.size))
        v = np.empty_like(q)
        for k in np.unique(seg):
            s = self._segments[k]
            m = seg == k
            q[:, m], v[:, m], _ = s.phase.state(s.alpha, s.beta, t_arr[m] - s.t_start)
        if np.ndim(t) == 0:
            return q[:, 0], v[:, 0]
        return q, v

    def evaluate(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """All DOFs, their velocities and the contact force at times ``t``.

        Returns
        -------
        q, v : ndarray, shape (n_dof, n_t) (or (n_dof,) for scalar t)
            Displacements/rotations (m, rad) and velocities of all DOFs.
        lam : ndarray, shape (n_t,) (or scalar)
            Contact force (N).
        """
        q_l, v_l = self.state_l(t)
        q, lam, v = self.system.state_to_full(q_l, v_l)
        return q, v, lam

    def q(self, t) -> np.ndarray:
        """All DOFs at times ``t``, shape (n_dof, n_t)."""
        return self.evaluate(t)[0]

    def v(self, t) -> np.ndarray:
        """All DOFs' velocities at times ``t``, shape (n_dof, n_t)."""
        return self.evaluate(t)[1]

    def contact_force(self, t) -> np.ndarray:
        """Contact force λ (N) at times ``t``, shape (n_t,)."""
        return self.evaluate(t)[2]

    def __repr__(self) -> str:
        kinds = [e.kind for e in self.events]
        return (f"Trajectory(t_end={self.t_end:.6g} s, phases={len(self._segments)}, "
                f"closes={kinds.count('close')}, grazes={kinds.count('graze')})")


def integrate(model_or_system, q_l0, v_l0, t_end: float, *, sensitivity: bool = False,
              samples_per_period: int = 16, max_events: int = 100_000) -> Trajectory:
    """Exact free motion from (q_l0, v_l0) at t = 0 up to ``t_end``.

    Parameters
    ----------
    model_or_system : Model or PiecewiseLinearSystem
    q_l0, v_l0 : array_like, shape (n_l,)
        Initial positions (m, rad) and velocities of the DOFs with mass (the massless DOFs
        follow).
    t_end : float
        Final time (s), >= 0.
    sensitivity : bool
        Also compute ``Trajectory.transition``, the derivative of the final state with
        respect to the initial state (exact: product of the phases' transition matrices,
        the saltation matrices being the identity).
    samples_per_period : int
        Samples of the switching function per shortest period of the modes that take part
        (>= 4) for the event search.
    max_events : int
        Stop with a ValueError after this many switches.

    Returns
    -------
    Trajectory
    """
    system = PiecewiseLinearSystem.of(model_or_system)
    q = system._check_states("q_l0", q_l0, (system.n_l,)).copy()
    v = system._check_states("v_l0", v_l0, (system.n_l,)).copy()
    t_end = check.non_negative("t_end", t_end)
    samples_per_period = check.integer("samples_per_period", samples_per_period, minimum=4)
    max_events = check.integer("max_events", max_events, minimum=1)
    t_ref = 2 * np.pi / system._omega_ref
    phase = system.initial_phase(q, v)
    other = {"open": system.closed, "closed": system.open}
    t = 0.0
    segments, events = [], []
    Tr = np.eye(2 * system.n_l) if sensitivity else None
    n_zero = 0
    while True:
        alpha, beta = phase.modal_state(q, v)
        t_sw, grazes = _first_switch(phase, alpha, beta, t_end - t, samples_per_period, t_ref)
        events.extend(Event(t + tg, "graze") for tg, _ in grazes)
        duration = (t_end - t) if t_sw is None else t_sw
        t_next = t_end if t_sw is None else t + duration
        if duration > 0 or t_sw is None or not segments:
            segments.append(_Segment(phase, t, t_next, alpha, beta))
        if sensitivity and duration > 0:
            Tr = phase.transition(duration) @ Tr
        if t_sw is None:
            break
        q, v, _ = phase.state(alpha, beta, duration)
        n_zero = n_zero + 1 if duration == 0 else 0
        if n_zero > 4:
            raise RuntimeError(f"event location stalled at t = {t!r} s (repeated zero-length phases)")
        t = t_next
        events.append(Event(t, "close" if phase.name == "open" else "open"))
        if len(events) > max_events:
            raise ValueError(f"more than max_events = {max_events} switches before t_end = {t_end!r} s")
        phase = other[phase.name]
    return Trajectory(system, segments, events, Tr)


# ============================================================================ periodic orbits
@dataclass(frozen=True, eq=False)
class PeriodicOrbit:
    """A symmetric periodic orbit (all velocities zero at t = 0 and t = T/2).

    Attributes
    ----------
    amplitude : float
        Prescribed ``-stop_side * q[contact_dof](0)`` (m).
    period : float
        T (s).
    frequency : float
        1/T (Hz).
    x : ndarray, shape (n_l,)
        q_l(0) (m, rad); t = 0 is the turning point farthest from the stop.
    q0 : ndarray, shape (n_dof,)
        All DOFs at t = 0.
    n_contacts : int
        Closed phases per period (from the symmetric half period).
    events : list of Event
        Switches and grazes over one period [0, T].
    converged : bool
    iterations : int
        Newton iterations.
    residual : float
        Final max |v_l(T/2)| / (ω_1 · amplitude), dimensionless.
    energy : float
        Total energy (J).
    max_excursion : float
        Measured max over the period of ``-stop_side * q[contact_dof]`` (m).
    max_contact_force : float
        Largest λ over the period (N), sampled.
    multipliers : ndarray, shape (2 n_l,)
        Floquet multipliers (eigenvalues of the monodromy matrix), complex.
    periodicity_error : float
        max |state(T) - state(0)| of the direct integration over a full period, relative
        to the state's scale (grows with instability).
    trajectory : Trajectory
        The motion over [0, T].
    """

    amplitude: float
    period: float
    frequency: float
    x: np.ndarray
    q0: np.ndarray
    n_contacts: int
    events: list
    converged: bool
    iterations: int
    residual: float
    energy: float
    max_excursion: float
    max_contact_force: float
    multipliers: np.ndarray
    periodicity_error: float
    trajectory: Trajectory

    @property
    def half_period(self) -> float:
        """T/2 (s)."""
        return 0.5 * self.period

    @property
    def multiple_contacts(self) -> bool:
        """True if the orbit has several contact phases per period."""
        return self.n_contacts > 1

    def __repr__(self) -> str:
        return (f"PeriodicOrbit(amplitude={self.amplitude:.6g} m, frequency={self.frequency:.12g} Hz, "
                f"n_contacts={self.n_contacts}, converged={self.converged}, iterations={self.iterations})")


def _guess(system: PiecewiseLinearSystem, amplitude: float) -> tuple[np.ndarray, float]:
    """The first open mode scaled to the amplitude, and the half period of the one-DOF
    analogue (DESIGN.md section 4 item 2) with ω1, ω2 the first open and closed frequencies."""
    phi = system.open.modes[:, 0]
    x = amplitude * phi / (system.amplitude_row @ phi)
    w1, w2 = system.open.omega[0], system.closed.omega[0]
    g = system.model.gap
    if amplitude <= g:
        return x, np.pi / w1
    rho = (w1 / w2) ** 2
    B = math.sqrt((rho * g) ** 2 + rho * (amplitude**2 - g**2))
    T = 2 / w1 * math.acos(-g / amplitude) + 2 / w2 * math.acos(min(1.0, rho * g / B))
    return x, 0.5 * T


def _scaled_jacobian(dv_dx, dv_dtau, r, w1, A) -> np.ndarray:
    """Jacobian of F = (v / (w1 A), r·x / A - 1) with respect to z = (x / A, tau w1)."""
    n = len(r)
    J = np.zeros((n + 1, n + 1))
    J[:n, :n] = dv_dx / w1
    J[:n, n] = dv_dtau / (w1**2 * A)
    J[n, :n] = r
    return J


def _shoot(system, x, tau, samples_per_period):
    """v_l(tau) and its derivatives with respect to x and tau from the start (x, 0)."""
    traj = integrate(system, x, np.zeros_like(x), tau, sensitivity=True,
                     samples_per_period=samples_per_period)
    _, v = traj.final_state()
    n = system.n_l
    dv_dx = traj.transition[n:, :n]
    dv_dtau = traj.final_acceleration()
    return v, dv_dx, dv_dtau, traj


def periodic_orbit(model_or_system, amplitude: float, guess=None, *, tol: float = 1e-13,
                   max_iter: int = 30, samples_per_period: int = 16) -> PeriodicOrbit:
    """The symmetric periodic orbit of prescribed amplitude, by Newton shooting.

    Parameters
    ----------
    model_or_system : Model or PiecewiseLinearSystem
    amplitude : float
        ``-stop_side * q[contact_dof](0)`` (m), > 0: the contact DOF's excursion away from
        the stop at the turning point t = 0 (see the module docstring).
    guess : PeriodicOrbit or (x, half_period), optional
        Starting point; x of shape (n_l,) is rescaled to the amplitude. Default: the first
        linear (open) mode and the one-DOF analogue's half period.
    tol : float
        Convergence: the scaled residual max |v_l(T/2)| / (ω_1 amplitude) and the scaled
        Newton step both below ``tol``, or the residual below ``tol**1.1``.
    max_iter : int
        Newton iterations at most.
    samples_per_period : int
        Passed to :func:`integrate`.

    Returns
    -------
    PeriodicOrbit
        ``converged`` says whether Newton met ``tol``; a non-converged result carries the
        last iterate.
    """
    system = PiecewiseLinearSystem.of(model_or_system)
    A = check.positive("amplitude", amplitude)
    tol = check.positive("tol", tol)
    max_iter = check.integer("max_iter", max_iter, minimum=1)
    r = system.amplitude_row
    if guess is None:
        x, tau = _guess(system, A)
    else:
        if isinstance(guess, PeriodicOrbit):
            x, tau = guess.x, guess.half_period
        else:
            try:
                x, tau = guess
            except (TypeError, ValueError):
                raise TypeError("guess must be a PeriodicOrbit or a pair (x, half_period)") from None
        x = system._check_states("guess x", x, (system.n_l,))
        tau = check.positive("guess half_period", tau)
        ax = r @ x
        if not ax > 0:
            raise ValueError(f"guess x has excursion {ax!r} <= 0 away from the stop")
        x = x * (A / ax)
    w1 = system._omega_ref
    n = system.n_l
    # round-off floor of the scaled residual: velocities synthesised from modes up to ω_max
    floor = system._velocity_roundoff * float(np.abs(x).max()) / (w1 * A)
    # scaled unknowns z = (x / A, tau w1), equations F = (v / (w1 A), r·x/A - 1)
    v, dv_dx, dv_dtau, _ = _shoot(system, x, tau, samples_per_period)
    F = np.append(v / (w1 * A), r @ x / A - 1.0)
    res = float(np.abs(F).max())
    converged, it = res <= 1e-16, 0
    while not converged and it < max_iter:
        it += 1
        try:
            dz = -np.linalg.solve(_scaled_jacobian(dv_dx, dv_dtau, r, w1, A), F)
        except np.linalg.LinAlgError:
            logger.warning("singular shooting Jacobian at amplitude %g", A)
            break
        step = 1.0
        for _ in range(12):  # backtracking on the residual
            x_new = x + step * A * dz[:n]
            tau_new = tau + step * dz[n] / w1
            if tau_new > 0:
                v_n, dvx_n, dvt_n, _ = _shoot(system, x_new, tau_new, samples_per_period)
                F_n = np.append(v_n / (w1 * A), r @ x_new / A - 1.0)
                res_n = float(np.abs(F_n).max())
                if res_n < res or res_n <= floor:
                    break
            step *= 0.5
        else:
            converged = res <= floor
            if not converged:
                logger.info("line search failed at amplitude %g (residual %.3e)", A, res)
            break
        x, tau, F, res = x_new, tau_new, F_n, res_n
        dv_dx, dv_dtau = dvx_n, dvt_n
        converged = step * float(np.abs(dz).max()) <= tol and res <= max(floor, tol)
    return _orbit_result(system, A, x, tau, converged, it, res, samples_per_period)


def _orbit_result(system, A, x, tau, converged, iterations, res, samples_per_period) -> PeriodicOrbit:
    half = integrate(system, x, np.zeros_like(x), tau, samples_per_period=samples_per_period)
    kinds = [e.kind for e in half.events]
    n_close = kinds.count("close")
    closed_at_half = half.phases[-1][0] == "closed"
    n_contacts = 2 * n_close - (1 if closed_at_half else 0)
    full = integrate(system, x, np.zeros_like(x), 2 * tau, sensitivity=True,
                     samples_per_period=samples_per_period)
    qT, vT = full.final_state()
    w1 = system._omega_ref
    scale = max(float(np.abs(x).max()), 1e-300)
    periodicity = max(float(np.abs(qT - x).max()), float(np.abs(vT).max()) / w1) / scale
    # excursion and contact force, sampled densely and refined at the sampled extremes
    ts = np.linspace(0.0, tau, 2049)
    q_half, _, lam = half.evaluate(ts)
    m = system.model
    exc = -m.stop_side * q_half[m.contact_dof]
    max_exc = float(exc.max())
    energy = float(system.energy(x, np.zeros_like(x)))
    multipliers = np.linalg.eigvals(full.transition)
    q0, _ = system.state_to_full(x)
    return PeriodicOrbit(
        amplitude=A, period=2 * tau, frequency=1.0 / (2 * tau), x=x, q0=q0, n_contacts=n_contacts,
        events=full.events, converged=bool(converged), iterations=int(iterations), residual=res,
        energy=energy, max_excursion=max_exc, max_contact_force=float(np.max(lam)),
        multipliers=multipliers, periodicity_error=periodicity, trajectory=full)


# ============================================================================ backbone
@dataclass(frozen=True, eq=False)
class Backbone:
    """Symmetric periodic orbits along a sequence of amplitudes.

    Attributes
    ----------
    amplitude, period, frequency, energy : ndarray, shape (n,)
        m, s, Hz, J.
    n_contacts : ndarray of int, shape (n,)
        Closed phases per period.
    converged : ndarray of bool, shape (n,)
    x : ndarray, shape (n, n_l)
        Initial positions q_l(0).
    max_excursion : ndarray, shape (n,)
        Measured largest excursion away from the stop (m): equals ``amplitude`` when the
        amplitude convention holds.
    stable : ndarray of bool, shape (n,)
        All Floquet multipliers on the unit circle (to 1e-6).
    orbits : list of PeriodicOrbit
    """

    amplitude: np.ndarray
    period: np.ndarray
    frequency: np.ndarray
    energy: np.ndarray
    n_contacts: np.ndarray
    converged: np.ndarray
    x: np.ndarray
    max_excursion: np.ndarray
    stable: np.ndarray
    orbits: list

    def __len__(self) -> int:
        return len(self.amplitude)


def backbone(model_or_system, amplitudes, *, guess=None, max_halvings: int = 6,
             max_jump: float = 0.25, **kwargs) -> Backbone:
    """Continue symmetric periodic orbits in amplitude (natural parameter).

    Each point starts from the previous converged orbit (secant extrapolation in amplitude
    from the two previous ones once available). If Newton fails the step is halved up to
    ``max_halvings`` times through intermediate amplitudes (not reported); a point that
    still fails is reported with ``converged = False`` and the continuation goes on from
    the last converged orbit. A converged orbit that lands far from the last converged one
    (half period off by more than ``max_jump`` relative, or shape rescaled to the
    amplitude off by more than ``4 max_jump`` of its largest entry) is taken for a jump to
    another family and treated as a failure (observed: from 1.5 to 3 gaps in one step the
    chain of the tests lands on the second nonlinear mode traversed four times). Orbits
    with several contacts per period are logged at INFO level and flagged by
    ``n_contacts``.

    Parameters
    ----------
    model_or_system : Model or PiecewiseLinearSystem
    amplitudes : array_like, shape (n,)
        Amplitudes (m), > 0, in the order to visit them.
    guess : PeriodicOrbit or (x, half_period), optional
        Start of the first point.
    max_halvings : int
    max_jump : float
        Largest accepted relative change of the half period from one converged orbit to
        the next (natural steps and halvings alike).
    **kwargs
        Passed to :func:`periodic_orbit` (tol, max_iter, samples_per_period).

    Returns
    -------
    Backbone
    """
    system = PiecewiseLinearSystem.of(model_or_system)
    A_all = np.atleast_1d(np.asarray(amplitudes, dtype=float))
    if A_all.ndim != 1 or A_all.size == 0:
        raise ValueError(f"amplitudes must be a non-empty 1-D array, got shape {A_all.shape}")
    if not np.all(np.isfinite(A_all)) or np.any(A_all <= 0):
        raise ValueError(f"amplitudes must be finite and > 0, got {A_all!r}")
    max_halvings = check.integer("max_halvings", max_halvings, minimum=0)
    max_jump = check.positive("max_jump", max_jump)
    history: list[PeriodicOrbit] = []  # converged orbits, for the predictor
    if isinstance(guess, PeriodicOrbit):
        history.append(guess)
        guess_pair = None
    else:
        guess_pair = guess

    def predict(A):
        if not history:
            return guess_pair
        o1 = history[-1]
        if len(history) >= 2 and history[-2].amplitude != o1.amplitude:
            o0 = history[-2]
            s = (A - o1.amplitude) / (o1.amplitude - o0.amplitude)
            x = o1.x + s * (o1.x - o0.x)
            tau = o1.half_period + s * (o1.half_period - o0.half_period)
            if tau > 0 and system.amplitude_row @ x > 0:
                return x, tau
        return o1.x, o1.half_period

    def jumped(orbit) -> bool:
        if not history:
            return False
        x_p, tau_p = history[-1].x, history[-1].half_period
        x_p = x_p * (orbit.amplitude / (system.amplitude_row @ x_p))
        dx = float(np.abs(orbit.x - x_p).max()) / float(np.abs(x_p).max())
        return abs(orbit.half_period / tau_p - 1) > max_jump or dx > 4 * max_jump

    def reach(target: float, depth: int) -> PeriodicOrbit:
        orbit = periodic_orbit(system, target, predict(target), **kwargs)
        if orbit.converged and jumped(orbit):
            logger.info("amplitude %.6g m: converged onto another family (f = %.6g Hz); rejected",
                        target, orbit.frequency)
            orbit = dataclasses.replace(orbit, converged=False)
        if orbit.converged or depth == 0 or not history:
            return orbit
        mid = reach(0.5 * (history[-1].amplitude + target), depth - 1)
        if not mid.converged:
            return orbit
        history.append(mid)
        return reach(target, depth - 1)

    orbits = []
    for A in A_all:
        target = float(A)
        orbit = reach(target, max_halvings)
        if orbit.converged:
            history.append(orbit)
            if orbit.multiple_contacts:
                logger.info("amplitude %.6g m: %d contacts per period (f = %.6g Hz)",
                            target, orbit.n_contacts, orbit.frequency)
        else:
            logger.warning("no converged orbit at amplitude %.6g m (residual %.3e)", target, orbit.residual)
        orbits.append(orbit)

    def arr(name, dtype=float):
        return np.array([getattr(o, name) for o in orbits], dtype=dtype)

    stable = np.array([bool(np.all(np.abs(np.abs(o.multipliers) - 1) < 1e-6)) for o in orbits])
    return Backbone(amplitude=arr("amplitude"), period=arr("period"), frequency=arr("frequency"),
                    energy=arr("energy"), n_contacts=arr("n_contacts", int),
                    converged=arr("converged", bool), x=np.array([o.x for o in orbits]),
                    max_excursion=arr("max_excursion"), stable=stable, orbits=orbits)
