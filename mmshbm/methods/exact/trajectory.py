"""Event-driven integration of the exact reference: switches located in closed form,
transition matrices through them (saltation = identity)."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from ... import _validate as check
from .phase import _CHUNK, _CHUNK_FIRST, _GRAZE_REL, _KEEP_REL, _RTOL, Phase
from .system import PiecewiseLinearSystem

__all__ = ["Event", "Trajectory", "integrate"]

logger = logging.getLogger(__name__)


def _first_switch(phase: Phase, j: int, alpha: np.ndarray, beta: np.ndarray, t_max: float,
                  samples_per_period: int, t_ref: float):
    """First time in (0, t_max] at which the phase's switching function ``j`` crosses to <= 0.

    Returns
    -------
    t_switch : float or None
        Local time of the switch, or None if the phase lasts beyond ``t_max``.
    grazes : list of (float, float)
        (local time, value of u) of grazing minima passed without switching.
    """
    c = phase.switch_modal[j]
    amp = np.abs(c) * np.hypot(alpha, beta)
    u_s = phase.switch_static[j]
    scale = phase.switch_scale(alpha, beta, j)
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
    contact : int
        Which contact (index into ``model.contacts``).
    """

    time: float
    kind: str
    contact: int = 0


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
    def active_sets(self) -> list[tuple[tuple, float, float]]:
        """(closed contacts, start time, end time) of each phase, in order."""
        return [(s.phase.active, s.t_start, s.t_end) for s in self._segments]

    @property
    def n_contacts(self) -> int:
        """Number of contact phases: with one contact the closed phases; with several the
        closings of any contact plus the contacts closed at t = 0."""
        if self.system.n_contacts == 1:
            return sum(s.phase.name == "closed" for s in self._segments)
        return sum(e.kind == "close" for e in self.events) + len(self._segments[0].phase.active)

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
            Contact force (N); with several contacts one row per contact,
            shape (n_contacts, n_t) (or (n_contacts,)).
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
        """Contact force λ (N) at times ``t``, shape (n_t,) ((n_contacts, n_t) with several
        contacts)."""
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
    t = 0.0
    segments, events = [], []
    Tr = np.eye(2 * system.n_l) if sensitivity else None
    n_zero = 0
    while True:
        alpha, beta = phase.modal_state(q, v)
        # the first of the phase's switching functions to reach zero (each searched only
        # up to the earliest switch found so far)
        t_sw, j_sw, grazes = None, None, []
        for j in range(phase.n_switch):
            t_j, g_j = _first_switch(phase, j, alpha, beta, (t_end - t) if t_sw is None else t_sw,
                                     samples_per_period, t_ref)
            grazes.extend((tg, j) for tg, _ in g_j)
            if t_j is not None and (t_sw is None or t_j < t_sw):
                t_sw, j_sw = t_j, j
        grazes.sort()
        events.extend(Event(t + tg, "graze", j) for tg, j in grazes if t_sw is None or tg < t_sw)
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
        if n_zero > 4 * system.n_contacts:
            raise RuntimeError(f"event location stalled at t = {t!r} s (repeated zero-length phases)")
        t = t_next
        events.append(Event(t, "open" if j_sw in phase.active else "close", j_sw))
        if len(events) > max_events:
            raise ValueError(f"more than max_events = {max_events} switches before t_end = {t_end!r} s")
        phase = system.next_phase(phase, j_sw)
    return Trajectory(system, segments, events, Tr)
