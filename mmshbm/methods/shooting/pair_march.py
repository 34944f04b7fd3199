"""Many friction contacts on massless DOFs: forced orbits by marching to steady state in
physical coordinates (no Newton, no harmonics), the ground truth of the harmonic balance's
interface damping.

The model: DOFs with mass q (mass M, damping C, any viscous damping), massless DOFs s
coupled to them by the stiffness (K_lc, K_cc), Coulomb friction of constant normal load
N_i on massless DOFs (slip force c_i = μ_i N_i; massless DOFs without friction are free,
c_i = 0), a harmonic force on the DOFs with mass:

    M q'' + C q' + K_ll q + K_lc s = F(t),      K_cl q + K_cc s + p = 0,
    |p_i| <= c_i,   p_i = c_i sign(s_i')  where s_i' ≠ 0,

p_i the force massless DOF i needs from its support. This is the bonded lap joint's
interface (:func:`mmshbm.lap_joint`, two tangential friction DOFs per pair with the
pair's share of the bolt's preload). The generalised-α scheme on q (second order; ρ∞ = 1
is the trapezoidal rule, whose discrete energy balance below is exact, ρ∞ < 1 damps the
unresolved stiff modes of the interface, which the stick–slip switches excite); at each
step the massless DOFs are in static equilibrium with the law implicit in the step's
increment (rate independent, so exact for the step's linear motion): with q eliminated, one
convex l1-regularised quadratic programme in the increments (:mod:`._pair_march_kernels`).
No harmonic truncation, no proximal parameter, no regularisation: an implementation
independent of the harmonic balance's friction rows.

Energy per period (J, trapezoidal; exact for ρ∞ = 1, to the scheme's order otherwise): the force's work W_in =
Σ ½(F_n + F_{n+1})·Δq equals the viscous work Σ h v̄ᵀ C v̄ plus the friction work
W_f = Σ_i Σ_n ½(p_n + p_{n+1}) Δs plus the change of the stored energy (zero on a periodic
orbit).

Steady state: the force is ramped up over ``ramp_periods`` (½(1 − cos π t/T_r): no
impulsive start, so that a node that sticks through the steady orbit keeps the zero mean
force it had at rest, the symmetric position the harmonic balance takes for it), then held
while whole periods are marched until the state (q, q'/Ω, s) repeats after one period to
``tol`` of its largest entry.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as la

from ... import _validate as check
from ..mms.forced import Excitation, harmonic_force
from ._pair_march_kernels import _march

__all__ = ["FrictionPairMarch", "PairOrbit", "march_pairs_to_steady"]


def _dense(a) -> np.ndarray:
    return a.toarray() if hasattr(a, "toarray") else np.asarray(a, dtype=float)


class FrictionPairMarch:
    """Newmark steps of a model whose massless DOFs carry Coulomb friction of constant
    normal load (module docstring).

    Parameters
    ----------
    model : Model
        Friction contacts with ``normal_load`` on massless DOFs, no unilateral contacts.
    force : array_like (n_dof,) or Excitation
        On the DOFs with mass (N).
    frequency : float
        Hz.
    steps_per_period : int
        >= 8.
    rho_inf : float
        The generalised-α scheme's spectral radius at h ω → ∞ (Chung & Hulbert), in [0, 1]:
        1 is the trapezoidal rule (no numerical damping, unresolved stiff modes ring for
        ever once a stick–slip switch excites them); below 1 those are damped by ρ∞ per step
        while the resolved modes keep second order accuracy (the algorithmic damping ratio
        grows as (ω h)³).
    max_iter, max_sweeps : int
        Passes of the active set and sweeps of the coordinate descent per step.

    Raises
    ------
    NotImplementedError
        Unilateral contacts, or friction pressed by a contact (``normal_contact``).
    """

    def __init__(self, model, force, frequency: float, steps_per_period: int = 512, *, rho_inf: float = 0.6,
                 max_iter: int = 200, max_sweeps: int = 100000):
        if model.contacts or any(fc.normal_contact is not None for fc in model.friction):
            raise NotImplementedError("the pair march takes friction of constant normal load (normal_load=) "
                                      "on massless DOFs and no unilateral contacts")
        if not model.friction:
            raise ValueError("the model has no friction contacts")
        exc = force if isinstance(force, Excitation) else harmonic_force(model, force)
        self.omega = 2 * np.pi * check.positive("frequency", frequency)
        self.steps = check.integer("steps_per_period", steps_per_period, minimum=8)
        self.h = h = 2 * np.pi / self.omega / self.steps
        self.max_iter = check.integer("max_iter", max_iter, minimum=1)
        self.max_sweeps = check.integer("max_sweeps", max_sweeps, minimum=1)
        b = model.blocks
        M, K_ll = _dense(b["M_ll"]), _dense(b["K_ll"])
        C = _dense(b["C_ll"]) if b["C_ll"] is not None else np.zeros_like(M)
        K_lc, K_cc = _dense(b["K_lc"]), _dense(b["K_cc"])
        rho = float(rho_inf)
        if not 0.0 <= rho <= 1.0:
            raise ValueError(f"rho_inf must be in [0, 1], got {rho_inf}")
        am, af = (2 * rho - 1) / (rho + 1), rho / (rho + 1)
        self.alpha_m, self.alpha_f = am, af
        self.gamma, self.beta = 0.5 - am + af, 0.25 * (1 - am + af) ** 2
        Keff = (1 - am) / ((1 - af) * self.beta * h**2) * M + self.gamma / (self.beta * h) * C + K_ll
        Kinv = la.inv(0.5 * (Keff + Keff.T))
        G = Kinv @ K_lc
        S = K_cc - K_lc.T @ G
        self.M, self.C, self.K_ll, self.K_lc, self.K_cc = M, C, K_ll, K_lc, K_cc
        self.Kinv, self.G = np.ascontiguousarray(Kinv), np.ascontiguousarray(G)
        self.KclKinv = np.ascontiguousarray(K_lc.T @ Kinv)
        self.S = np.ascontiguousarray(0.5 * (S + S.T))
        c_index = {int(d): i for i, d in enumerate(model.c)}
        self.slip = np.zeros(len(model.c))
        for fc in model.friction:
            self.slip[c_index[fc.dof]] = fc.mu * fc.normal_load
        sig, _ = exc.scale(self.omega)
        F = sig * np.asarray(exc.vector, dtype=complex)[model.l]
        self.Fc, self.Fs = np.ascontiguousarray(F.real), np.ascontiguousarray(-F.imag)
        self.n_l, self.n_c = len(model.l), len(model.c)
        self.model = model

    def rest(self):
        """The state at rest: (q, v, a, s, p, state) zeros."""
        n, m = self.n_l, self.n_c
        return (np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(m), np.zeros(m), np.zeros(m, dtype=np.int64))

    def advance(self, state, t0: float, steps: int, ramp: float = 0.0, record: bool = False):
        """``steps`` steps from time ``t0`` (s) on ``state`` (:meth:`rest`, in place):
        (work (W_in, W_visc, W_fric) in J, records (q (steps+1, n_l), s, p (steps+1, n_c))
        or None).

        Raises
        ------
        RuntimeError
            A step whose law neither solver settled.
        """
        q, v, a, s, p, st = state
        k = steps + 1 if record else 0
        rq, rs, rp = np.empty((k, self.n_l)), np.empty((k, self.n_c)), np.empty((k, self.n_c))
        work = _march(q, v, a, s, p, st, self.M, self.C, self.K_ll, self.K_lc, self.Kinv, self.G,
                      self.KclKinv, self.S, self.Fc, self.Fs, self.slip, self.omega, self.h, float(t0),
                      int(steps), float(ramp), self.alpha_m, self.alpha_f, self.beta, self.gamma,
                      self.max_iter, self.max_sweeps, rq, rs, rp)
        if not np.isfinite(work[0]):
            raise RuntimeError("a step's friction law was not solved: neither the active set nor the "
                               "coordinate descent settled")
        return work, ((rq, rs, rp) if record else None)

    def initial_acceleration(self, state, t: float = 0.0, factor: float = 1.0) -> None:
        """a = M⁻¹ (F(t) − C v − K_ll q − K_lc s) on ``state`` in place."""
        q, v, a, s = state[:4]
        F = factor * (self.Fc * np.cos(self.omega * t) + self.Fs * np.sin(self.omega * t))
        a[:] = la.solve(self.M, F - self.C @ v - self.K_ll @ q - self.K_lc @ s)


class PairOrbit:
    """The recorded period of :func:`march_pairs_to_steady`.

    Attributes
    ----------
    converged : bool
        Whether the state repeated after one period to ``tol``.
    periods : int
        Periods marched (ramp included) before the record.
    change : ndarray (periods - ramp_periods,)
        Relative change of the state over each period after the ramp.
    q : ndarray (steps+1, n_l); s, p : ndarray (steps+1, n_c)
        The recorded period's samples (m; m; N).
    work_input, work_viscous, work_friction : float
        J over the recorded period (module docstring).
    period : float
        s.
    """

    def __init__(self, converged, periods, change, rec, work, period):
        self.converged, self.periods = bool(converged), int(periods)
        self.change = np.asarray(change, dtype=float)
        self.q, self.s, self.p = rec
        self.work_input, self.work_viscous, self.work_friction = (float(w) for w in work)
        self.period = float(period)

    def amplitude(self, dof: int = 0) -> float:
        """Largest |q| (m) of DOF ``dof`` (an index among the DOFs with mass) over the
        samples, refined by the parabola through the largest sample and its neighbours."""
        y = np.abs(self.q[:-1, dof])
        k = int(np.argmax(y))
        y0, y1, y2 = y[k - 1], y[k], y[(k + 1) % len(y)]
        den = y0 - 2 * y1 + y2
        return float(y1 - 0.125 * (y2 - y0) ** 2 / den) if den < 0 else float(y1)

    def harmonic(self, dof: int = 0, k: int = 1) -> complex:
        """Complex amplitude of harmonic k of DOF ``dof``: q ≈ Re(c e^{ikΩt}) (m)."""
        y = self.q[:-1, dof]
        return complex(2.0 / len(y) * np.fft.rfft(y)[k])


def march_pairs_to_steady(model, force, frequency: float, steps_per_period: int = 512, *,
                          ramp_periods: int = 20, max_periods: int = 4000, tol: float = 1e-9,
                          marcher: FrictionPairMarch | None = None) -> PairOrbit:
    """March from rest, the force ramped over ``ramp_periods``, until the state (q, q'/Ω, s)
    repeats after one period to ``tol`` (relative to its largest entry) or ``max_periods``;
    then one period recorded (:class:`PairOrbit`).

    Parameters
    ----------
    model, force, frequency, steps_per_period
        As :class:`FrictionPairMarch` (or pass ``marcher``).
    """
    mr = marcher or FrictionPairMarch(model, force, frequency, steps_per_period)
    ramp_periods = check.integer("ramp_periods", ramp_periods, minimum=0)
    max_periods = check.integer("max_periods", max_periods, minimum=ramp_periods + 1)
    T, steps = 2 * np.pi / mr.omega, mr.steps
    state = mr.rest()
    mr.initial_acceleration(state, 0.0, 0.0 if ramp_periods else 1.0)
    ramp = ramp_periods * T
    sc = 1.0 / mr.omega

    def snapshot():
        return np.concatenate([state[0], sc * state[1], state[3]])

    past = snapshot()
    change, converged, p = [], False, 0
    for p in range(max_periods):
        mr.advance(state, p * T, steps, ramp)
        now = snapshot()
        if p + 1 > ramp_periods:
            change.append(np.abs(now - past).max() / max(np.abs(now).max(), 1e-300))
            if change[-1] <= tol:
                converged = True
                break
        past = now
    work, rec = mr.advance(state, (p + 1) * T, steps, ramp, record=True)
    return PairOrbit(converged, p + 1, change, rec, work, T)
