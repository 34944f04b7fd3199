"""The one search for the family beyond a frontier: deflated Newton at pinned amplitudes.

Where the branch has left the family (docs/resonances.md), the family's continuation is
sought at amplitudes A_i = frontier·(1 + jump_step·2^i), consecutive ones at most
``target_ratio`` apart, up to the amplitude bound, by Newton on the pinned system
G(u) = [R(u); A(u)/A_i − 1] = 0 (:mod:`mmshbm.core.pinned`) from a fixed set of starts
(:class:`BranchStarts`; a method's own through the problem's ``family_starts()``).
Every orbit u_k found at A_i is *deflated*: Newton then solves F(u) = M(u) G(u) = 0 with

    M(u) = Π_k (‖u − u_k‖⁻ᵖ + σ),      p = :data:`POWER`, σ = :data:`SHIFT`,

which has the same roots as G except the u_k (M → ∞ there), so from the same start Newton
goes to another orbit or fails. Each start is solved from at most ``max_roots`` times
(its deflation depth: the orbits it reached deflated, its own chain) and stops at its
first orbit of the family; every start runs at every target (at most starts ×
``max_roots`` solves per target), and no start's orbits are deflated in another's solve,
so which orbits a target yields does not depend on the order of the starts. With d the
Newton step of G, the Newton step of F is
d / (1 − ∇log M·d) (Sherman–Morrison on the rank-one change of the Jacobian), so one
bordered solve per iteration serves both. At the first target where orbits of the
family are found (:func:`mmshbm.family.definition.on_family` with the first mode's
frequency band, :func:`~mmshbm.family.definition.frequency_band`), the one of largest fundamental share is the
landing (the backbone rule of docs/resonances.md); the follower fills the family back
down from it to the frontier. Where no target has one, the method's costly starts
(``last_resort``: MMS-HBM's homotopy from the fundamental's family) are tried at the
targets in turn. When none is found then the search ends
the branch with a :class:`~mmshbm.family.end.FamilyEnd` that lists every solve.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable
from typing import Protocol

import numpy as np

from ..core.bordered import bordered_solve
from ..core.pinned import PinnedFailure, StartOutside, amplitude_and_gradient
from ..core.problem import as_problem
from .definition import family_value, frequency_band, on_family
from .end import Attempt, FamilyEnd, FamilyEnded, crossing, turned_back
from .guard import FamilyGuard
from .options import FamilyOptions

__all__ = ["POWER", "SHIFT", "FamilyStarts", "KnownOrbit", "BranchStarts", "deflated_solve", "deflation",
           "search_beyond"]

log = logging.getLogger(__name__)

#: p of the deflation operator (2: M grows like the inverse squared distance to a known orbit)
POWER = 2

#: σ of the deflation operator (dimensionless, the unknowns are scaled to order one): far
#: from every known orbit M tends to σ^(number known), a constant factor of the residual
SHIFT = 1.0

#: relative distance (to the orbit's norm) below which a converged orbit is the known one:
#: a round-off bound of Newton's convergence, far below any two distinct orbits
_SAME_ORBIT_ROUNDOFF = 1e-8

#: the trust region of Newton's iterates: the first mode's frequency band widened by this
#: factor either way (a numerical safeguard, not an acceptance rule: the path to an orbit
#: in the band may leave it, but an iterate far beyond it evaluates harmonics above the
#: modes the condensation kept)
_TRUST_FACTOR = 2.0

#: a pinned solve's iterations in units of the corrector's ``max_newton``: a start away
#: from the branch needs more than a predictor on it (on the nonsmooth residual a solve
#: can creep for 20–28 iterations before it converges; :mod:`mmshbm.core.pinned`)
_NEWTON_FACTOR = 3

#: Newton's step halvings per iteration (the last step, λ = 1/32, is taken whatever its
#: residual, as in :func:`mmshbm.core.pinned.solve_at_amplitude`)
_HALVINGS = 6


class KnownOrbit(PinnedFailure):
    """A deflated solve converged onto an orbit already found (within round-off)."""


def deflation(u: np.ndarray, known: list, shift: float) -> tuple[float, np.ndarray]:
    """(M(u), ∇log M(u)) of the deflation operator over the ``known`` orbits (shape (n,)
    each) with shift σ = ``shift``; (1, 0) without known orbits."""
    M = 1.0
    w = np.zeros(len(u))
    for uk in known:
        e = u - uk
        r2 = float(e @ e)
        if r2 == 0.0:
            return math.inf, w
        r_p = r2 ** (-POWER / 2)
        m = r_p + shift
        M *= m
        w += (-POWER * r_p / r2 / m) * e
    return M, w


def deflated_solve(problem, u0: np.ndarray, amplitude: float, known: list, *, shift: float = SHIFT,
                   tol: float = 1e-10, max_iter: int = 30, step_tol: float = 1e-8,
                   admissible: Callable[[np.ndarray], bool] | None = None):
    """Newton on the deflated pinned system M(u)·[R(u); A(u)/A* − 1] = 0 from ``u0``.

    Converged when the undeflated residual's infinity norm is at most ``tol`` (or the
    step at most ``step_tol`` with the residual at most √tol, as
    :func:`mmshbm.core.pinned.solve_at_amplitude`), so the result is an orbit of the
    undeflated problem. ``admissible(u)`` is the trust region of the iterates (a step
    that leaves it is halved; a start outside it raises
    :class:`~mmshbm.core.pinned.StartOutside`).

    Returns
    -------
    u, iterations, residual history, unit tangent at u (oriented to growing amplitude)

    Raises
    ------
    KnownOrbit
        Converged within round-off of a known orbit (deflation makes this rare).
    PinnedFailure
        No convergence, a singular system, a non-finite residual or the trust region left.
    """
    if not amplitude > 0:
        raise ValueError(f"amplitude must be positive, got {amplitude!r}")
    problem = as_problem(problem)
    gradient = problem.amplitude_and_gradient or (lambda v: amplitude_and_gradient(problem, v))
    u = np.array(u0, dtype=float)
    if admissible is not None and not admissible(u):
        raise StartOutside("the start lies outside the trust region")
    history = []
    du_norm = math.inf
    for it in range(max_iter + 1):
        try:
            R, J = problem.residual_and_jacobian(u)
            A, g = gradient(u)
        except (ArithmeticError, np.linalg.LinAlgError, ValueError, RuntimeError) as err:
            raise PinnedFailure(f"evaluation failed: {err}") from None
        c = A / amplitude - 1.0
        norm = max(float(np.abs(R).max()) if R.size else 0.0, abs(c))
        history.append(norm)
        if not math.isfinite(norm):
            raise PinnedFailure("non-finite residual")
        if norm <= tol or (du_norm <= step_tol and norm <= math.sqrt(tol)):
            _check_new(u, known)
            rhs = np.zeros(len(u))
            rhs[-1] = 1.0
            t = bordered_solve(J, g / amplitude, rhs)
            if not np.all(np.isfinite(t)):
                raise PinnedFailure("singular system at the solution")
            return u, it, np.array(history), t / np.linalg.norm(t)
        if it == max_iter:
            break
        rhs = np.empty(len(u))
        rhs[:-1] = R
        rhs[-1] = c
        du = bordered_solve(J, g / amplitude, rhs)  # the undeflated step is −du
        if not np.isfinite(du).all():
            raise PinnedFailure("singular system")
        M, w = deflation(u, known, shift)
        denominator = 1.0 + float(w @ du)
        if not (math.isfinite(M) and denominator != 0.0):
            raise PinnedFailure("the deflated step is undefined (at a known orbit)")
        du = du / denominator
        du_norm = float(np.abs(du).max())
        lam = 1.0
        for halving in range(_HALVINGS + 1):
            trial = u - lam * du
            last = halving == _HALVINGS
            if admissible is not None and not admissible(trial):
                if last:
                    raise PinnedFailure(f"Newton left the trust region (iteration {it + 1})")
            elif last or _deflated_norm(problem, trial, amplitude, known, shift, M * norm) < M * norm:
                break
            lam *= 0.5
        u = u - lam * du
    raise PinnedFailure(f"no convergence in {max_iter} iterations (residual {history[-1]:.2e})")


def _check_new(u: np.ndarray, known: list) -> None:
    if any(_same(u, uk) for uk in known):
        raise KnownOrbit("converged onto an orbit already found")


def _same(u: np.ndarray, v: np.ndarray) -> bool:
    """Whether two states agree within round-off (relative to their size)."""
    scale = max(float(np.abs(u).max()), 1.0)
    return u.shape == v.shape and float(np.abs(u - v).max()) <= _SAME_ORBIT_ROUNDOFF * scale


def _deflated_norm(problem, u: np.ndarray, amplitude: float, known: list, shift: float,
                   above: float = math.inf) -> float:
    """M(u)·‖G(u)‖∞ (inf where the evaluation fails). Where the residual alone puts it at
    ``above`` or more, that bound is returned without evaluating the amplitude."""
    try:
        r = float(np.abs(problem.residual(u)).max())
        M = deflation(u, known, shift)[0]
        if M * r >= above:
            return above
        A = (problem.amplitude_value(u) if problem.amplitude_value is not None
             else amplitude_and_gradient(problem, u)[0])
    except (ArithmeticError, np.linalg.LinAlgError, ValueError, RuntimeError):
        return math.inf
    return M * max(r, abs(A / amplitude - 1.0))


class FamilyStarts(Protocol):
    """What the deflated search starts Newton from (supplied by composition)."""

    def landings(self, us: list, recs: list, guard: FamilyGuard,
                 amplitude_max: float) -> list[tuple[str, np.ndarray, float]]:
        """(name, u0, amplitude) per start that picks its own amplitude (m) beyond the
        frontier (MMS-HBM: the resonance passed with the resonant harmonic filtered out)."""

    def starts(self, us: list, recs: list, guard: FamilyGuard, amplitude: float,
               amplitude_max: float) -> list[tuple[str, np.ndarray]]:
        """(name, u0) per start at the pinned ``amplitude`` (m), best first."""


class BranchStarts:
    """The method-agnostic starts of the deflated search, from the branch alone: from the
    frontier and from the family points of largest share in the windows below it (before
    an internal resonance drew energy from them; :meth:`FamilyGuard.origins`), the orbit
    extrapolated in amplitude (a polynomial of degree <= 2 through the last family points
    up to it); then the linear mode at the target (``linear_mode_point``, where the
    problem has one). A method adds its own by subclassing (:meth:`origin_starts`,
    :meth:`landings`) and offers the object as the problem's ``family_starts()``
    (MMS-HBM: :class:`mmshbm.methods.mms.family_starts.MMSHBMStarts`)."""

    def __init__(self, problem):
        self.problem = problem
        self.amplitude_max = math.inf
        #: (tol, max_iter, admissible) of the search's pinned solves, for starts that solve
        self.solver = (1e-10, 30, None)
        #: deflated solves per start, for starts that deflate (the search's ``max_roots``)
        self.depth = 3
        #: (u0, amplitude) of this search's landings of the problem's own (:meth:`landings`)
        self._landed: list[tuple[np.ndarray, float]] = []

    def landings(self, us: list, recs: list, guard: FamilyGuard,
                 amplitude_max: float) -> list[tuple[str, np.ndarray, float]]:
        """The problem's own landing beyond the frontier (``family_landing``, where it
        offers one: MMS-HBM's resonance passed with its harmonic filtered out, EPMC's
        path followed on until it is back on the family), from the best origin
        (:meth:`FamilyGuard.origins`) where it lands between the frontier and the bound:
        a start that picks its own amplitude. None where the problem offers none."""
        self._landed = []
        landing = getattr(self.problem, "family_landing", None)
        if landing is None:
            return []
        i = guard.frontier_index
        frontier = float(recs[i]["amplitude"])
        excursion = us[i + 1:]
        for origin in guard.origins(lambda j: float(recs[j]["amplitude"])):
            try:
                u0, target = landing(us[origin], recs[origin], excursion, amplitude_max, frontier,
                                     family_share=guard.family_share)
            except (ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError) as err:
                log.debug("no landing of the problem's own from %d: %s", origin, err)
                continue
            if frontier < target <= amplitude_max:
                self._landed.append((u0, float(target)))
                return [("filtered landing", u0, float(target))]
        return []

    def origin_starts(self, us: list, recs: list, guard: FamilyGuard, origin: int, amplitude: float,
                      amplitude_max: float) -> list[tuple[str, np.ndarray]]:
        """The problem's starts at ``amplitude`` from the family point ``origin``, where it
        offers them: the orbit along its auxiliary branch (``family_predictor``) and the
        orbit scaled to the target (``scaled_state``: far above the gap a
        piecewise-linear system is nearly homogeneous)."""
        p = self.problem
        A_o = float(recs[origin]["amplitude"])
        out = []
        predictor = getattr(p, "family_predictor", None)
        if predictor is not None:
            try:
                out.append(("family predictor", predictor(us[origin], A_o, amplitude, amplitude_max)))
            except (ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError):
                pass
        scaled = getattr(p, "scaled_state", None)
        if scaled is not None and A_o > 0:
            out.append(("scaled", scaled(us[origin], amplitude / A_o)))
        return out

    def starts(self, us: list, recs: list, guard: FamilyGuard, amplitude: float,
               amplitude_max: float) -> list[tuple[str, np.ndarray]]:
        i = guard.frontier_index
        A_f = float(recs[i]["amplitude"])
        out = self.before(us, recs, guard, amplitude)
        for origin in [i] + [j for j in guard.origins(lambda j: float(recs[j]["amplitude"])) if j != i]:
            A_o = float(recs[origin]["amplitude"])
            at = "the frontier" if origin == i else f"{A_o / A_f:.2f} of the frontier"
            own = self.origin_starts(us, recs, guard, origin, amplitude, amplitude_max)
            out += [(f"{name} from {at}", u0) for name, u0 in own]
            clean = [j for j in guard.clean if j <= origin]
            if clean:
                out.append((f"extrapolated from {at}", extrapolated(us, recs, clean, amplitude)))
        last = len(us) - 1
        if last > i:  # where the branch is now: the excursion's end, which may come back beyond
            own = self.origin_starts(us, recs, guard, last, amplitude, amplitude_max)
            out += [(f"{name} from the branch's end", u0) for name, u0 in own]
        linear = getattr(self.problem, "linear_mode_point", None)
        if linear is not None:
            try:
                out.append(("linear mode", linear(amplitude)))
            except (NotImplementedError, ArithmeticError, ValueError):
                pass
        return out

    def before(self, us: list, recs: list, guard: FamilyGuard,
               amplitude: float) -> list[tuple[str, np.ndarray]]:
        """Starts tried first at ``amplitude`` (none here)."""
        return []

    def last_resort(self, us: list, recs: list, guard: FamilyGuard, amplitude: float,
                    amplitude_max: float) -> list[tuple[str, np.ndarray]]:
        """Costly starts at ``amplitude``, tried at the targets in turn only where the
        others found no orbit of the family at any target (none here)."""
        return []


def extrapolated(us: list, recs: list, clean: list, amplitude: float) -> np.ndarray:
    """u at ``amplitude`` by a polynomial in the amplitude (degree <= 2) through the last
    three family points ``clean`` (indices)."""
    idx = clean[-3:]
    A = np.array([recs[i]["amplitude"] for i in idx], dtype=float)
    U = np.array([us[i] for i in idx])
    if len(idx) == 1 or np.ptp(A) == 0:
        return U[-1].copy()
    deg = min(len(idx) - 1, 2)
    x = (A - A[-1]) / abs(A[-1])
    coef = np.polyfit(x, U, deg)
    xt = (amplitude - A[-1]) / abs(A[-1])
    return sum(c * xt ** (deg - p) for p, c in enumerate(coef))


def _targets(frontier: float, amplitude_max: float, options: FamilyOptions) -> list[float]:
    """The amplitude targets beyond ``frontier``: frontier·(1 + jump_step·2^i), consecutive
    ones at most ``target_ratio`` apart, up to ``amplitude_max`` (at most
    frontier/jump_step)."""
    top = min(amplitude_max, frontier / options.jump_step)
    out = []
    target, i = frontier, 0
    while target < top:
        target = min(frontier * (1.0 + options.jump_step * 2.0**i), target * options.target_ratio, top)
        out.append(target)
        i += 1
    return out


def search_beyond(problem, guard: FamilyGuard, us: list, recs: list, *, options: FamilyOptions,
                  amplitude_max: float, newton_tol: float, max_newton: int, monitor,
                  starts: FamilyStarts | None = None) -> tuple:
    """The family's continuation beyond the frontier (see the module docstring).

    Returns
    -------
    (u, iterations, history, record, tangent, target, origin) of the landing: the state,
    its Newton iterations and residual history, its record, its unit tangent oriented to
    growing amplitude, the target amplitude (m) and the index of the frontier point.

    Raises
    ------
    FamilyEnded
        No orbit of the family found; ``err.end`` lists every solve.
    """
    if guard.frontier_index < 0:
        raise PinnedFailure("the branch has no family point to jump from")
    problem = as_problem(problem)
    if starts is None:
        starts = problem.family_starts() if problem.family_starts is not None else BranchStarts(problem)
    i = guard.frontier_index
    frontier = float(recs[i]["amplitude"])
    f_frontier = float(recs[i].get("frequency", math.nan))
    band = frequency_band(problem, recs, options.band_slack)
    frequency_of = problem.frequency_of
    admissible = None
    if frequency_of is not None and math.isfinite(band[1]):
        lo, hi = band[0] / _TRUST_FACTOR, band[1] * _TRUST_FACTOR

        def admissible(u):
            return lo <= frequency_of(u) <= hi

    tried = []
    starts.amplitude_max = amplitude_max
    starts.solver = (newton_tol, _NEWTON_FACTOR * max_newton, admissible)
    starts.depth = options.max_roots
    # the method's landings (a start that picks its own amplitude, MMS-HBM's filtered
    # passage, costly) join the targets once the first target has found no family orbit
    landings = None
    queue = _targets(frontier, amplitude_max, options)
    searched = queue[-1]
    done = []  # the targets searched, in order

    def at(target, candidates):
        """The landing at ``target`` from the starts ``candidates``, or None."""
        found = []  # (u, iterations, history, record, tangent, member) of every orbit found at target
        seen = []  # the starts solved from at this target
        for name, u0 in candidates:
            if any(_same(u0, v) for v in seen):
                continue  # the same start goes the same way
            seen.append(u0)
            chain = []  # the orbits this start reached, deflated for its next solve
            for _ in range(options.max_roots):  # the start's deflation depth
                try:
                    u, nit, hist, t = deflated_solve(
                        problem, u0, target, chain,
                        tol=newton_tol, max_iter=_NEWTON_FACTOR * max_newton, admissible=admissible)
                except PinnedFailure as err:
                    outcome = ("outside" if isinstance(err, StartOutside)
                               else "known" if isinstance(err, KnownOrbit) else "failed")
                    tried.append(Attempt("deflated", name, target, outcome))
                    break
                chain.append(u)
                rec = monitor(problem, u)
                f = float(rec.get("frequency", math.nan))
                share = family_value(rec)
                share = math.nan if share is None else share
                if any(_same(u, x[0]) for x in found):  # reached from an earlier start too
                    tried.append(Attempt("deflated", name, target, "known", f, share))
                    continue
                member = on_family(rec, options.family_share, band) is not False
                tried.append(Attempt("deflated", name, target, "landed" if member else "off the family", f,
                                     share))
                found.append((u, nit, hist, rec, t, member))
                log.debug("deflated search at %.4g from the %s start: %.4g Hz, share %.3f (%s)", target, name,
                          f, share, "family" if member else "not the family")
                if member:
                    break  # the start has reached the family
        family = [x for x in found if x[5]]
        if not family:
            return None
        # the tangent solves [J; ∇A/A*] t = e_n: oriented to growing amplitude
        u, nit, hist, rec, t, _ = max(family, key=lambda x: family_value(x[3]) or 0.0)
        return u, nit, hist, rec, t, target, i

    while queue:
        target = queue.pop(0)
        done.append(target)
        own = [(name, u0) for name, u0, a in landings or () if a == target]
        landing = at(target, own + starts.starts(us, recs, guard, target, amplitude_max))
        if landing is not None:
            return landing
        if landings is None:
            landings = starts.landings(us, recs, guard, amplitude_max)
            queue = sorted(set(queue) | {a for _, _, a in landings})
            searched = max([searched] + queue)
    # the costly starts, at the targets in turn, where the others found nothing at any
    last = getattr(starts, "last_resort", None)
    for target in done if last is not None else ():
        landing = at(target, last(us, recs, guard, target, amplitude_max))
        if landing is not None:
            return landing
    cross = crossing(recs, guard, problem)
    end = FamilyEnd(ended=cross is not None, frontier=frontier, frontier_frequency=f_frontier,
                    searched_to=float(searched), crossing=cross, attempts=tuple(tried))
    if cross is None:
        end = dataclasses.replace(end, notes=turned_back(recs, guard) + end.tried())
    raise FamilyEnded(end)
