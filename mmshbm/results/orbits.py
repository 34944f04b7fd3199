"""Every orbit of the starting mode's family that a branch knows at one amplitude.

Past an internal resonance several periodic orbits of the same amplitude can hold the
fundamental harmonic's majority of the kinetic energy: the backbone's (what
:meth:`~mmshbm.Branch.frequency_at` returns) and others, on the tongues and loops the
branch went through (:mod:`mmshbm.results.coexisting` names those amplitude intervals)
or on pieces of the family the continuation never visited. :func:`orbits_at` lists them:

1. **backbone**: the branch's own point at the amplitude (:meth:`~mmshbm.Branch.solve_at`,
   the orbit ``frequency_at`` reports), whatever its share;
2. **branch**: every other segment of the computed path that crosses the amplitude
   (two consecutive points not separated by a jump), solved there exactly with the
   amplitude pinned (:func:`mmshbm.core.pinned.solve_at_amplitude`, the Newton that
   ``frequency_at`` uses);
3. **search** (``search=True``): Newton at the pinned amplitude from a small fixed set of
   starts (:func:`search_starts`: each orbit of 1–2 with its frequency moved by the
   factors :data:`SEARCH_FREQUENCY_FACTORS`, the linear first mode scaled to the
   amplitude at its own frequency and at the closed-contact first mode's), on the
   *deflated* residual (:class:`Deflated`): the residual times
   ``Π_k (1/‖u − u_k‖^p + σ)`` over the orbits already found (and their copies shifted by
   half a period), so that Newton cannot converge to a known orbit again and is pushed
   toward another one (deflation, P. E. Farrell et al., SIAM J. Sci. Comput. 37, 2015).

An orbit of 2 or 3 counts as the family's when its fundamental holds at least
:data:`FAMILY_SHARE` of the kinetic energy (the solver's ``fundamental_share``); two
orbits are the same when their frequencies agree within :data:`SAME_ORBIT_RTOL` and their
shares within the same tolerance (both are unchanged by a shift of the time origin, so a
copy of an orbit shifted by half a period is the same orbit).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..core.problem import ContinuationProblemBase, as_problem

__all__ = ["DEFLATION_POWER", "DEFLATION_SHIFT", "FAMILY_SHARE", "SAME_ORBIT_RTOL",
           "SEARCH_FREQUENCY_FACTORS", "SEARCH_MAX_ITER", "SEARCH_WINDOW", "Deflated", "Orbit", "OrbitsAt",
           "orbits_at", "search_starts"]

#: an orbit is the starting mode's family's when its fundamental harmonic holds at least
#: this share of the kinetic energy (docs/orbits.md)
FAMILY_SHARE = 0.5
#: two solved orbits are one when their frequencies, and their fundamental shares, agree
#: within this (relative; the pinned solves converge to 1e-10)
SAME_ORBIT_RTOL = 1e-7
#: the search's starts from each known orbit: its state with the frequency times these
SEARCH_FREQUENCY_FACTORS = (0.95, 1.03, 1.08)
#: the deflation's power p and shift σ: M(u) = Π_k (1/‖u − u_k‖^p + σ)
DEFLATION_POWER = 2.0
DEFLATION_SHIFT = 1.0
#: Newton iterations of one search start
SEARCH_MAX_ITER = 30
#: the search's iterates stay between the linear frequency / this and the closed-contact
#: frequency × this (beyond, a harmonic may pass the modes a condensation kept)
SEARCH_WINDOW = 2.0
#: sources of an orbit, in the order :func:`orbits_at` lists them
SOURCES = ("backbone", "branch", "search")


@dataclass(frozen=True, eq=False)
class Orbit:
    """One periodic orbit at a pinned amplitude.

    Attributes
    ----------
    amplitude : float
        Its amplitude (m): the branch's amplitude measure (largest excursion of the
        amplitude DOF away from the stop).
    frequency : float
        Its frequency (Hz).
    fundamental_share : float
        The fundamental harmonic's share of the kinetic energy (0..1; NaN where the solver
        does not record it, e.g. penalty-HBM: such an orbit is listed only as the backbone's).
    state : ndarray, shape (n_unknowns,)
        The solver's scaled unknowns (the layout of ``Branch.states``; read-only).
    source : str
        "backbone" (the orbit ``frequency_at`` returns), "branch" (another segment of the
        computed path crossing the amplitude) or "search" (found by the deflated search).
    origin : str
        Where it came from in words: the path segment's point indices, or the search start.
    """

    amplitude: float
    frequency: float
    fundamental_share: float
    state: np.ndarray = field(repr=False)
    source: str
    origin: str = ""

    def __post_init__(self):
        state = np.array(self.state, dtype=float)
        state.flags.writeable = False
        object.__setattr__(self, "state", state)

    def same_as(self, other: Orbit, rtol: float = SAME_ORBIT_RTOL) -> bool:
        """Whether ``other`` is this orbit: frequencies and fundamental shares within ``rtol``."""
        if not abs(self.frequency - other.frequency) <= rtol * abs(self.frequency):
            return False
        shares = (self.fundamental_share, other.fundamental_share)
        return not all(math.isfinite(x) for x in shares) or abs(shares[0] - shares[1]) <= max(rtol, 1e-12)


@dataclass(frozen=True)
class OrbitsAt:
    """The family's orbits at one amplitude, the backbone's first (a sequence of
    :class:`Orbit`; empty with a ``reason`` where the branch has none there).

    Attributes
    ----------
    amplitude : float
        The amplitude (m).
    orbits : tuple of Orbit
        The backbone's orbit (when the branch has one there), then the other orbits of the
        branch, then those of the search, each in increasing frequency.
    reason : str
        Why there are none (empty otherwise).
    searched : int
        Search starts tried (0 without ``search``).
    rejected : tuple of float
        Frequencies (Hz) of the distinct orbits found off the family (fundamental share
        below :data:`FAMILY_SHARE`), not listed.
    """

    amplitude: float
    orbits: tuple = ()
    reason: str = ""
    searched: int = 0
    rejected: tuple = ()

    def __len__(self) -> int:
        return len(self.orbits)

    def __iter__(self):
        return iter(self.orbits)

    def __getitem__(self, i):
        return self.orbits[i]

    @property
    def frequencies(self) -> np.ndarray:
        """The orbits' frequencies (Hz), in list order."""
        return np.array([o.frequency for o in self.orbits], dtype=float)


class Deflated(ContinuationProblemBase):
    """The residual of ``problem`` deflated at the states ``known``: R_d(u) = M(u) R(u) with
    M(u) = Π_k (‖u − u_k‖^−p + σ) (module docstring). M ≥ σ^K, so ‖R‖ ≤ ‖R_d‖ / σ^K: a
    deflated solve that converges has converged on R too; toward a known (regular) root
    ‖R_d‖ does not tend to zero for p ≥ 1 (R shrinks like ‖u − u_k‖, the factor grows
    like ‖u − u_k‖^−p). The amplitude and the monitor are the problem's."""

    def __init__(self, problem, known, power: float = DEFLATION_POWER, shift: float = DEFLATION_SHIFT):
        self.problem = as_problem(problem)
        self.known = [np.asarray(k, dtype=float) for k in known]
        self.power, self.shift = float(power), float(shift)
        self.n_unknowns = self.problem.n_unknowns
        self.amplitude_and_gradient = self.problem.amplitude_and_gradient
        self.amplitude_value = self.problem.amplitude_value

    def factor(self, u: np.ndarray) -> tuple[float, np.ndarray]:
        """(M(u), ∇M(u))."""
        m, grad_log = 1.0, np.zeros(len(u))
        for k in self.known:
            d = u - k
            r2 = max(float(d @ d), 1e-300)
            term = r2 ** (-self.power / 2) + self.shift
            m *= term
            grad_log += (-self.power * r2 ** (-self.power / 2 - 1) / term) * d
        return m, m * grad_log

    def residual(self, u: np.ndarray) -> np.ndarray:
        return self.factor(u)[0] * np.asarray(self.problem.residual(u))

    def residual_and_jacobian(self, u: np.ndarray):
        R, J = self.problem.residual_and_jacobian(u)
        J = J.toarray() if hasattr(J, "toarray") else np.asarray(J)
        m, g = self.factor(u)
        return m * R, m * J + np.outer(R, g)

    def monitor(self, u: np.ndarray) -> dict:
        return self.problem.monitor(u)


def _pinned(problem, u0, amplitude: float, tol: float, max_iter: int, admissible=None):
    """The pinned solve's state, or None where it fails."""
    from ..core.pinned import PinnedFailure, solve_at_amplitude

    try:
        u, _, _, _ = solve_at_amplitude(problem, u0, amplitude, tol=tol, max_iter=max_iter,
                                        admissible=admissible)
        return u
    except (PinnedFailure, ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError):
        return None


def _orbit(solver, u, amplitude: float, source: str, origin: str) -> Orbit | None:
    """The orbit of the solved state ``u`` (None where its monitor fails, or its amplitude
    is not ``amplitude``)."""
    try:
        rec = solver.monitor(u)
    except (ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError):
        return None
    share = rec.get("fundamental_share", rec.get("mode_share", math.nan))
    f, a = float(rec["frequency"]), float(rec["amplitude"])
    if not (math.isfinite(f) and f > 0 and abs(a / amplitude - 1) <= 1e-6):
        return None
    return Orbit(amplitude, f, float(share), u, source, origin)


def _half_period_shift(solver, u: np.ndarray) -> np.ndarray | None:
    """``u`` with the time origin moved by half a period (cosine coefficient k times
    (−1)^k), for a harmonic balance solver whose ``unpack`` gives one row per harmonic
    0..H; None otherwise."""
    if not (hasattr(solver, "unpack") and hasattr(solver, "pack")):
        return None
    a, omega = solver.unpack(u)
    if np.ndim(a) != 2 or a.shape[0] != int(getattr(solver, "H", -1)) + 1:
        return None
    sign = (-1.0) ** np.arange(a.shape[0])
    return np.asarray(solver.pack(a * sign[:, None], omega), dtype=float)


def _with_frequency(solver, u: np.ndarray, frequency: float) -> np.ndarray:
    """``u`` with its frequency set to ``frequency`` (Hz), the coefficients kept."""
    a, _ = solver.unpack(u)
    return np.asarray(solver.pack(a, 2 * np.pi * frequency), dtype=float)


def _closed_frequency(solver) -> float:
    """The first mode's frequency (Hz) with every contact DOF held at its stop (NaN where
    the solver does not say which DOFs those are)."""
    from .base import entry_point

    dofs, model = getattr(solver, "contact_dofs", None), getattr(solver, "model", None)
    if dofs is None or model is None:
        return math.nan
    try:
        return float(entry_point("held_frequency")(model, dofs, int(getattr(solver, "mode", 1))))
    except (ValueError, ArithmeticError, np.linalg.LinAlgError, RuntimeError):
        return math.nan


def search_starts(solver, known: list[Orbit], amplitude: float) -> list[tuple[str, np.ndarray]]:
    """The search's fixed set of starts at ``amplitude`` (m), as (description, state):
    each of ``known`` with its frequency times each of :data:`SEARCH_FREQUENCY_FACTORS`;
    the linear first mode scaled to the amplitude at its own frequency and at the
    closed-contact first mode's (every contact DOF held at its stop)."""
    out = []
    for o in known:
        for factor in SEARCH_FREQUENCY_FACTORS:
            out.append((f"{o.source} orbit {o.frequency:.6g} Hz × {factor:g}",
                        _with_frequency(solver, o.state, o.frequency * factor)))
    linear = np.asarray(solver.linear_mode_point(amplitude), dtype=float)
    out.append(("linear first mode", linear))
    f_closed = _closed_frequency(solver)
    if math.isfinite(f_closed) and f_closed > 0:
        out.append((f"linear first mode at the closed-contact frequency {f_closed:.6g} Hz",
                    _with_frequency(solver, linear, f_closed)))
    return out


def _window(solver, amplitude: float):
    """The search's trust region: frequency (from the state, no evaluation) within
    [f_linear / SEARCH_WINDOW, f_closed × SEARCH_WINDOW]."""
    _, omega = solver.unpack(np.asarray(solver.linear_mode_point(amplitude), dtype=float))
    lo = omega / (2 * np.pi) / SEARCH_WINDOW
    f_closed = _closed_frequency(solver)
    hi = (f_closed if math.isfinite(f_closed) else omega / (2 * np.pi)) * SEARCH_WINDOW
    last = 2 * np.pi / float(solver.colscale[-1]) if hasattr(solver, "colscale") else None

    def admissible(u) -> bool:
        f = u[-1] / last if last else solver.unpack(u)[1] / (2 * np.pi)
        return bool(lo <= f <= hi)

    return admissible


def _crossings(branch, amplitude: float) -> list[tuple[int, int]]:
    """Consecutive point pairs (i, i + 1) of the path whose amplitudes bracket
    ``amplitude`` (m), not separated by a jump; a stored point at that amplitude is its
    own pair (i, i)."""
    A = np.asarray(branch.amplitude, dtype=float)
    jumps = {int(s[1]) for s in branch.special_points if s[0] == "jump"}
    out = [(int(i), int(i)) for i in np.flatnonzero(np.isclose(A, amplitude, rtol=1e-9, atol=0))]
    for i in range(len(A) - 1):
        if i + 1 in jumps or A[i] == A[i + 1]:
            continue
        if min(A[i], A[i + 1]) < amplitude < max(A[i], A[i + 1]):
            out.append((i, i + 1))
    return out


def _outside(branch, amplitude: float) -> str:
    """Why ``branch`` has no orbit at ``amplitude`` (m) when the amplitude lies outside
    the range its points cover; empty when inside."""
    A = np.asarray(branch.amplitude, dtype=float)
    if not len(A):
        return "the branch has no points"
    lo, hi = float(np.nanmin(A)), float(np.nanmax(A))
    if lo * (1 - 1e-9) <= amplitude <= hi * (1 + 1e-9):
        return ""
    gap = branch.gap
    span = f"{lo:.4g}..{hi:.4g} m" + (f" ({lo / gap:.4g}..{hi / gap:.4g} gaps)" if gap and gap > 0 else "")
    return f"{amplitude:.4g} m lies outside the amplitudes the branch covers, {span}"


def _searchable(branch, solver, amplitude: float) -> bool:
    """Whether the search can run on ``solver``: harmonic balance with ``unpack``/``pack``
    and a linear start, whose monitor records ``fundamental_share`` (the family rule)."""
    from .._method_info import is_harmonic_balance

    if not (is_harmonic_balance(branch.method) and int(branch.harmonics) >= 1
            and all(hasattr(solver, n) for n in ("unpack", "pack", "linear_mode_point"))):
        return False
    try:
        start = np.asarray(solver.linear_mode_point(amplitude), dtype=float)
        return "fundamental_share" in solver.monitor(start)
    except (ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError):
        return False


def orbits_at(branch, amplitude: float, *, search: bool = False, tol: float = 1e-10) -> OrbitsAt:
    """The starting mode's family's orbits at ``amplitude`` (m) that ``branch`` knows, and
    with ``search`` also those a deflated Newton search finds there (module docstring).

    Parameters
    ----------
    branch : Branch
        A backbone with a solver (attached or rebuildable).
    amplitude : float
        The amplitude (m), > 0.
    search : bool
        Also search for orbits the branch did not visit (harmonic balance solvers that
        record the fundamental's share: MMS-HBM).
    tol : float
        Newton tolerance of every solve.

    Returns
    -------
    OrbitsAt
        Empty, with its ``reason``, where the amplitude lies outside the amplitudes the
        branch's points cover (a BranchWarning says it too).

    Raises
    ------
    ValueError
        For an amplitude that is not a positive number, or ``search`` with a solver that
        does not expose its harmonics.
    """
    from .._warnings import BranchWarning

    a = float(amplitude)
    if not (math.isfinite(a) and a > 0):
        raise ValueError(f"amplitude must be a positive number of m (or of gaps with unit='gap'), "
                         f"got {amplitude!r}")
    why = _outside(branch, a)
    if why:
        warnings.warn(f"orbits_at: {why}: no orbit listed", BranchWarning, stacklevel=3)
        return OrbitsAt(a, (), why)
    solver = branch._require_solver()
    if search and not _searchable(branch, solver, a):
        raise ValueError(f"search=True needs a harmonic balance branch whose solver exposes its harmonics "
                         f"(unpack, pack, linear_mode_point) and records the fundamental's share; this one "
                         f"is {branch.method!r} ({type(solver).__name__}): call orbits_at without search")
    found: list[Orbit] = []
    rejected: list[Orbit] = []
    known_states: list[np.ndarray] = []

    def add(orbit: Orbit | None, family_rule: bool = True) -> None:
        if orbit is None or any(orbit.same_as(o) for o in found + rejected):
            return
        known_states.append(np.asarray(orbit.state))
        shifted = _half_period_shift(solver, orbit.state)
        if shifted is not None:
            known_states.append(shifted)
        if family_rule and not orbit.fundamental_share >= FAMILY_SHARE:
            rejected.append(orbit)
        else:
            found.append(orbit)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BranchWarning)
        point = branch.solve_at([a], tol=tol)
    if int(point.records["solved"][0]):
        backbone = _orbit(solver, np.asarray(point.states[0]), a, "backbone", "frequency_at's orbit")
        add(backbone, family_rule=False)
    n_backbone = len(found)
    states = np.asarray(branch.states, dtype=float)
    A = np.asarray(branch.amplitude, dtype=float)
    for i, j in _crossings(branch, a):
        s = 0.0 if i == j else (a - A[i]) / (A[j] - A[i])
        u = _pinned(solver, states[i] + s * (states[j] - states[i]), a, tol, SEARCH_MAX_ITER)
        if u is not None:
            add(_orbit(solver, u, a, "branch", f"path segment {i}–{j}" if i != j else f"point {i}"))
    n_branch = len(found)
    searched = 0
    if search:
        admissible = _window(solver, a)
        for origin, u0 in search_starts(solver, list(found), a):
            searched += 1
            if not admissible(u0):
                continue
            # Newton on the problem itself first; where it returns a known orbit (or
            # fails), on the residual deflated at every orbit known so far
            u = _pinned(solver, u0, a, tol, SEARCH_MAX_ITER, admissible)
            orbit = None if u is None else _orbit(solver, u, a, "search", f"from the {origin}")
            if orbit is None or any(orbit.same_as(o) for o in found + rejected):
                u = _pinned(Deflated(solver, known_states), u0, a, tol, SEARCH_MAX_ITER, admissible)
                if u is not None:
                    u = _pinned(solver, u, a, tol, 5)  # polished on the problem itself
                orbit = None if u is None else _orbit(solver, u, a, "search", f"from the {origin}, deflated")
            add(orbit)
    ordered = (found[:n_backbone] + sorted(found[n_backbone:n_branch], key=lambda o: o.frequency)
               + sorted(found[n_branch:], key=lambda o: o.frequency))
    reason = ""
    if not ordered:
        reason = ("no orbit of the family converged at this amplitude"
                  + ("" if n_backbone else " (the backbone has none: frequency_at is NaN here)"))
    return OrbitsAt(a, tuple(ordered), reason, searched, tuple(o.frequency for o in rejected))
