"""Baseline: periodic forced orbits with Coulomb friction by time-domain shooting, the
friction node's law solved exactly (its proximal point) at every step.

One friction contact with constant normal load, no unilateral contact (the setting of
:mod:`mmshbm.methods.exact.friction`, whose :class:`FrictionSystem` supplies the reduced
equations): with g the support's force on the node, y = wᵀq_l the free node's position
and k = 1/(K_cc⁻¹)_tt,

    M q_l'' + C q_l' + K_red q_l = F(t) + w g,      g = k (u − y) with |g| <= s, u the node.

Time stepping: Newmark's average acceleration (trapezoidal, second order, unconditionally
stable) with the friction force implicit. At each step the node's law is the proximal
point g_{n+1} = clip(k (u_n − y_{n+1}), −s, s) (stick at u_n, or slide with |g| = s and
u_{n+1} = y_{n+1} + g/k) — the return map of Coulomb's law over the step. y_{n+1} is affine
in g_{n+1} and decreasing, so the clip has one fixed point: the stick trial
(K_eff + k w wᵀ) q = rhs + k u_n w, accepted when |g| <= s, else the slip solve
K_eff q = rhs ± s w (both matrices factored once per Ω). The periodic orbit: Newton on
the period map of the state (q_l, q_l', u) with a forward-difference Jacobian (the map is
piecewise affine: the differences are exact away from a change of the step's branch).
Error against the exact orbit: O(Δt²) on smooth phases, the switches located to within a
step (tests/friction/test_friction_shooting.py measures the rate).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as la

from ... import _validate as check
from ...core.problem import ForcedProblemBase, OneEvaluation
from ..exact.friction import FrictionSystem, periodic_state

__all__ = ["FrictionShooting", "friction_shooting_orbit", "ShootingOrbit"]


class FrictionShooting:
    """The period map by Newmark steps with the friction node's exact prox per step.

    Parameters
    ----------
    model : Model
        One friction contact (constant normal load), no unilateral contact.
    force : array_like (n_dof,) or Excitation
    frequency : float
        Hz.
    steps_per_period : int
        Newmark steps per period (>= 8).
    """

    def __init__(self, model, force, frequency: float, steps_per_period: int = 256):
        omega = 2 * np.pi * check.positive("frequency", frequency)
        self.steps = check.integer("steps_per_period", steps_per_period, minimum=8)
        sysm = FrictionSystem(model, force, omega)
        self.system = sysm
        b = model.blocks
        self.M = b["M_ll"].toarray()
        self.C = sysm.C
        K = model.reduced_stiffness.toarray()
        self.K = 0.5 * (K + K.T)
        self.w, self.k, self.s = sysm.w, sysm.k, sysm.s
        self.omega = omega
        self.h = h = 2 * np.pi / omega / self.steps
        K_eff = self.K + 2.0 / h * self.C + 4.0 / h**2 * self.M
        self._slip = la.lu_factor(K_eff)
        self._stick = la.lu_factor(K_eff + self.k * np.outer(self.w, self.w))
        self._M_lu = la.lu_factor(self.M)
        tau = 2 * np.pi * np.arange(self.steps + 1) / self.steps
        self._F = np.real(np.outer(sysm.F_l, np.exp(1j * tau)))  # F(t_j) (n_l, steps+1)

    def _g(self, q, u):
        return float(np.clip(self.k * (u - self.w @ q), -self.s, self.s))

    def march(self, z: np.ndarray, record: bool = False):
        """One period from the state z = (q_l, q_l', u) at t = 0: the state at T and, with
        ``record``, the samples (q_l (n_l, steps+1), u (steps+1,), g (steps+1,))."""
        n = self.M.shape[0]
        q, v, u = z[:n].copy(), z[n:2 * n].copy(), float(z[-1])
        h, w, k, s = self.h, self.w, self.k, self.s
        g = self._g(q, u)
        u = self.w @ q + g / k if abs(g) >= s else u
        a = la.lu_solve(self._M_lu, self._F[:, 0] + w * g - self.C @ v - self.K @ q)
        if record:
            Q, U, G = np.empty((n, self.steps + 1)), np.empty(self.steps + 1), np.empty(self.steps + 1)
            Q[:, 0], U[0], G[0] = q, u, g
        for j in range(1, self.steps + 1):
            rhs = self._F[:, j] + self.M @ (4.0 / h**2 * (q + h * v) + a) + self.C @ (2.0 / h * q + v)
            q1 = la.lu_solve(self._stick, rhs + k * u * w)
            g = k * (u - w @ q1)
            if abs(g) > s:  # slides: the force at the slip bound, the node dragged along
                g = s if g > 0 else -s
                q1 = la.lu_solve(self._slip, rhs + g * w)
                u = w @ q1 + g / k
            a1 = 4.0 / h**2 * (q1 - q - h * v) - a
            v = 2.0 / h * (q1 - q) - v
            q, a = q1, a1
            if record:
                Q[:, j], U[j], G[j] = q, u, g
        out = np.concatenate([q, v, [u]])
        return (out, (Q, U, G)) if record else out


class ShootingOrbit:
    """A periodic orbit by :class:`FrictionShooting`: ``state`` (q_l, q_l', u) at t = 0,
    ``converged``, ``residual``, and the sampled period (``q_l``, ``u``, ``g``: the support's
    force on the node, N)."""

    def __init__(self, shooting, state, converged, residual, iterations):
        self.shooting, self.state, self.converged = shooting, state, converged
        self.residual, self.iterations = residual, iterations
        _, (self.q_l, self.u, self.g) = shooting.march(state, record=True)

    def amplitude(self, dof: int) -> float:
        """Largest |q| (m) over the samples of a DOF with mass (model numbering)."""
        model = self.shooting.system.model
        i = int(np.flatnonzero(model.l == dof)[0])
        return float(np.abs(self.q_l[i]).max())

    @property
    def slip_fraction(self) -> float:
        return float(np.mean(np.abs(self.g[1:]) >= self.shooting.s * (1 - 1e-12)))


def friction_shooting_orbit(model, force, frequency: float, steps_per_period: int = 256, guess=None, *,
                            tol: float = 1e-11, max_iter: int = 40, settle_periods: int = 3) -> ShootingOrbit:
    """Periodic orbit by shooting with the exact prox of the friction node per step.

    Parameters
    ----------
    model, force, frequency, steps_per_period
        As :class:`FrictionShooting`.
    guess : ndarray (2 n_l + 1,), optional
        (q_l(0), q_l'(0), u(0)); default the stuck linear response at u = 0 (that of
        :func:`mmshbm.methods.exact.friction.friction_orbit`).
    tol : float
        On max |z(T) − z(0)| relative to the state's scale.
    settle_periods : int
        Periods marched from the guess before Newton.
    """
    sh = FrictionShooting(model, force, frequency, steps_per_period)
    n = sh.M.shape[0]
    z = (np.concatenate([sh.system.stick(0.0).particular(0.0)[0], [0.0]]) if guess is None
         else np.asarray(guess, dtype=float).copy())
    for _ in range(settle_periods):
        z = sh.march(z)

    z, converged, it, res = periodic_state(sh.march, z, n, sh.omega, tol, max_iter)
    return ShootingOrbit(sh, z, converged, res, it)


class FrictionShootingProblem(OneEvaluation, ForcedProblemBase):
    """Shooting with friction as a continuation problem in (z, Ω) for
    :func:`mmshbm.frequency_response` (``method="shooting"``): unknowns the state
    z = (q_l, q_l', u) at t = 0 and Ω, scaled; residual z(T) − z; Jacobian by forward
    differences of the period map (2 n_l + 2 marches per Jacobian; small models).

    Parameters
    ----------
    model : Model
        One friction contact (constant normal load), no unilateral contact.
    force : array_like (n_dof,) or Excitation
    steps_per_period : int
        Newmark steps per period.
    stability : bool
        Not available (False).
    """

    method = "shooting"

    def __init__(self, model, force, steps_per_period: int = 256, stability: bool = False):
        if stability:
            raise NotImplementedError("Floquet multipliers of friction orbits are not available for shooting")
        self.model, self.force = model, force
        self.steps = check.integer("steps_per_period", steps_per_period, minimum=8)
        sh = FrictionShooting(model, force, 1.0, self.steps)  # validates, gives the sizes
        self.n_l = n = sh.M.shape[0]
        self.n_unknowns = 2 * n + 2
        freqs, _ = model.linear_modes(1)
        self.omega_ref = 2 * np.pi * float(freqs[0])
        self.amplitude_dof = model.amplitude_dof
        self._track = int(np.flatnonzero(model.l == model.amplitude_dof)[0])
        F_l = np.abs(sh.system.F_l)
        stat = np.linalg.solve(sh.K, F_l)
        q = float(np.abs(stat).max()) or 1.0
        self.colscale = np.concatenate([np.full(n, q), np.full(n, q * self.omega_ref), [q, self.omega_ref]])
        self._cache = {}

    def _shooting(self, omega: float) -> FrictionShooting:
        if omega not in self._cache:
            self._cache.clear()
            self._cache[omega] = FrictionShooting(self.model, self.force, omega / (2 * np.pi), self.steps)
        return self._cache[omega]

    def unpack(self, u):
        y = np.asarray(u, dtype=float) * self.colscale
        return y[:-1], float(y[-1])

    def pack(self, z, omega):
        return np.concatenate([z, [omega]]) / self.colscale

    def initial_tangent(self):
        t = np.zeros(self.n_unknowns)
        t[-1] = 1.0
        return t

    def start_point(self, frequency: float) -> np.ndarray:
        orbit = friction_shooting_orbit(self.model, self.force, frequency, self.steps)
        return self.pack(orbit.state, 2 * np.pi * frequency)

    def linear_response_point(self, frequency: float) -> np.ndarray:
        return self.start_point(frequency)

    def _residual(self, u):
        """(z(T) − z)/scale; in full stick the node's position is history (a null direction):
        its row is replaced by the mean support force (the symmetric position, as MMS-HBM)."""
        z, omega = self.unpack(u)
        sh = self._shooting(omega)
        end, (_, _, G) = sh.march(z, record=True)
        R = (end - z) / self.colscale[:-1]
        if np.all(np.abs(G) < sh.s):
            R[-1] = np.mean(G[1:]) / (sh.k * self.colscale[-2])
        return R


    def _evaluate(self, u, jacobian: bool):
        R = self._residual(u)
        if not jacobian:
            return R
        J = np.empty((len(R), self.n_unknowns))
        for j in range(self.n_unknowns):
            h = 1e-7 * max(1.0, abs(u[j]))
            e = np.array(u, dtype=float)
            e[j] += h
            J[:, j] = (self._residual(e) - R) / h
        self._residual(u)  # Ω of u back in the cache
        return R, J

    def monitor(self, u) -> dict:
        """frequency (Hz), amplitude (m, largest sampled |q| of the amplitude DOF), phase and
        energy (nan), contact_force_max (0), slip_fraction, friction_dissipation (J per period,
        Σ f Δu with f = −g, trapezoidal)."""
        z, omega = self.unpack(u)
        _, (Q, U, G) = self._shooting(omega).march(z, record=True)
        f = -G
        work = float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(U)))
        s = self._shooting(omega).s
        return {"frequency": omega / (2 * np.pi), "amplitude": float(np.abs(Q[self._track]).max()),
                "phase": np.nan, "energy": np.nan, "contact_force_max": 0.0,
                "slip_fraction": float(np.mean(np.abs(G[1:]) >= s * (1 - 1e-12))) if s > 0 else 1.0,
                "friction_dissipation": work}
