"""Impact with friction on one massless node: periodic forced orbits by shooting, the node's
law (Signorini in the normal direction, Coulomb with the normal force preload + λ(t) in the
tangential one) solved exactly at every step.

The model: one unilateral contact j on a massless DOF n (stop at side·gap, gap function
g_N = gap − side·q_n >= 0, force on the node −side·λ with λ >= 0) and one friction contact
on a massless DOF t with ``normal_contact=j`` (slip force S = μ (preload + λ)). With
A = K_cc⁻¹ (every massless DOF condensed), p_i = K_lc A e_i and the support's tangential
force g on the node,

    M q_l'' + C q_l' + K_red q_l = F(t) + side·λ p_n − g p_t,
    q_c = A (−side λ e_n + g e_t − K_cl q_l).

Time stepping: Newmark's average acceleration with (λ, g) implicit. q_{n+1} is affine in
(λ, g) (one factorisation of K_eff per Ω), so are q_n and u_t; each step picks, among
normal {open: λ = 0, closed: g_N = 0} × tangential {stick: u_t = u_t,old, slip: g = ±S},
the combination whose inequalities hold (λ >= 0 or g_N >= 0; |g| <= S; the node sliding
against the force): a 2 × 2 linear solve each, the previous step's state tried first. This
is the exact proximal point of the node's laws over the step. Periodic orbits: Newton on
the period map of (q_l, q_l', u_t), forward differences. No exact reference exists for this
case; tests/friction/test_friction_impact.py checks the limits (μ = 0 is the impact model, a stop
that is never reached is constant-load friction) and the convergence in Δt.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as la

from ... import _validate as check
from ..mms.forced import Excitation, harmonic_force

__all__ = ["ImpactFrictionShooting", "impact_friction_orbit"]

_COMBOS = [(nm, tg) for nm in ("open", "closed") for tg in ("stick", +1, -1)]


class ImpactFrictionShooting:
    """The period map of a model with one node in impact with friction (module docstring).

    Parameters
    ----------
    model : Model
        One unilateral contact and one friction contact with ``normal_contact`` = that
        contact, both on massless DOFs; damping optional.
    force : array_like (n_dof,) or Excitation
    frequency : float
        Hz.
    steps_per_period : int
    """

    def __init__(self, model, force, frequency: float, steps_per_period: int = 512):
        if len(model.contacts) != 1 or len(model.friction) != 1 or model.friction[0].normal_contact != 0:
            raise NotImplementedError("impact with friction is solved for one unilateral contact and one "
                                      "friction contact coupled to it (normal_contact=0)")
        exc = force if isinstance(force, Excitation) else harmonic_force(model, force)
        self.omega = 2 * np.pi * check.positive("frequency", frequency)
        self.steps = check.integer("steps_per_period", steps_per_period, minimum=8)
        ct, fc = model.contacts[0], model.friction[0]
        self.side, self.gap = float(ct.side), float(ct.gap)
        self.mu, self.preload = float(fc.mu), float(fc.preload)
        b = model.blocks
        self.M = b["M_ll"].toarray()
        self.C = b["C_ll"].toarray() if b["C_ll"] is not None else np.zeros_like(self.M)
        K = model.reduced_stiffness.toarray()
        self.K = 0.5 * (K + K.T)
        A = la.inv(b["K_cc"].toarray() if hasattr(b["K_cc"], "toarray") else b["K_cc"])
        i_n, i_t = (int(np.searchsorted(model.c, d)) for d in (ct.dof, fc.dof))
        K_lc = b["K_lc"].toarray() if hasattr(b["K_lc"], "toarray") else np.asarray(b["K_lc"])
        self.p_n, self.p_t = K_lc @ A[:, i_n], K_lc @ A[:, i_t]
        self.A2 = A[np.ix_([i_n, i_t], [i_n, i_t])]
        self.h = h = 2 * np.pi / self.omega / self.steps
        self._lu = la.lu_factor(self.K + 2.0 / h * self.C + 4.0 / h**2 * self.M)
        self._M_lu = la.lu_factor(self.M)
        self.Z_n = la.lu_solve(self._lu, self.side * self.p_n)  # ∂q_{n+1}/∂λ
        self.Z_t = la.lu_solve(self._lu, -self.p_t)            # ∂q_{n+1}/∂g
        tau = 2 * np.pi * np.arange(self.steps + 1) / self.steps
        sig, _ = exc.scale(self.omega)
        self._F = np.real(np.outer(sig * exc.vector[model.l], np.exp(1j * tau)))
        self.model = model

    def _node(self, q0, Zn, Zt, u_old, first):
        """(λ, g, u_t, combination) of the node with q = q0 + Zn λ + Zt g."""
        s, A = self.side, self.A2
        # q_n and u_t affine in (λ, g): c + R @ (λ, g)
        c = np.array([-self.p_n @ q0, -self.p_t @ q0])
        R = np.array([[-s * A[0, 0] - self.p_n @ Zn, A[0, 1] - self.p_n @ Zt],
                      [-s * A[1, 0] - self.p_t @ Zn, A[1, 1] - self.p_t @ Zt]])
        for nm, tg in sorted(_COMBOS, key=lambda cb: cb != first):
            E, r = np.zeros((2, 2)), np.zeros(2)
            if nm == "open":
                E[0], r[0] = (1.0, 0.0), 0.0                         # λ = 0
            else:
                E[0], r[0] = -s * R[0], s * c[0] - self.gap          # gap − s q_n = 0
            if tg == "stick":
                E[1], r[1] = R[1], u_old - c[1]                      # u_t = u_old
            else:
                E[1], r[1] = (-tg * self.mu, 1.0), tg * self.mu * self.preload   # g = ±μ(N0 + λ)
            try:
                lam, g = np.linalg.solve(E, r)
            except np.linalg.LinAlgError:
                continue
            qn, ut = c + R @ (lam, g)
            S = self.mu * (self.preload + lam)
            tol = 1e-12 * max(1.0, abs(S))
            ok_n = lam >= -tol if nm == "closed" else self.gap - s * qn >= -1e-14 * max(self.gap, 1e-300)
            if tg == "stick":
                ok_t = abs(g) <= S + tol
            else:  # g = +S pushes the node toward −: it must not move +
                ok_t = -tg * (ut - u_old) >= -1e-14 * max(abs(ut), 1e-300)
            if ok_n and ok_t and S >= -tol:
                return max(lam, 0.0), g, ut, (nm, tg)
        raise RuntimeError("no consistent contact state at the step (μ too large for the coupling?)")

    def march(self, z: np.ndarray, record: bool = False):
        """One period from z = (q_l, q_l', u_t) at t = 0: the state at T and, with ``record``,
        (q_l (n_l, steps+1), λ (steps+1,), g (steps+1,), u_t (steps+1,))."""
        n = self.M.shape[0]
        q, v, u = z[:n].copy(), z[n:2 * n].copy(), float(z[-1])
        h, zero = self.h, np.zeros(n)
        lam, g, u, state = self._node(q, zero, zero, u, ("open", "stick"))
        a = la.lu_solve(self._M_lu, self._F[:, 0] + self.side * lam * self.p_n - g * self.p_t
                        - self.C @ v - self.K @ q)
        if record:
            out = [np.empty((n, self.steps + 1))] + [np.empty(self.steps + 1) for _ in range(3)]
            out[0][:, 0], out[1][0], out[2][0], out[3][0] = q, lam, g, u
        for j in range(1, self.steps + 1):
            rhs = self._F[:, j] + self.M @ (4.0 / h**2 * (q + h * v) + a) + self.C @ (2.0 / h * q + v)
            q0 = la.lu_solve(self._lu, rhs)
            lam, g, u, state = self._node(q0, self.Z_n, self.Z_t, u, state)
            q1 = q0 + self.Z_n * lam + self.Z_t * g
            a1 = 4.0 / h**2 * (q1 - q - h * v) - a
            v = 2.0 / h * (q1 - q) - v
            q, a = q1, a1
            if record:
                out[0][:, j], out[1][j], out[2][j], out[3][j] = q, lam, g, u
        end = np.concatenate([q, v, [u]])
        return (end, tuple(out)) if record else end


def impact_friction_orbit(model, force, frequency: float, steps_per_period: int = 512, guess=None, *,
                          tol: float = 1e-10, max_iter: int = 40, settle_periods: int = 20):
    """Periodic orbit of a node in impact with friction by shooting (module docstring).

    Returns (state z = (q_l, q_l', u_t) at t = 0, converged, the recorded period
    (q_l, λ, g, u_t), the :class:`ImpactFrictionShooting`).
    """
    sh = ImpactFrictionShooting(model, force, frequency, steps_per_period)
    n = sh.M.shape[0]
    z = np.zeros(2 * n + 1) if guess is None else np.asarray(guess, dtype=float).copy()
    for _ in range(settle_periods):
        z = sh.march(z)

    def scales(z):
        q = max(float(np.abs(z[:n]).max()), abs(z[-1]), 1e-300)
        return np.concatenate([np.full(n, q), np.full(n, q * sh.omega), [q]])

    converged = False
    for _ in range(max_iter):
        sc = scales(z)
        r = sh.march(z) - z
        if float(np.abs(r / sc).max()) <= tol:
            converged = True
            break
        J = np.empty((2 * n + 1, 2 * n + 1))
        for j in range(2 * n + 1):
            e = z.copy()
            e[j] += 1e-7 * sc[j]
            J[:, j] = (sh.march(e) - r - z) / (1e-7 * sc[j])
        J -= np.eye(2 * n + 1)
        dz = np.linalg.lstsq(J, -r, rcond=None)[0]
        big = float(np.abs(dz / sc).max())
        z = z + (dz / big if big > 1.0 else dz)
    _, rec = sh.march(z, record=True)
    return z, converged, rec, sh
