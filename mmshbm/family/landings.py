"""The jumps' last-resort searches, after the near and far searches from the branch below:
the orbit continued in the harmonics from a low-harmonic family (:func:`harmonic_search`),
the orbit reached by a homotopy from the fundamental's family (:func:`homotopy_search`)
and, last, the family's upper side of a tongue found by a scan in frequency
(:func:`frequency_search`).

The homotopy search:

Where a backbone folds back without an internal resonance taking the energy (the turn is
the truncation's or a light DOF's rattling stiffens the orbit past the family's limit),
the starting mode's family resumes above the fold, often at a lower frequency. No
predictor taken from the branch below converges to it; the problem's
``homotopy_landing(A, A_max, tol=, max_iter=, admissible=) -> (u, f_start)`` reaches it
from the orbit of the family of the fundamental alone at the same amplitude
(:mod:`mmshbm.family.homotopy`). A landing counts as any other (``accept``: on the family,
in the frequency window) and, since the homotopy continues the fundamental family's
orbit, within ``_NEAR`` of that orbit's frequency ``f_start`` — a curve that wandered off
to another mode's orbit lands far from it.
"""

from __future__ import annotations

import itertools
import logging
import math

import numpy as np

from ..core.pinned import PinnedFailure, StartOutside

log = logging.getLogger(__name__)

#: relative margin above the frequency bound within which a landing of the harmonic
#: search (the problem's ``family_frequency_ceiling``) or above the bound (its
#: ``family_frequency_limit``) is still accepted: rigid stops stiffen the structure at
#: most to the frequency with every contact DOF held
LIMIT_SLACK = 0.01

#: targets of the harmonic search (each a ladder of pinned solves from the low H to H)
MAX_LADDERS = 8


def harmonic_search(ladder, guard, targets, amplitude_max, newton_tol, max_newton, admissible, accept,
                     frequency_of, monitor, problem, f_ceiling: float) -> tuple:
    """The last resort of a jump: the starting mode's orbit at each target above the
    frontier (increasing, at most ``MAX_LADDERS``) continued in the harmonics from a
    low-harmonic family (``problem.harmonic_landing``), which reaches orbits that no
    predictor taken from the family below a tongue converges to. The ladder must start
    on the family (the fundamental's share at its low H at least ``family_share``); its
    orbit at H is then accepted as any other landing (``accept``: on the family, in the
    frequency window) that lies at most ``LIMIT_SLACK`` above ``f_ceiling``, the problem's
    ``family_frequency_ceiling`` (the frequency with every contact DOF held; not the
    zero-gap limit of one one-sided contact, 2/(1/f_open + 1/f_held), which is exact for
    one DOF only: above a 2:1 tongue a chain's first-mode orbit lies well above it,
    docs/resonances.md). Returns (u, iterations, history, record, tangent, target); raises
    PinnedFailure with the last reason."""
    last_error = "no attempt"
    tried = 0
    for target in targets:
        if target <= float(guard.frontier) * (1 + 1e-12):
            continue
        if tried >= MAX_LADDERS:
            break
        tried += 1
        for fundamental in (False, True):
            found = _ladder_landing(ladder, guard, target, amplitude_max, newton_tol, max_newton, admissible,
                                    accept, frequency_of, monitor, problem, f_ceiling, fundamental)
            if isinstance(found, str):
                if found:
                    last_error = found
                continue
            return (*found, target)
    raise PinnedFailure(last_error)


def _ladder_landing(ladder, guard, target, amplitude_max, newton_tol, max_newton, admissible, accept,
                    frequency_of, monitor, problem, f_ceiling: float, fundamental: bool) -> tuple | str:
    """One ladder's landing at ``target``: (u, iterations, history, record, tangent), or
    the reason it failed ("" where the problem has no ladder from the fundamental's
    family apart from its first)."""
    try:
        start = ladder(target, amplitude_max, tol=newton_tol, max_iter=3 * max_newton, admissible=admissible,
                       fundamental=fundamental)
        if start is None:
            return ""
        u0, share_ref = start
        if share_ref < guard.family_share:
            raise PinnedFailure(f"the low-harmonic orbit at {target:.4g} is off the family "
                                f"(fundamental share {share_ref:.3f})")
        f_pred = frequency_of(u0) if frequency_of is not None else \
            monitor(problem, u0).get("frequency", math.nan)
        u, nit, hist, rec, t = accept(u0, target, f_pred)
        f = float(rec.get("frequency", math.nan))
        if f > f_ceiling * (1.0 + LIMIT_SLACK):
            raise PinnedFailure(f"landed above the family's frequency ceiling ({f:.4g} > {f_ceiling:.4g} Hz)")
    except (PinnedFailure, ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError) as err:
        log.debug("harmonic ladder at %.4g: %s", target, err)
        return str(err)
    return u, nit, hist, rec, t


#: homotopies run at the targets nearest the frontier (increasing; a target whose start
#: lies outside the jump's trust region runs none), then at most MAX_FAR_TARGETS more
#: spread over the rest of the targets below the bound: next to a fold the homotopy's
#: curve can turn back in s for every target near the frontier while it reaches the
#: family farther up. Each takes up to a few hundred steps, so the search costs at most
#: a few seconds where every evaluation is expensive
MAX_TARGETS = 4
MAX_FAR_TARGETS = 3
#: largest relative distance of a landing from the frequency of the fundamental family's
#: orbit it started from (the harmonics move a backbone by a few percent; the jumps'
#: predictors are held to the same 15 %)
_NEAR = 0.15


def homotopy_search(landing, guard, targets, amplitude_max: float, accept, frequency_of, monitor, problem, *,
                    tol: float, max_iter: int, admissible=None, descend=None) -> tuple:
    """Land at the first target above the frontier where ``landing`` converges onto the
    family near its start's frequency: :data:`MAX_TARGETS` homotopies at the targets
    nearest the frontier, then at most :data:`MAX_FAR_TARGETS` at targets spread over the
    rest below the bound. A landing at a spread target counts only where its branch,
    followed back down (``descend(u, tangent, amplitude, amplitude_to)``, None when it
    leaves the family or turns back first), reaches the frontier's amplitude on the
    family: the family resumes above a fold of the branch below, not somewhere apart.
    Without ``descend`` no spread target runs. Returns (u, iterations, history, record,
    tangent, target); raises PinnedFailure with the last reason."""
    errors = ["no attempt"]
    frontier = float(guard.frontier)

    def attempt(target, spread: bool = False) -> tuple | None:
        """The landing at ``target``, or None (its reason kept); raises StartOutside
        when the target's start lies outside the trust region (no homotopy run)."""
        try:
            u0, f_start = landing(target, amplitude_max, tol=tol, max_iter=max_iter, admissible=admissible)
            f0 = (frequency_of(u0) if frequency_of is not None
                  else float(monitor(problem, u0).get("frequency", math.nan)))
            if math.isfinite(f_start) and not abs(f0 - f_start) <= _NEAR * f_start:
                raise PinnedFailure(f"the homotopy ended at {f0:.4g} Hz, far from the fundamental family's "
                                    f"{f_start:.4g} Hz")
            u, nit, hist, rec, t = accept(u0, target, f0)
            if spread and descend(u, t, target, frontier) is None:
                raise PinnedFailure(f"the branch through the landing at {target:.4g} does not come down "
                                    f"to the frontier's amplitude {frontier:.4g} on the family")
            return u, nit, hist, rec, t, target
        except StartOutside:
            raise
        except (PinnedFailure, ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError) as err:
            errors.append(str(err))
            log.debug("homotopy landing at %.4g: %s", target, err)
            return None

    above = [t for t in targets if t > float(guard.frontier) * (1 + 1e-12)]
    tried, nearest = 0, len(above)
    for position, target in enumerate(above):
        if tried >= MAX_TARGETS:
            nearest = position
            break
        try:
            found = attempt(target)
        except StartOutside as err:
            errors.append(str(err))
            continue
        tried += 1
        if found is not None:
            return found
    # the bound is not among the spread targets: a landing there has no family above it
    # to continue along, and one that does not come down either is a lone orbit
    rest = [t for t in above[nearest:] if t < amplitude_max * (1 - 1e-9)] if descend is not None else []
    picks = sorted({round(k * (len(rest) - 1) / MAX_FAR_TARGETS) for k in range(1, MAX_FAR_TARGETS + 1)}
                   ) if rest else []
    for target in (rest[i] for i in picks):
        try:
            found = attempt(target, spread=True)
        except StartOutside as err:
            errors.append(str(err))
            continue
        if found is not None:
            return found
    raise PinnedFailure(errors[-1])


#: targets of the frequency scan (the first above the frontier) and frequencies per target
MAX_SCAN_TARGETS = 3
N_SCAN_FREQUENCIES = 12


def frequency_search(problem, guard, us: list, recs: list, targets, f_ceiling: float, accept,
                     descend) -> tuple:
    """The family on the far side of a tongue, at a frequency no predictor reaches.

    Where the starting mode's orbit climbs a k:1 tongue with a higher mode (kΩ ≈ ω_j)
    and never comes back to the fundamental's majority, the family goes on along the
    tongue's other side: orbits at the same amplitudes, well above the tongue's
    frequency (on chains 25–40 % above it, below the frequency with every contact DOF
    held), which coexist with the tongue down to the frontier's amplitude. Newton finds
    them from the problem's shapes at each target (``problem.scan_starts``: e.g. the
    linear mode's, since that side keeps the fundamental's majority, and the frontier's
    scaled) with the frequency set (``problem.with_frequency``) on a geometric grid from
    just above the frontier's frequency to ``f_ceiling``. A landing counts when
    ``accept`` takes it (on the family, in the trust region), it lies above the
    frontier's frequency and at most ``LIMIT_SLACK`` above the ceiling, the starting
    mode leads its fundamental (``problem.leads_fundamental``: not another mode's
    backbone), and its branch, followed back down (``descend``), reaches the frontier's
    amplitude on the family (the tongue's other side, not an orbit apart). Returns (u,
    iterations, history, record, tangent, target); raises PinnedFailure with the last
    reason."""
    at_frequency, leads, shapes = problem.with_frequency, problem.leads_fundamental, problem.scan_starts
    if at_frequency is None or leads is None or shapes is None or descend is None:
        raise PinnedFailure("not offered")
    i = guard.frontier_index
    frontier = float(guard.frontier)
    f_front = float(recs[i].get("frequency", math.nan))
    if not (math.isfinite(f_front) and math.isfinite(f_ceiling) and f_ceiling > f_front):
        raise PinnedFailure("no frequencies between the frontier's and the ceiling")
    last_error = "no landing"
    above = [t for t in targets if t > frontier * (1 + 1e-12)][:MAX_SCAN_TARGETS]
    grid = np.geomspace(f_front * 1.02, f_ceiling, N_SCAN_FREQUENCIES)
    for target in above:
        for start, f_try in itertools.product(shapes(us[i], frontier, target), grid):
            try:
                u, nit, hist, rec, t = accept(at_frequency(start, float(f_try)), target, math.nan)
                f = float(rec.get("frequency", math.nan))
                if not f_front < f <= f_ceiling * (1.0 + LIMIT_SLACK):
                    raise PinnedFailure(f"landed at {f:.4g} Hz, outside ({f_front:.4g}, {f_ceiling:.4g}] Hz")
                if not leads(u):
                    raise PinnedFailure(f"landed on another mode's backbone at {f:.4g} Hz")
                if descend(u, t, target, frontier) is None:
                    raise PinnedFailure(f"the branch through the landing at {f:.4g} Hz does not come down "
                                        f"to the frontier's amplitude {frontier:.4g} on the family")
                return u, nit, hist, rec, t, target
            except (PinnedFailure, ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError) as err:
                last_error = str(err)
                log.debug("frequency scan at %.4g, %.4g Hz: %s", target, f_try, err)
    raise PinnedFailure(last_error)
