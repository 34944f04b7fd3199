"""Following the family of a nonlinear mode: the event plug-in of the driver.

:class:`FamilyFollower` implements :class:`mmshbm.core.events.BranchEvents` with the
bookkeeping of :class:`mmshbm.family.stages.FamilyGuard`: it marks every point on or off
the starting mode's family (``record["on_family"]``) and asks for a jump
(:func:`mmshbm.family.stages.jump`) when the branch has left the family for good (an
excursion, a loop), when a tongue climbs to a bound, or when the step size fails at
``ds_min``. A jump lands beyond the family's frontier; the family below the landing is
filled back down by plain path following (:func:`_backfill`) and joins the branch in
increasing amplitude, the first point marked by a ``"jump"`` special point. Its options
are :class:`mmshbm.core.options.FamilyOptions`
(``ContinuationOptions(follow="family", ...)`` builds them).
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable

import numpy as np

from ..core.events import NoEvents, Relocation, RelocationFailed
from ..core.options import ContinuationOptions, FamilyOptions
from ..core.pinned import PinnedFailure
from ..core.special_points import SpecialPoint
from ..core.status import Status
from ..core.steps import _pinned_monitor
from .definition import FAMILY_RECORD, family_value, frequency_band, on_family
from .deflation import FamilyStarts, search_beyond
from .end import FamilyEnded
from .guard import FamilyGuard
from .stages import jump

__all__ = ["FamilyFollower", "default_events"]

log = logging.getLogger(__name__)


class FamilyFollower:
    """The driver's event plug-in that keeps a backbone on its starting mode's family.

    Parameters
    ----------
    family : FamilyOptions
        Membership threshold, excursion length, jump step and jump budget.
    options : ContinuationOptions
        The run's options (step control resolved): the jumps' Newton settings, the
        amplitude bound and the options of the backfill.
    follow : callable
        The path follower of the backfill (:func:`mmshbm.core.continuation.continue_branch`).
    starts : FamilyStarts, optional
        The starts of the deflated search (``family.search == "deflated"``); default
        :class:`~mmshbm.family.deflation.ProblemStarts` of the problem.
    """

    def __init__(self, family: FamilyOptions, options: ContinuationOptions, follow: Callable,
                 starts: FamilyStarts | None = None):
        self.family = family
        self.starts = starts
        self.options = options
        self.follow = follow
        self.guard = FamilyGuard(family.family_share, family.max_excursion)
        self.jumps = 0
        self.amplitude_max = float(dict(options.bounds).get("amplitude", (0.0, math.inf))[1])

    def replay(self, records: list, special: list) -> None:
        jumped = {s[1] for s in special if s[0] == "jump"}
        for i, rec in enumerate(records):
            if i in jumped:
                self.guard.jumped(i, rec)
            else:
                self.guard.observe(i, rec)
        self.jumps = sum(1 for s in special if s[0] == "jump")

    def _may_jump(self) -> bool:
        return self.jumps < self.family.max_jumps

    def observe(self, index: int, record: dict) -> str | None:
        guard = self.guard
        if guard.observe(index, record) != "jump" or not self._may_jump():
            return None
        return "loop" if guard.left and guard.away <= self.family.max_excursion else "excursion"

    def at_bound(self, index: int, record: dict) -> str | None:
        self.guard.observe(index, record)
        # reached off the family (a tongue climbing to the bound, or a pending climb
        # locked onto ω_j/k that the bound cut short): not an end of the backbone; jump
        # from the frontier instead
        if not (self.guard.active and self._may_jump()):
            return None
        if record.get("on_family", 1.0) < 0.5 or self.guard.locked_at_bound():
            return "tongue reached the bound"
        return None

    def at_ds_min(self) -> str | None:
        return "ds_min" if self.guard.active and self._may_jump() else None

    def register(self, index: int, record: dict, first: bool) -> None:
        if first:
            self.guard.jumped(index, record)
        else:
            self.guard.observe(index, record)

    def relocate(self, problem, points: list, records: list, reason: str, index: int) -> Relocation:
        """Jump beyond the family's frontier and fill the family back down from the landing
        point (:func:`_backfill`); the points in increasing amplitude, the landing last."""
        opt, guard = self.options, self.guard
        try:
            if self.family.search == "deflated":
                u_j, nit_j, hist_j, rec_j, t_j, target, i_from = search_beyond(
                    problem, guard, points, records, options=self.family, amplitude_max=self.amplitude_max,
                    newton_tol=opt.newton_tol, max_newton=opt.max_newton, monitor=_pinned_monitor,
                    starts=self.starts)
            else:
                u_j, nit_j, hist_j, rec_j, t_j, target, i_from = jump(
                    problem, guard, points, records, step=self.family.jump_step,
                    amplitude_max=self.amplitude_max, newton_tol=opt.newton_tol, max_newton=opt.max_newton,
                    monitor=_pinned_monitor,
                    coexisting=lambda u, t, a, rec: _coexisting(self.follow, problem, u, t, a, rec, opt,
                                                                self.family, self.amplitude_max),
                    descend=lambda u, t, a, a_to: _descend(self.follow, problem, u, t, a, a_to, opt,
                                                           self.family))
        except (FamilyEnded, PinnedFailure) as err:
            along = (_along_path(self.follow, problem, points, records, guard, opt, self.family)
                     if reason in _MOVING and self.family.search == "deflated" else None)
            if along is None:
                if isinstance(err, FamilyEnded):
                    end = err.end
                    raise RelocationFailed(end.detail(), kind=Status.FAMILY_ENDED if end.ended else None,
                                           cause=end) from None
                raise RelocationFailed(str(err)) from None
            u_j, nit_j, hist_j, rec_j, t_j = along
            target, i_from = float(rec_j["amplitude"]), guard.frontier_index
        A_from = float(records[i_from]["amplitude"])
        frontier = float(records[guard.frontier_index]["amplitude"])
        filled = (_backfill(self.follow, problem, u_j, t_j, frontier, target, opt, self.family)
                  if target > frontier * (1 + 1e-9) else [])
        found = filled + [(u_j, nit_j, hist_j, rec_j, t_j)]
        first = found[0][3]
        special = SpecialPoint("jump", index, reason=reason, from_index=i_from, amplitude_from=A_from,
                               amplitude_frontier=frontier, amplitude_to=float(first["amplitude"]),
                               landing_amplitude=float(target),
                               frequency_from=float(records[i_from].get("frequency", math.nan)),
                               frequency_to=float(first.get("frequency", math.nan)))
        terminal = None
        if _outside(found[-1][3], opt.bounds) or target >= self.amplitude_max:
            terminal = Status.bound("amplitude")
        self.jumps += 1
        log.info("jump (%s) from amplitude %.4g to %.4g (landed at %.4g, %d points filled back)", reason,
                 A_from, special.data["amplitude_to"], target, len(filled))
        return Relocation(found, special, terminal)


#: the reasons of a search where the branch itself still goes on (not a step size failure
#: or a tongue at the bound): where the search finds nothing, the path is followed on
_MOVING = ("excursion", "loop")


def _along_path(follow: Callable, problem, us: list, recs: list, guard: FamilyGuard, opt: ContinuationOptions,
                family: FamilyOptions):
    """The first orbit of the family beyond the frontier on the branch itself: the path
    followed on from its last point (plain path following, at most ``max_excursion``
    steps, the tangent from the last secant) to the first point that satisfies the
    definition (:func:`~mmshbm.family.definition.on_family`, the first mode's frequency
    band) above the frontier's amplitude. The last start of a search that found nothing
    from the frontier: a branch that folds back and forth (S-bends) can come back beyond
    the frontier only along itself. Returns (u, iterations, history, record, tangent
    oriented to growing amplitude), or None."""
    if len(us) < 2:
        return None
    frontier = float(recs[guard.frontier_index]["amplitude"])
    band = frequency_band(problem, recs, family.band_slack)
    secant = np.asarray(us[-1]) - np.asarray(us[-2])
    norm = float(np.linalg.norm(secant))
    if not norm > 0:
        return None
    on = dataclasses.replace(opt, max_steps=family.max_excursion, follow="path")
    try:
        res = follow(problem, us[-1], secant / norm, on, catch_interrupt=False)
    except (PinnedFailure, ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError):
        return None
    for i in range(1, len(res.u)):
        rec = {k: v[i] for k, v in res.records.items()}
        if float(rec["amplitude"]) > frontier and on_family(rec, family.family_share, band) is not False:
            tangent = res.u[i] - res.u[i - 1]
            if float(rec["amplitude"]) < float(res.records["amplitude"][i - 1]):
                tangent = -tangent
            tangent /= max(np.linalg.norm(tangent), 1e-300)
            return res.u[i], int(res.newton_iterations[i]), res.residual_histories[i], rec, tangent
    return None


def default_events(options: ContinuationOptions, follow: Callable):
    """The event plug-in ``options`` ask for: a :class:`FamilyFollower` for
    ``follow="family"``, else :class:`~mmshbm.core.events.NoEvents` (plain path following)."""
    family = options.family
    return NoEvents() if family is None else FamilyFollower(family, options, follow)


def _outside(rec: dict, bounds) -> bool:
    for name, (lo, hi) in dict(bounds).items():
        v = rec.get(name)
        if v is not None and (v > hi or v < lo):
            return True
    return False


#: the backfill's target residual of the residual step rule (ContinuationOptions' default)
_BACKFILL_TARGET_RESIDUAL = 1e-3


#: relative frequency difference below which a branch crossing an amplitude passes
#: through a given point there (crossings are interpolated linearly between branch points)
_SAME_ORBIT = 1e-3


def _coexisting(follow: Callable, problem, u, t, landing: float, rec_land: dict, opt: ContinuationOptions,
                family: FamilyOptions, amplitude_max: float) -> bool:
    """Whether the branch through a landing ``u`` (tangent ``t``, oriented to growing
    amplitude) found below a jump's landing (amplitude ``landing``, record ``rec_land``)
    is another orbit's: followed up (plain path following, at most 2·``max_excursion``
    steps) it crosses the landing's amplitude with the fundamental's majority, but never
    through the landing point (the frequency there differs by more than ``_SAME_ORBIT``).
    Two orbits with the fundamental's majority then coexist at that amplitude; the one
    the filtered passage reached continues the family, the other is the side of a tongue
    (it folds back above while the fundamental keeps the majority). False when the
    branch passes through the landing (an S-bend may cross its amplitude first
    elsewhere), or never crosses it on the family within those steps."""
    f_land = float(rec_land.get("frequency", math.nan))
    if not math.isfinite(f_land):
        return False
    up = dataclasses.replace(
        opt, max_steps=2 * family.max_excursion, follow="path", step_control="auto",
        target_residual=_BACKFILL_TARGET_RESIDUAL, bounds={"amplitude": (0.0, amplitude_max)})
    try:
        res = follow(problem, u, t, up, catch_interrupt=False)
    except (PinnedFailure, ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError):
        return False
    A = np.asarray(res.records.get("amplitude", []), dtype=float)
    f = np.asarray(res.records.get("frequency", np.full(len(A), np.nan)), dtype=float)
    share = res.records.get(FAMILY_RECORD)
    crossed = False
    for i in range(len(A) - 1):
        if (A[i] - landing) * (A[i + 1] - landing) > 0 or A[i] == A[i + 1]:
            continue
        w = (landing - A[i]) / (A[i + 1] - A[i])
        f_x = (1 - w) * f[i] + w * f[i + 1]
        if abs(f_x / f_land - 1.0) <= _SAME_ORBIT:
            return False
        if share is None or (1 - w) * share[i] + w * share[i + 1] >= family.family_share:
            crossed = True
    return crossed


def _backfill(follow: Callable, problem, u, t, frontier: float, landing: float, opt: ContinuationOptions,
              family: FamilyOptions) -> list:
    """The family below a jump's landing point: continued backwards from it (plain path
    following) until it leaves the family (its family measure refined onto
    ``family_share``) or reaches the frontier. Returns the points in increasing amplitude,
    as tuples (u, iterations, history, record, tangent oriented to growing amplitude),
    without the landing point.

    The run's options carry over, except the step rule: the backfill takes the problem's
    own (``step_control="auto"``) with the default ``target_residual``, as it always has
    (a run's explicit step rule or target would change the filled points, and with them
    the branch)."""
    back = dataclasses.replace(
        opt, max_steps=family.max_excursion, follow="path", step_control="auto",
        target_residual=_BACKFILL_TARGET_RESIDUAL,
        bounds={"amplitude": (frontier, landing * (1 + 1e-6)), FAMILY_RECORD: (family.family_share, 2.0)})
    res = follow(problem, u, -t, back, catch_interrupt=False)
    out = []
    for i in range(len(res.u) - 1, 0, -1):
        rec = {k: v[i] for k, v in res.records.items()}
        share = family_value(rec)
        if share is not None and share < family.family_share * (1 - 1e-6):
            continue
        tangent = res.u[i - 1] - res.u[i]
        tangent /= max(np.linalg.norm(tangent), 1e-300)
        out.append((res.u[i], int(res.newton_iterations[i]), res.residual_histories[i], rec, tangent))
    return out


def _descend(follow: Callable, problem, u, t, amplitude: float, amplitude_to: float, opt: ContinuationOptions,
             family: FamilyOptions):
    """The family point at ``amplitude_to`` below a family point ``u`` (amplitude
    ``amplitude``, tangent ``t`` oriented to growing amplitude) found above the bound:
    the branch through it followed back down (plain path following, at most
    ``max_excursion`` steps, the backfill's step rule) onto ``amplitude_to``, where the
    driver refines its end onto the bound. Returns (u, iterations, history, record,
    tangent oriented to growing amplitude) there, or None when the branch leaves the
    family (its family measure below ``family_share``) or turns back first."""
    down = dataclasses.replace(
        opt, max_steps=family.max_excursion, follow="path", step_control="auto",
        target_residual=_BACKFILL_TARGET_RESIDUAL,
        bounds={"amplitude": (amplitude_to, amplitude * (1 + 1e-6)),
                FAMILY_RECORD: (family.family_share, 2.0)})
    try:
        res = follow(problem, u, -t, down, catch_interrupt=False)
    except (PinnedFailure, ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError):
        return None
    if len(res.u) < 2:
        return None
    rec = {k: v[-1] for k, v in res.records.items()}
    share = family_value(rec)
    log.debug("descent from %.4g to %.4g: %s after %d points at %.4g (share %s)", amplitude, amplitude_to,
              res.status, len(res.u), float(rec["amplitude"]), share)
    if abs(float(rec["amplitude"]) / amplitude_to - 1.0) > 1e-6 or (
            share is not None and share < family.family_share):
        return None
    tangent = res.u[-2] - res.u[-1]
    tangent /= max(np.linalg.norm(tangent), 1e-300)
    return res.u[-1], int(res.newton_iterations[-1]), res.residual_histories[-1], rec, tangent
