"""Symmetric periodic orbits of the exact reference by Newton shooting, and backbones of them."""

from __future__ import annotations

import dataclasses
import logging
import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from ... import _validate as check
from .system import PiecewiseLinearSystem
from .trajectory import Trajectory, integrate

__all__ = ["PeriodicOrbit", "Backbone", "periodic_orbit", "backbone"]

logger = logging.getLogger(__name__)


# ============================================================================ periodic orbits
@dataclass(frozen=True, eq=False)
class PeriodicOrbit:
    """A symmetric periodic orbit (all velocities zero at t = 0 and t = T/2).

    Attributes
    ----------
    amplitude : float
        Prescribed amplitude (m): ``-stop_side * q[contact_dof](0)`` with one contact;
        with several, the amplitude DOF's value at t = 0 signed by
        ``PiecewiseLinearSystem.amplitude_row``.
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
        Measured max over the period of ``-stop_side * q[contact_dof]`` (m); with several
        contacts of ``|q[amplitude_dof]|`` (or ``-side * q`` when the amplitude DOF carries
        the only contact).
    max_contact_force : float
        Largest λ over the period and the contacts (N), sampled.
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

    def fundamental_share(self, n_samples: int = 2048) -> float:
        """Share (0..1) of the period-mean kinetic energy in the fundamental harmonic: the
        family measure of the harmonic-balance branches (docs/resonances.md), here of the
        exact motion (harmonics up to ``n_samples``/2 of the velocities of the DOFs with
        mass, sampled from the closed-form phases). Below one half the orbit's energy has
        moved into higher harmonics: an internal resonance's orbit, not the mode's."""
        n_samples = check.integer("n_samples", n_samples, minimum=8)
        t = np.arange(n_samples) * (self.period / n_samples)
        _, v = self.trajectory.state_l(t)
        V = np.fft.rfft(v, axis=1)
        T = np.einsum("ik,ij,jk->k", V.conj(), self.trajectory.system.M_ll, V).real
        total = float(T[1:].sum())
        return float(T[1] / total) if total > 0 else 1.0

    def __repr__(self) -> str:
        return (f"PeriodicOrbit(amplitude={self.amplitude:.6g} m, frequency={self.frequency:.12g} Hz, "
                f"n_contacts={self.n_contacts}, converged={self.converged}, iterations={self.iterations})")


def _guess(system: PiecewiseLinearSystem, amplitude: float) -> tuple[np.ndarray, float]:
    """The first open mode scaled to the amplitude, and a half period: with one contact
    that of the one-DOF analogue (docs/design.md §5) with ω1, ω2 the first open
    and closed frequencies; with several, the first return of the mode's modal velocity
    to zero along the exact motion from that start (π/ω1 if no contact closes before)."""
    if system.n_contacts > 1:
        return _guess_several(system, amplitude)
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


def _guess_several(system: PiecewiseLinearSystem, amplitude: float) -> tuple[np.ndarray, float]:
    from ...contact.table import start_mode

    _, phi = start_mode(system.model, 1)
    phi = phi[system.model.l]
    x = amplitude * phi / (system.amplitude_row @ phi)
    w1 = system.open.omega[0]
    half = np.pi / w1
    traj = integrate(system, x, np.zeros_like(x), 1.25 * half)
    if not len(traj.switch_times):
        return x, half
    weight = system.M_ll @ phi
    ts = np.linspace(0.0, 1.25 * half, 401)[1:]
    eta_dot = weight @ traj.state_l(ts)[1]
    change = np.flatnonzero(np.sign(eta_dot[1:]) != np.sign(eta_dot[0]))
    if not len(change):
        return x, half
    k = int(change[0])
    return x, float(brentq(lambda t: float(weight @ traj.state_l(t)[1]), ts[k], ts[k + 1]))


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
        the stop at the turning point t = 0 (see the module docstring). With several
        contacts: ``model.amplitude_dof``'s value at t = 0, the turning point where the
        first contact is farthest from its stop (``PiecewiseLinearSystem.amplitude_row``).
    guess : PeriodicOrbit or (x, half_period), optional
        Starting point; x of shape (n_l,) is rescaled to the amplitude. Default: the first
        linear (open) mode and the one-DOF analogue's half period (several contacts: the
        first return of that mode's velocity to zero along the exact motion).
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
    v, dv_dx, dv_dtau, traj = _shoot(system, x, tau, samples_per_period)
    if system.n_contacts > 1:
        # with several contacts the half period strings more phases together, each restart
        # adding its own round-off; the phases built meanwhile may raise the bound too
        floor = system._velocity_roundoff * float(np.abs(x).max()) / (w1 * A) * len(traj.phases)
    F = np.append(v / (w1 * A), r @ x / A - 1.0)
    res = float(np.abs(F).max())
    converged, it = res <= 1e-16, 0
    while not converged and it < max_iter:
        it += 1
        try:
            dz = -np.linalg.solve(_scaled_jacobian(dv_dx, dv_dtau, r, w1, A), F)
        except np.linalg.LinAlgError:
            logger.info("singular shooting Jacobian at amplitude %g", A)
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
    # v(0) = 0 and v(T/2) = 0 hold trivially as T/2 → 0: Newton can slide to that spurious
    # root. A motion whose velocities vanish at t = 0 turns back no sooner than half a
    # period of its fastest phase, so a shorter half period is no orbit
    fastest = max(float(ph.omega.max()) for ph in system._phases.values())
    converged = converged and tau >= 0.5 * math.pi / fastest
    return _orbit_result(system, A, x, tau, converged, it, res, samples_per_period)


def _orbit_result(system, A, x, tau, converged, iterations, res, samples_per_period) -> PeriodicOrbit:
    half = integrate(system, x, np.zeros_like(x), tau, samples_per_period=samples_per_period)
    kinds = [e.kind for e in half.events]
    n_close = kinds.count("close")
    if system.n_contacts == 1:
        closed_at_half = half.phases[-1][0] == "closed"
        n_contacts = 2 * n_close - (1 if closed_at_half else 0)
    else:
        # contact phases within a half appear twice per period, one spanning T/2 once; a
        # phase spanning t = 0 closes in the second half (the mirror of its opening)
        n_contacts = 2 * n_close - len(half.active_sets[-1][0]) + len(half.active_sets[0][0])
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
    if system.n_contacts == 1:
        exc = -m.stop_side * q_half[m.contact_dof]
    else:
        exc = system.amplitude_of(q_half)
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
    ``n_contacts``; a point that failed is logged at INFO level too (nothing reaches stderr:
    the result's ``converged`` says it).

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
            logger.info("no converged orbit at amplitude %.6g m (residual %.3e)", target, orbit.residual)
        orbits.append(orbit)

    def arr(name, dtype=float):
        return np.array([getattr(o, name) for o in orbits], dtype=dtype)

    stable = np.array([bool(np.all(np.abs(np.abs(o.multipliers) - 1) < 1e-6)) for o in orbits])
    return Backbone(amplitude=arr("amplitude"), period=arr("period"), frequency=arr("frequency"),
                    energy=arr("energy"), n_contacts=arr("n_contacts", int),
                    converged=arr("converged", bool), x=np.array([o.x for o in orbits]),
                    max_excursion=arr("max_excursion"), stable=stable, orbits=orbits)
