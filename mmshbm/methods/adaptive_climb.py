"""H per point of a backbone to a tolerance, one point after the other along the branch:
the rules of :mod:`mmshbm.methods.adaptive` (steps 2–5 of its docstring), with what the
point before it on the family front found.

The H a stiff contact needs changes slowly along a branch (it is set by how much faster
than the orbit the contact rings), and so do the harmonics above H that a zero-padded
start leaves out. So a point of the family front in contact

* **starts at the rung its predecessor decided on** (the front point before it, in
  contact: the H it kept, or the H below where that was extrapolated at the cap; the
  start H where ``tol`` was out of its reach, which is judged at a point's first rung):
  where that is H* > ``start_harmonics``, the point is solved at H* and 2H* first instead
  of climbing H = start, 2·start, … to it;
  the rung below is tried where the estimate predicted there meets ``tol`` (the estimate
  at H* times the contraction per doubling the predecessor measured between H*/2 and
  H*, at least ``contraction``, the weakest counted as converging): H*/2 is kept where
  its estimate meets ``tol`` and the pair above it, (H*, 2H*), contracts (its
  confirmation, step 4, costs nothing more), and so on down; otherwise the climb goes on
  from H* by the rules of step 3 (where a point goes to the cap or out of reach from H*,
  the contraction it is credited is measured on the rung below, solved then: the
  cheapest solve of the point);
* **is solved at a higher H from its own coefficients padded with zeros**, and where that
  fails (a stiff contact whose harmonics above H are not small; the pair is then not
  tried so again on the branch, as in :func:`mmshbm.results.point_errors.raise_point`),
  **from its predecessor's solution at that H** with this point's amplitude pinned (the
  continuation's corrector from the neighbouring point: it carries the harmonics the
  padding leaves out), accepted where its change of frequency from H is at most
  ``SEED_CHANGE`` times the predecessor's (else it is another orbit at the amplitude,
  which the predecessor's start led to);
  only where both fail do the √2 steps of ``raise_point`` follow.

Points off the front and points without contact force get one estimate at the start H,
as in :mod:`mmshbm.methods.adaptive`. A point off the front in contact (an excursion into
an internal-resonance tongue: no part of the backbone's contract, which
:meth:`~mmshbm.Branch.frequency_at` reads on the front) is solved at 2H from its padded
start (tried even where the pair failed on the branch: one solve of at most
``DIRECT_ITERATIONS``), and where that fails from the 2H solution of the excursion's last
point with an estimate, its amplitude pinned and checked by ``SEED_CHANGE`` as above (a
start from another point of a tongue otherwise lands on other orbits); it never takes the
√2 steps, which cost about two pinned solves per step. Where neither converges its
estimate is NaN and ``records["error_not_estimated"]`` is 1 there. The memory of the
failed pairs is filled as before, so the front points take the same solves.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["refine_points_along", "SEED_CHANGE", "FASTEST", "ASSUMED_CONTRACTION"]

#: the fastest contraction of an estimate per doubling of H that a point is credited with
#: (rate 6; a stiff contact's points just past grazing were measured contracting 28-fold
#: once H resolves the contact time): a point whose estimate exceeds ``tol`` by more than
#: FASTEST ** (the doublings the cap still allows) cannot meet it below the cap and is left
#: where it is
FASTEST = 64.0
#: the contraction per doubling credited to a point at the cap whose last doubling was not
#: measured (rate 2, the estimator's own)
ASSUMED_CONTRACTION = 4.0

#: a solve started from the predecessor's solution is this point refined where its change
#: of frequency from H to H2 is at most this many times the predecessor's (the truncation's
#: change varies slowly along a branch; a larger change is another orbit at the amplitude)
SEED_CHANGE = 4.0


class _Point:
    """One point's solves: ``known`` H -> (scaled unknowns, frequency Hz); ``estimate``
    H -> the estimate at H (from the solve at 2H; NaN where that failed)."""

    def __init__(self, H: int, u: np.ndarray, f: float, amplitude: float, free: bool = False,
                 off: bool = False):
        self.known = {int(H): (np.asarray(u, dtype=float), float(f))}
        self.estimate: dict[int, float] = {}
        self.amplitude = float(amplitude)
        #: no contact force: the orbit is exact at every H, its harmonics above H are zero, so
        #: the padded start is the solution whatever failed on the branch's other points
        self.free = bool(free)
        #: off the family front, in contact: solved from its padded start and its
        #: predecessor's solution only, never by the √2 steps (module docstring)
        self.off = bool(off)


class _Solves:
    """The solves of the points of one branch, from the predecessor's harmonics where known."""

    def __init__(self, ladder, factor: float, tol: float = 1e-10):
        self.ladder, self.factor, self.tol = ladder, factor, tol
        self.solves = 0

    def at(self, p: _Point, H2: int, before: _Point | None) -> bool:
        """Solve ``p`` at ``H2`` from its highest known H below (module docstring); whether
        it converged."""
        from ..core.pinned import PinnedFailure, solve_at_amplitude
        from ..results.point_errors import DIRECT_ITERATIONS, STEP, pad, raise_point

        if H2 in p.known:
            return True
        H = max(h for h in p.known if h < H2)
        u, f = p.known[H]
        s2 = self.ladder.at(H2)
        errors = (PinnedFailure, ArithmeticError, ValueError, np.linalg.LinAlgError)
        pair = (H, H2)
        u2 = None

        def solve(solver, start):
            self.solves += 1
            try:
                return solve_at_amplitude(solver, start, p.amplitude, tol=self.tol,
                                          max_iter=DIRECT_ITERATIONS)[0]
            except errors:
                return None

        s = self.ladder.at(H)
        if p.free or p.off or pair not in self.ladder.stepped or STEP * H >= H2:
            u2 = solve(s2, pad(s, u, s2))  # the point's own start, padded
            if u2 is None and not p.free:
                self.ladder.stepped.add(pair)
        if u2 is None and before is not None and H in before.known and H2 in before.known:
            u2 = solve(s2, before.known[H2][0])  # the predecessor's solution at H2, this amplitude pinned
            if u2 is not None:
                f_b, f2_b = before.known[H][1], before.known[H2][1]
                f2 = float(s2.unpack(u2)[1]) / (2 * math.pi)
                if abs(f2 - f) > SEED_CHANGE * abs(f2_b - f_b) + 1e-12 * abs(f):
                    u2 = None  # another orbit at this amplitude, not this point refined
        if u2 is None and p.off:
            return False  # no cheap solve at H2: the point's estimate is NaN, flagged
        if u2 is None:
            self.solves += 1
            try:
                u2 = raise_point(self.ladder, H, u, p.amplitude, H2, self.tol)
            except errors:
                return False
        p.known[H2] = (u2, float(s2.unpack(u2)[1]) / (2 * math.pi))  # Ω (rad/s): the monitor's frequency
        return True

    def estimate(self, p: _Point, H: int, before: _Point | None) -> float:
        """The estimate of ``p`` at H (solving it at 2H; NaN where that fails)."""
        if H not in p.estimate:
            e = math.nan
            if H in p.known and self.at(p, 2 * H, before):
                f, f2 = p.known[H][1], p.known[2 * H][1]
                e = self.factor * abs(f2 - f) / abs(f2)
            p.estimate[H] = e
        return p.estimate[H]


def refine_points_along(base, tol: float, start_harmonics: int, max_harmonics: int, patience: int,
                        contraction: float, confirm: bool):
    """H, state, frequency, estimate and flags of every point of ``base`` (module
    docstring; the options as in :func:`mmshbm.methods.adaptive.backbone_to_tolerance`).
    Returns (ladder, H, states, frequency, estimate, (extrapolated, confirmed), the most
    estimates one point needed, the pinned solves tried)."""
    from ..results.point_errors import SolverLadder, error_factor

    n = len(base)
    ladder = SolverLadder(base)
    solves = _Solves(ladder, error_factor(2.0))
    H = np.full(n, start_harmonics, dtype=int)
    states = [np.asarray(u, dtype=float) for u in base.states]
    freq = np.asarray(base.frequency, dtype=float).copy()
    amp = np.asarray(base.amplitude, dtype=float)
    err = np.full(n, np.nan)
    extrapolated = np.zeros(n, dtype=np.int8)
    confirmed = np.zeros(n, dtype=np.int8)  # 1: the next pair contracted, or no contact force
    touching = np.asarray(base.contact_force_max, dtype=float) > 0
    confirmed[~touching] = 1
    on_front = np.zeros(n, dtype=bool)
    on_front[np.asarray(base.family_front(), dtype=int)] = True
    rungs = [start_harmonics]
    while 2 * rungs[-1] <= max_harmonics:
        rungs.append(2 * rungs[-1])
    before: _Point | None = None  # the last front point in contact
    before_off: _Point | None = None  # the last point in contact of this excursion off the front
    unestimated = np.zeros(n, dtype=np.int8)  # 1: off the front, in contact, no cheap solve at 2H
    kept_before = start_harmonics  # the rung the predecessor decided on
    most = 0
    for i in range(n):
        a = float(amp[i])
        if not (a > 0 and math.isfinite(a) and math.isfinite(freq[i])):
            continue
        off = bool(touching[i] and not on_front[i])
        if on_front[i]:
            before_off = None
        p = _Point(start_harmonics, states[i], freq[i], a, free=not touching[i], off=off)
        climbs = bool(on_front[i] and touching[i])
        first = start_harmonics
        if climbs and kept_before > start_harmonics and len(rungs) > 2:
            first = max(r for r in rungs[:-1] if r <= kept_before)
        seed_from = before if climbs else before_off if off else None
        h, e, flag, conf, out = _climb(p, first, solves, seed_from, tol, max_harmonics,
                                       patience, contraction, confirm and climbs, bool(on_front[i]))
        most = max(most, len(p.estimate))
        if h in p.known:
            states[i], freq[i] = p.known[h]
        H[i], err[i], extrapolated[i] = h, e, flag
        if conf:
            confirmed[i] = 1
        if off:
            if math.isfinite(e):
                before_off = p
            else:
                unestimated[i] = 1
        if climbs:  # the rung of its last decision (the one below an extrapolated H); none out of reach
            before, kept_before = p, (start_harmonics if out else h // 2 if flag else h)
    return ladder, H, states, freq, err, (extrapolated, confirmed, unestimated), most, solves.solves


def _predicted_below(e: float, h: int, before: _Point | None, contraction: float) -> float:
    """The estimate a point with the estimate ``e`` at ``h`` can be expected to have at h/2:
    ``e`` times the contraction per doubling its predecessor measured between h/2 and h,
    at least ``contraction`` (the weakest that counts as converging; NaN for a NaN ``e``)."""
    c = contraction
    if before is not None:
        e_low, e_at = before.estimate.get(h // 2, math.nan), before.estimate.get(h, math.nan)
        if e_low > 0 and e_at > 0:
            c = max(c, e_low / e_at)
    return e * c


def _climb(p: _Point, first: int, solves: _Solves, seed_from, tol, max_harmonics, patience, contraction,
           confirm: bool, raise_: bool):
    """The rules of :mod:`mmshbm.methods.adaptive` for one point from the rung ``first``
    (module docstring): (H kept, its estimate, extrapolated 0/1, confirmed, out of reach)."""
    est = lambda h: solves.estimate(p, h, seed_from)  # noqa: E731
    h = first
    if first > min(p.known):
        if not solves.at(p, first, seed_from):  # no start there: climb from the start H
            h = min(p.known)
        else:
            est(h)
            down = h
            while down // 2 >= min(p.known) and _predicted_below(p.estimate[down], down, seed_from,
                                                                 contraction) <= tol:
                low = down // 2  # the rung below may meet tol: tried
                if not solves.at(p, low, seed_from):
                    break
                e_low = est(low)
                f_low, f, f2 = p.known[low][1], p.known[down][1], p.known[2 * down][1]
                if not (e_low <= tol and abs(f2 - f) < abs(f - f_low)):
                    break
                down = low
            if down < h:
                return down, p.estimate[down], 0, True, False
    last, stalls, held = math.inf, 0, None
    ratio = math.nan

    def measured(h, e):  # a climb from a predecessor's rung measures its first contraction on demand
        if h // 2 >= min(p.known) and solves.at(p, h // 2, seed_from):
            e_low = est(h // 2)
            if math.isfinite(e_low):
                return e_low / e
        return math.nan

    while True:
        e = est(h)
        if held is not None:  # a confirmation: the pair above the one that met tol
            h0, e0 = held
            held = None
            if math.isfinite(e) and e < e0:  # it contracts: the lower pair was asymptotic
                return h0, e0, 0, True, False
            if not math.isfinite(e):  # no estimate above: the lower one stands, unconfirmed
                return h0, e0, 0, False, False
            last = math.inf  # pre-asymptotic pair: the point goes on from 2H, afresh
        if not math.isfinite(e):
            return h, e, 0, False, False
        if e <= tol:
            if confirm and 4 * h <= max_harmonics:
                held = (h, e)
                h *= 2
                continue
            return h, e, 0, False, False
        ratio = last / e if math.isfinite(last) else math.nan
        stalls = 0 if e * contraction <= last else stalls + 1
        last = e
        left = math.floor(math.log2(max_harmonics / h) + 1e-9)  # the doublings the cap allows
        if not raise_ or stalls >= patience or left < 1:
            return h, e, 0, False, False
        top = e > tol * FASTEST ** left or 4 * h > max_harmonics
        if top and not math.isfinite(ratio) and h == first and h > min(p.known):
            ratio = measured(h, e)
        if e > tol * FASTEST ** left:  # out of reach: the finer solve is the better point
            c = min(max(ratio, 1.0), FASTEST) if math.isfinite(ratio) else ASSUMED_CONTRACTION
            return 2 * h, e / c, 1, False, True
        h *= 2
        if 2 * h > max_harmonics:  # the top: no solve above the cap, the estimate extrapolated
            c = ratio if math.isfinite(ratio) else ASSUMED_CONTRACTION
            return h, e / min(max(c, ASSUMED_CONTRACTION), FASTEST), 1, False, False
