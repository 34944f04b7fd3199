"""Staying on the family of the starting mode: internal-resonance tongues and jumps.

A backbone continued from a linear mode meets internal resonances where a harmonic k of
the motion reaches another mode j (kΩ ≈ ω_j). There the branch of the conservative
problem turns into a *tongue*: the frequency locks near ω_j/k while the energy moves into
mode j. Arclength continuation follows the tongue. Sometimes the tongue comes back onto
the starting mode's family above the amplitude where it left (a *passage*); sometimes it
becomes the nonlinear mode of mode j and leads back down onto the family below that
amplitude, and the path follower cycles (a *loop*), or it never comes back.

:class:`FamilyGuard` watches the fundamental harmonic's share of the kinetic energy
(``record["fundamental_share"]``, 0..1, :func:`family_value`), the amplitude and the
frequency of every accepted point (docs/resonances.md says why):

* a point is *on the family* when the fundamental carries at least ``family_share`` of
  the kinetic energy (default a majority, 0.5), or when it continues the family from its
  frontier with amplitude and frequency rising and the frequency not locked (a change of
  shape or of harmonic content is not a resonance); a climb that then folds or locks was
  a tongue and is marked off the family after the fact;
* the *frontier* is the largest amplitude reached on the family so far;
* it asks for a **jump** when the branch left the family and has not come back above the
  frontier within ``max_excursion`` steps, when it comes back onto the family 5 % or more
  below the frontier (a loop), when it stays on the family without passing the frontier for
  ``max_excursion`` steps, or when the step size fails at ``ds_min``.

A jump (:func:`jump`) solves the problem with the amplitude pinned
(:mod:`mmshbm.core.pinned`) slightly beyond the frontier, in a frequency trust region,
from the problem's own landing (MMS-HBM: the resonant harmonic filtered out) or from
three predictors in turn (``problem.family_predictor`` along an auxiliary branch, a
quadratic through the last clean family points, the frontier point scaled to the
target), and accepts the result only if it is on the family; otherwise it tries further
out (amplitude steps 2, 4, 8, ... % beyond the frontier), at most 40 pinned solves, then
in a far search up to the bound (30 more), and last by continuing the orbit in the
harmonics (``problem.harmonic_landing``: a low-harmonic family's orbit at the target,
solved again with more and more harmonics; at most 8 targets), then above the bound,
followed back down onto it, and last by a homotopy from the orbit of the fundamental's
family raised to H (``problem.homotopy_landing``, :mod:`mmshbm.family.landings`; at
most 4 targets). When nothing lands and the starting mode's own orbit lost the
fundamental's majority at the frontier, the family ended there
(:class:`~mmshbm.family.end.FamilyEnded`). The
continuation goes on from there; the skipped interval is recorded as a ``"jump"``
special point. Points of the excursion stay on the branch with
``record["on_family"] = 0``.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from ..core.pinned import PinnedFailure, solve_at_amplitude
from .definition import FAMILY_RECORD, family_value, on_family
from .end import Attempt, FamilyEnd, FamilyEnded, crossing, turned_back
from .guard import FamilyGuard
from .landings import (
    LIMIT_SLACK,
    MAX_FAR_TARGETS,
    MAX_LADDERS,
    MAX_SCAN_TARGETS,
    MAX_TARGETS,
    N_SCAN_FREQUENCIES,
    frequency_search,
    harmonic_search,
    homotopy_search,
)

__all__ = ["FAMILY_RECORD", "FamilyEnded", "FamilyGuard", "family_value", "jump"]

log = logging.getLogger(__name__)

#: pinned solves a jump may try before it gives up (bounds the cost of a failing jump)
_MAX_SOLVES = 40
#: pinned solves of the far search (from one origin, up to the bound)
_MAX_FAR_SOLVES = 30


class _Exhausted(PinnedFailure):
    """A jump used up its pinned solves."""


class _Outside(PinnedFailure):
    """A predictor outside the jump's trust region (not solved, not counted)."""


class _Converged(PinnedFailure):
    """A pinned solve that converged to an orbit the jump refuses; ``orbit`` is its
    (frequency Hz, fundamental share)."""

    def __init__(self, message: str, orbit: tuple[float, float]):
        super().__init__(message)
        self.orbit = orbit


class _OffFamily(_Converged):
    """A pinned solve that converged to a point off the family (by its fundamental share).
    The far search does not repeat it: only its wider trust region could change where
    Newton goes from the same start, which is rare for a solve that converged."""


class _Rejected(_Converged):
    """A pinned solve that converged on the family outside the jump's frequency window
    (another branch)."""



#: largest ratio between consecutive targets of the far search beyond the near targets
_FAR_RATIO = 1.1


def _extrapolated(us: list, recs: list, clean: list, amplitude: float) -> np.ndarray:
    """u at ``amplitude`` by a polynomial in the amplitude (degree <= 2) through the last
    clean frontier points."""
    idx = clean[-3:]
    A = np.array([recs[i]["amplitude"] for i in idx])
    U = np.array([us[i] for i in idx])
    if len(idx) == 1 or np.ptp(A) == 0:
        return U[-1].copy()
    deg = min(len(idx) - 1, 2)
    x = (A - A[-1]) / max(abs(A[-1]), 1e-300)
    coef = np.polyfit(x, U, deg)
    xt = (amplitude - A[-1]) / max(abs(A[-1]), 1e-300)
    return sum(c * xt ** (deg - p) for p, c in enumerate(coef))


def _nearer_landing(problem, u_front, frontier: float, u_land, landing: float, predictor,
                    amplitude_max: float, step: float, accept, rec_land: dict, coexisting=None):
    """A landing on the family nearer the frontier than ``landing``: the filtered passage
    of an internal resonance lands where the resonant harmonic is released, which can be
    well beyond the tongue (the family may reappear between two tongues). Tries
    amplitudes frontier·(1 + step·2^i) and the midpoints between them, upwards, up to the
    landing, from the state interpolated between the frontier point and the landing and
    from the problem's family predictor (from the frontier and back from the landing);
    returns (u, iterations, history, record, tangent, amplitude) of the lowest one on the
    family, or None. With ``coexisting(u, tangent, landing, rec_land)`` (True when the
    branch through the nearer point passes the landing's amplitude on the family at
    another orbit) the lowest point found is checked, and None returned when it lies on
    such a coexisting branch: a tongue's side that keeps the fundamental's majority up
    to its fold, which the filtered passage went around."""
    if landing <= frontier * (1.0 + 2.0 * step):
        return None
    grid = []
    i = 0
    while True:
        a = frontier * (1.0 + step * 2.0**i)
        if a >= landing * (1.0 - step):
            break
        grid.append(a)
        i += 1
    grid = sorted(set(grid) | {0.5 * (p + q) for p, q in zip(grid, grid[1:] + [landing], strict=True)})
    for a in grid:
        s = (a - frontier) / (landing - frontier)
        starts = [(1.0 - s) * u_front + s * u_land]
        if predictor is not None:
            for u_from, a_from in ((u_front, frontier), (u_land, landing)):
                try:
                    starts.append(predictor(u_from, a_from, a, amplitude_max))
                except (ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError):
                    pass
        for u0 in starts:
            try:
                u, nit, hist, rec, t = accept(u0, a, math.nan)
            except (PinnedFailure, ArithmeticError, ValueError) as err:
                log.debug("nearer landing at %.4g: %s", a, err)
                continue
            if coexisting is not None and coexisting(u, t, landing, rec_land):
                log.debug("nearer landing at %.4g lies on a branch beside the landing's", a)
                return None
            return u, nit, hist, rec, t, a
    return None


def jump(problem, guard: FamilyGuard, us: list, recs: list, *, step: float, amplitude_max: float,
         newton_tol: float, max_newton: int, monitor, coexisting=None, descend=None) -> tuple:
    """Land on the family beyond the frontier.

    Tries the origins of :meth:`FamilyGuard.origins` and, from each, amplitudes
    ``frontier·(1 + step·2^i)``, i = 0..6 (capped at ``amplitude_max``); then a far
    search from the best origin, i = 0..12, in the window up to the problem's
    ``family_frequency_limit``. A landing counts when Newton converges, the point is on
    the family, and its frequency is within 15 % of the predicted one or at or above the
    frontier's (a backbone with rigid stops only stiffens), inside the frequency window
    (else it found another branch). ``coexisting`` checks a landing nearer the frontier
    than a filtered passage's (:func:`_nearer_landing`). When all of these fail, the
    problem's ``harmonic_landing`` (if any) gives the orbit at each target continued in
    the harmonics from a low-harmonic family, up to the problem's
    ``family_frequency_ceiling`` (:func:`~mmshbm.family.landings.harmonic_search`);
    when that fails too, the
    family is sought above the bound and followed back down onto it by ``descend(u,
    tangent, amplitude, amplitude_max)`` (None or the tuple (u, iterations, history,
    record, tangent) at ``amplitude_max``; :func:`_beyond_bound`), and last
    ``homotopy_landing`` gives the orbit reached by a homotopy from the fundamental's
    family (:func:`~mmshbm.family.landings.homotopy_search`).

    Returns
    -------
    (u, iterations, history, record, tangent, target, origin) of the landing point.

    Raises
    ------
    FamilyEnded
        If no attempt lands and the branch's point after the frontier has lost the
        fundamental's share (:func:`~mmshbm.family.end.end_of_family`).
    PinnedFailure
        If no attempt lands on the family otherwise.
    """
    if guard.frontier_index < 0:
        raise PinnedFailure("the branch has no family point to jump from")
    frontier = float(recs[guard.frontier_index]["amplitude"])
    f_frontier = float(recs[guard.frontier_index].get("frequency", math.nan))
    predictor = problem.family_predictor
    landing = problem.family_landing
    last_error = "no attempt"
    targets = []
    for attempt in range(7):
        target = min(frontier * (1.0 + step * 2.0**attempt), amplitude_max)
        if not targets or target > targets[-1]:
            targets.append(target)

    f_lo, f_hi = _frequency_window(recs, guard, targets[-1])
    window = {"hi": f_hi}  # the far search below widens it to its own targets
    limit = problem.family_frequency_limit
    f_limit = limit() if limit is not None else math.inf
    ceiling = problem.family_frequency_ceiling
    f_ceiling = ceiling() if ceiling is not None else f_limit
    frequency_of = problem.frequency_of
    admissible = None
    if frequency_of is not None and math.isfinite(f_lo) and f_lo > 0:
        # the trust region: a landing is accepted within 30 % of the family's frequencies,
        # so no iterate needs to leave [f_lo/2, 2 f_hi]
        def admissible(u):
            return 0.5 * f_lo <= frequency_of(u) <= 2.0 * window["hi"]

    solves = [0, _MAX_SOLVES]  # solves made, solves allowed

    tried = []  # the Attempt of every pinned solve
    stage = ["filtered"]  # the search now running

    def accept(u0, target, f_pred):
        try:
            u, nit, hist, rec, t = solved(u0, target, f_pred)
        except (_Outside, _Exhausted):  # nothing solved
            raise
        except _OffFamily as err:
            tried.append(Attempt(stage[0], stage[0], float(target), "off the family", *err.orbit))
            raise
        except _Rejected as err:
            tried.append(Attempt(stage[0], stage[0], float(target), "rejected", *err.orbit))
            raise
        except (PinnedFailure, ArithmeticError, ValueError):
            tried.append(Attempt(stage[0], stage[0], float(target), "failed"))
            raise
        share = family_value(rec)
        f = float(rec.get("frequency", math.nan))
        share = math.nan if share is None else share
        tried.append(Attempt(stage[0], stage[0], float(target), "landed", f, share))
        return u, nit, hist, rec, t

    def solved(u0, target, f_pred):
        f_hi = window["hi"]
        if admissible is not None and not admissible(u0):
            raise _Outside("the predictor lies outside the trust region")
        if solves[0] >= solves[1]:
            raise _Exhausted(f"{solves[1]} pinned solves tried")
        solves[0] += 1
        u, nit, hist, t = solve_at_amplitude(problem, u0, target, tol=newton_tol, max_iter=3 * max_newton,
                                             admissible=admissible)
        rec = monitor(problem, u)
        f = rec.get("frequency", math.nan)
        share = family_value(rec)
        orbit = (float(f), math.nan if share is None else float(share))
        if on_family(rec, guard.family_share) is False:
            raise _OffFamily(f"landed off the family (fundamental share {share:.3f}) at {target:.4g}", orbit)
        # near the predicted frequency, or on the rising side of the frontier: a backbone
        # with rigid stops only stiffens, so the family beyond the frontier lies at or
        # above the frontier's frequency (a predictor taken from a point near grazing
        # can be far below it on a steeply rising backbone)
        near = math.isfinite(f_pred) and abs(f - f_pred) <= 0.15 * abs(f_pred)
        rising = math.isfinite(f_frontier) and f >= f_frontier * (1.0 - 1e-6)
        if math.isfinite(f_pred) and not (near or rising):
            raise _Rejected(f"landed on another branch ({f:.4g} instead of about {f_pred:.4g})", orbit)
        if math.isfinite(f_lo) and not 0.7 * f_lo <= f <= _WINDOW_SLACK * f_hi:
            raise _Rejected(f"landed on another branch ({f:.4g} Hz, the family was at "
                            f"{f_frontier:.4g} Hz, expected up to {f_hi:.4g} Hz)", orbit)
        return u, nit, hist, rec, t

    if landing is not None:  # the problem's own landing (MMS-HBM: filtering the resonant harmonic)
        excursion = us[guard.frontier_index + 1:]  # the states of the excursion
        for origin in guard.origins(lambda i: float(recs[i]["amplitude"])):
            try:
                u0, target = landing(us[origin], recs[origin], excursion, amplitude_max, frontier)
                u, nit, hist, rec, t = accept(u0, target, math.nan)
                nearer = _nearer_landing(problem, us[guard.frontier_index], frontier, u, target, predictor,
                                         amplitude_max, step, accept, rec, coexisting)
                if nearer is not None:
                    u, nit, hist, rec, t, target = nearer
                return u, nit, hist, rec, t, target, origin
            except _Exhausted:
                break
            except (PinnedFailure, ArithmeticError, ValueError, RuntimeError) as err:
                last_error = f"filtered passage: {err}"
                log.debug("jump from %d by filtering: %s", origin, last_error)
    stage[0] = "near"
    origins = guard.origins(lambda i: float(recs[i]["amplitude"]))
    settled = set()  # attempts that landed off the family: the far search does not repeat them
    try:
        return _search(problem, us, recs, guard, origins, targets, amplitude_max, accept, frequency_of,
                       monitor, settled)
    except _Exhausted as err:
        reason = f" after {_MAX_SOLVES} pinned solves: "
        last_error = str(err) if str(err) != "no attempt" else last_error
    except PinnedFailure as err:
        reason = ": "
        last_error = str(err) if str(err) != "no attempt" else last_error
    # the far search: a tongue (or an S-shaped stretch of backbone that folds back) can
    # span more amplitude than 2.28 times the frontier, and a backbone that rises steeply
    # just past grazing (a clearance) can leave the window extrapolated from a frontier
    # near grazing; the family is sought again from the frontier's best origin, up to the
    # bound, in the window up to the highest frequency the family can reach (the
    # problem's limit: rigid stops stiffen the structure at most to all contacts held).
    # Its targets beyond the near ones are at most _FAR_RATIO apart: whether Newton
    # converges from a predictor scaled several-fold is a matter of the target, and
    # doubling steps can leave a family that returns below the bound with only one or two
    # tries near it
    far = list(targets)
    for i in range(7, 13):
        target = min(frontier * (1.0 + step * 2.0**i), amplitude_max)
        while target > far[-1] * _FAR_RATIO * (1 + 1e-12):
            far.append(far[-1] * _FAR_RATIO)
        if target > far[-1] * (1 + 1e-12):
            far.append(target)
    window["hi"] = max(_frequency_window(recs, guard, far[-1])[1], f_limit if math.isfinite(f_limit) else 0.0)
    solves[:] = [0, _MAX_FAR_SOLVES]
    stage[0] = "far"
    try:
        return _search(problem, us, recs, guard, origins, far, amplitude_max, accept, frequency_of,
                       monitor, settled)
    except PinnedFailure as err:
        far_error = str(err)
        log.debug("far jump from %.4g: %s", frontier, far_error)
    ladder = problem.harmonic_landing
    if ladder is not None:
        try:
            solves[:] = [0, MAX_LADDERS]
            stage[0] = "harmonics"
            u, nit, hist, rec, t, target = harmonic_search(
                ladder, guard, far, amplitude_max, newton_tol, max_newton, admissible, accept, frequency_of,
                monitor, problem, f_ceiling)
            return u, nit, hist, rec, t, target, guard.frontier_index
        except PinnedFailure as err:
            far_error += f"; in the harmonics: {err}"
    beyond = ""
    window_near = window["hi"]
    if far[-1] >= amplitude_max * (1 - 1e-12):
        stage[0] = "above the bound"
        beyond, down = _beyond_bound(problem, us, recs, guard, origins, amplitude_max, accept, frequency_of,
                                     monitor, settled, window, solves, f_limit, descend)
        if down is not None:
            return down
    homotopy = problem.homotopy_landing
    if homotopy is not None:
        window["hi"] = window_near  # the far search's window, not the one above the bound
        solves[:] = [0, MAX_TARGETS + MAX_FAR_TARGETS]  # one acceptance per homotopy
        stage[0] = "homotopy"
        try:
            u, nit, hist, rec, t, target = homotopy_search(
                homotopy, guard, far, amplitude_max, accept, frequency_of, monitor, problem, tol=newton_tol,
                max_iter=3 * max_newton, admissible=admissible, descend=descend)
            return u, nit, hist, rec, t, target, guard.frontier_index
        except PinnedFailure as err:
            far_error += f"; by a homotopy from the fundamental's family: {err}"
    if problem.with_frequency is not None:
        window["hi"] = f_ceiling * (1.0 + LIMIT_SLACK)
        solves[:] = [0, 2 * MAX_SCAN_TARGETS * N_SCAN_FREQUENCIES]  # two starts
        stage[0] = "frequency scan"
        try:
            u, nit, hist, rec, t, target = frequency_search(problem, guard, us, recs, far, f_ceiling, accept,
                                                            descend)
            return u, nit, hist, rec, t, target, guard.frontier_index
        except PinnedFailure as err:
            far_error += f"; in frequency up to {f_ceiling:.4g} Hz: {err}"
    message = (f"jump from amplitude {frontier:.4g} failed{reason}{last_error}; the far search "
               f"up to {far[-1]:.4g}: {far_error}{beyond}")
    cross = None if beyond else crossing(recs, guard, problem)
    end = FamilyEnd(ended=cross is not None, frontier=frontier, frontier_frequency=f_frontier,
                    searched_to=float(far[-1]), crossing=cross, attempts=tuple(tried),
                    notes=message if cross is not None else turned_back(recs, guard) + message)
    raise FamilyEnded(end)


#: pinned solves of the search above the bound (where the family resumes)
_MAX_BEYOND_SOLVES = 15

#: how far above the frequency window (the frontier's frequency raised along the
#: steepest earlier secant, :func:`_frequency_window`) a landing may lie
_WINDOW_SLACK = 1.3


def _below_limit(accept, f_limit: float):
    """``accept`` that also refuses a landing more than ``LIMIT_SLACK`` above the
    problem's ``family_frequency_limit`` (the first mode's backbone tends to it from
    below far above the gaps; above it lies another mode's branch)."""
    def checked(u0, target, f_pred):
        u, nit, hist, rec, t = accept(u0, target, f_pred)
        f = float(rec.get("frequency", math.nan))
        if math.isfinite(f_limit) and f > f_limit * (1.0 + LIMIT_SLACK):
            raise PinnedFailure(f"landed above the family's frequency limit ({f:.4g} > {f_limit:.4g} Hz)")
        return u, nit, hist, rec, t
    return checked


def _beyond_bound(problem, us, recs, guard, origins, amplitude_max, accept, frequency_of, monitor,
                  settled, window, solves, f_limit: float, descend=None) -> tuple[str, tuple | None]:
    """Where the family resumes above the bound, when the searches, capped by the bound,
    found nothing: a tongue can cover the bound, or the searches, started from the
    family below a stretch of tongues, missed the family at the bound, which a landing
    above it reaches by following its branch back down (``descend(u, tangent, amplitude,
    amplitude_max)``, as :func:`jump` takes it). Up to twice the bound in steps of
    _FAR_RATIO, landings at most ``LIMIT_SLACK`` above ``f_limit``
    (:func:`_below_limit`); a landing whose branch does not come down to the bound on
    the family (another orbit with the fundamental's majority, which folds back above
    the bound) does not end the search. Returns (the sentence that says where the family
    resumes, or "" when nothing lands there; the jump's tuple at the bound, or None)."""
    above = [amplitude_max * _FAR_RATIO ** i for i in range(1, 8)]
    window["hi"] = max(window["hi"], _frequency_window(recs, guard, above[-1])[1])
    solves[:] = [0, _MAX_BEYOND_SOLVES]
    check = _below_limit(accept, f_limit)
    seen = {}

    def within_reach(rec: dict, amplitude: float, what: str) -> None:
        # the family's reach from its own rise (not widened to the frequency limit): a
        # branch far above it with the fundamental's majority is another mode's
        f = float(rec.get("frequency", math.nan))
        reach = _WINDOW_SLACK * _frequency_window(recs, guard, amplitude)[1]
        if math.isfinite(f) and math.isfinite(reach) and f > reach:
            raise PinnedFailure(f"{what} at {amplitude:.4g} lies at {f:.4g} Hz, above the family's reach "
                                f"there ({reach:.4g} Hz from its steepest rise): another mode's branch")

    def connected(u0, target, f_pred):
        u, nit, hist, rec, t = check(u0, target, f_pred)
        within_reach(rec, target, "the landing")
        first = "first" not in seen
        if first:
            seen["first"] = (rec, target)
        if descend is not None:
            down = descend(u, t, target, amplitude_max)
            if down is None:
                raise PinnedFailure(f"the branch through the landing at {target:.4g} does not come down to "
                                    "the bound on the family")
            try:
                within_reach(down[3], amplitude_max, "the branch through the landing comes down to the bound")
            except PinnedFailure:
                if first:  # not where the family resumes either
                    del seen["first"]
                raise
            seen["down"] = down
        return u, nit, hist, rec, t

    try:
        found = _search(problem, us, recs, guard, origins, above, above[-1], connected, frequency_of, monitor,
                        settled)
    except PinnedFailure:
        found = None
    if "first" not in seen:
        return "", None
    rec, target = seen["first"]
    sentence = (f"; the family resumes above the bound, at amplitude {target:.4g} "
                f"({rec.get('frequency', math.nan):.4g} Hz): the bound lies inside a tongue (a run with its "
                f"bound above {target:.4g} can pass it)")
    if found is None or "down" not in seen:
        return sentence, None
    return sentence, (*seen["down"], amplitude_max, found[-1])


def _search(problem, us, recs, guard, origins, targets, amplitude_max, accept, frequency_of, monitor,
            settled: set):
    """Pinned solves from each origin at each target (increasing) from each predictor,
    until one lands (returns the jump's tuple); raises _Exhausted when the budget runs
    out, else PinnedFailure with the last solve's reason. Attempts (origin, target,
    predictor) in ``settled`` are skipped; those that land off the family are added."""
    last_error = "no attempt"
    for origin in origins:
        A_o = float(recs[origin]["amplitude"])
        for target in targets:
            if target <= A_o * (1 + 1e-12):
                continue
            for name, u0 in _predictors(problem, us, recs, guard, origin, target, amplitude_max):
                key = (origin, target, name)
                if key in settled:
                    continue
                try:
                    f_pred = problem.frequency_of(u0) if frequency_of is not None else \
                        monitor(problem, u0).get("frequency", math.nan)
                    u, nit, hist, rec, t = accept(u0, target, f_pred)
                    return u, nit, hist, rec, t, target, origin
                except _Exhausted:
                    raise _Exhausted(last_error) from None
                except _Outside as err:  # no solve tried: keep the last solve's reason
                    if last_error == "no attempt":
                        last_error = str(err)
                except _OffFamily as err:
                    settled.add(key)
                    last_error = str(err)
                except (PinnedFailure, ArithmeticError, ValueError) as err:
                    last_error = str(err)
                log.debug("jump attempt from %d (%.4g) to %.4g by the %s predictor: %s", origin, A_o, target,
                          name, last_error)
    raise PinnedFailure(last_error)


def _frequency_window(recs, guard, top: float) -> tuple[float, float]:
    """(f_lo, f_hi): the frontier's frequency, and the highest frequency the family can
    have at amplitude ``top`` (the largest target of a jump), extrapolated linearly in the amplitude with the
    steepest secant from an earlier family point to the frontier (a backbone that rises
    steeply, as a massive DOF held by a clearance, reaches far above the frontier's
    frequency within a small amplitude step; the last two family points alone can sit on
    a fold at the tongue's foot and see no rise at all); the frontier's frequency both
    times where no secant rises."""
    f0 = float(recs[guard.frontier_index].get("frequency", math.nan))
    a0 = float(recs[guard.frontier_index]["amplitude"])
    if not math.isfinite(f0):
        return f0, f0
    slope = 0.0
    for i in guard.clean:
        a1, f1 = float(recs[i]["amplitude"]), float(recs[i].get("frequency", math.nan))
        # secants over at least 2 % of the amplitude (shorter ones near a fold are noise)
        if a1 <= a0 * (1.0 - 0.02) and math.isfinite(f1) and f0 > f1:
            slope = max(slope, (f0 - f1) / (a0 - a1))
    return f0, f0 + slope * max(top - a0, 0.0)


def _predictors(problem, us, recs, guard, origin: int, target: float, amplitude_max: float):
    """Starts of a jump's pinned solve at ``target`` from the family point ``origin``, in
    order: the problem's family predictor (along an auxiliary low-harmonic branch), the
    polynomial extrapolation through the last frontier points, and the origin scaled to
    the target amplitude (``problem.scaled_state``: the homogeneous limit far above the
    gap). Yields (name, u0); each is tried until one lands."""
    A_o = float(recs[origin]["amplitude"])
    u_o = us[origin]
    predictor = problem.family_predictor
    if predictor is not None:
        try:
            yield "family", predictor(u_o, A_o, target, amplitude_max)
        except (ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError):
            pass
    clean = [i for i in guard.clean if i <= origin]
    if clean:
        yield "extrapolated", _extrapolated(us, recs, clean, target)
    scaled = problem.scaled_state
    if scaled is not None and A_o > 0:
        yield "scaled", scaled(u_o, target / A_o)
