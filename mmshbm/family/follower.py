"""Following the family of a nonlinear mode: the event plug-in of the driver.

:class:`FamilyFollower` implements :class:`mmshbm.core.events.BranchEvents` with the
bookkeeping of :class:`mmshbm.family.guard.FamilyGuard`: it marks every point on or off
the starting mode's family (``record["on_family"]``) and asks for the search beyond the
family's frontier (:func:`mmshbm.family.deflation.search_beyond`) when the branch has left
the family for good (an excursion, a loop), when a tongue climbs to a bound, or when the
step size fails at ``ds_min``. Where the search finds nothing and the branch itself still
goes on, the path is followed on to the first orbit of the family beyond the frontier
(:func:`_along_path`). The family below the landing is filled back down by plain path
following (:func:`_backfill`) and joins the branch in increasing amplitude, the first
point marked by a ``"jump"`` special point. Its options are
:class:`mmshbm.family.options.FamilyOptions` (``ContinuationOptions(follow="family", ...)``
builds them).
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable

import numpy as np

from ..core.events import NoEvents, Relocation, RelocationFailed
from ..core.options import ContinuationOptions
from ..core.pinned import PinnedFailure
from ..core.special_points import SpecialPoint
from ..core.status import Status
from ..core.steps import _pinned_monitor
from .definition import FAMILY_RECORD, family_value, frequency_band, on_family
from .deflation import FamilyStarts, search_beyond
from .end import FamilyEnded
from .guard import FamilyGuard
from .options import FamilyOptions

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
        The starts of the search beyond a frontier; default the problem's own
        (``problem.family_starts()``) or :class:`~mmshbm.family.deflation.BranchStarts`.
    """

    def __init__(self, family: FamilyOptions, options: ContinuationOptions, follow: Callable,
                 starts: FamilyStarts | None = None):
        self.family = family
        self.starts = starts
        self.options = options
        self.follow = follow
        self.guard = FamilyGuard(family.family_share, family.max_excursion, family)
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
            u_j, nit_j, hist_j, rec_j, t_j, target, i_from = search_beyond(
                problem, guard, points, records, options=self.family, amplitude_max=self.amplitude_max,
                newton_tol=opt.newton_tol, max_newton=opt.max_newton, monitor=_pinned_monitor,
                starts=self.starts)
        except (FamilyEnded, PinnedFailure) as err:
            along = (_along_path(self.follow, problem, points, records, guard, opt, self.family)
                     if reason in _MOVING else None)
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
    family = FamilyOptions.of(options)
    return NoEvents() if family is None else FamilyFollower(family, options, follow)


def _outside(rec: dict, bounds) -> bool:
    for name, (lo, hi) in dict(bounds).items():
        v = rec.get(name)
        if v is not None and (v > hi or v < lo):
            return True
    return False


#: the backfill's target residual of the residual step rule (ContinuationOptions' default)
_BACKFILL_TARGET_RESIDUAL = 1e-3


def _backfill(follow: Callable, problem, u, t, frontier: float, landing: float, opt: ContinuationOptions,
              family: FamilyOptions) -> list:
    """The family below a jump's landing point: continued backwards from it (plain path
    following) until it leaves the family (its family measure refined onto
    ``family_share``), reaches the frontier, or turns back in amplitude (a fold: the
    piece of the family the landing lies on begins there; beyond the fold the path goes
    up again on another orbit of the family). Returns the points in increasing amplitude,
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
    amplitude = np.asarray(res.records["amplitude"], dtype=float)
    end = len(res.u)
    for i in range(1, end):
        if amplitude[i] > amplitude[i - 1]:
            end = i  # the fold lies at point i - 1
            break
    out = []
    for i in range(end - 1, 0, -1):
        rec = {k: v[i] for k, v in res.records.items()}
        share = family_value(rec)
        if share is not None and share < family.family_share * (1 - 1e-6):
            continue
        tangent = res.u[i - 1] - res.u[i]
        tangent /= max(np.linalg.norm(tangent), 1e-300)
        out.append((res.u[i], int(res.newton_iterations[i]), res.residual_histories[i], rec, tangent))
    return out
