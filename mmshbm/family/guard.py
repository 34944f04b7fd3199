"""The family guard: which points of a branch belong to the starting mode's family, and
when the branch must search beyond its frontier (see :mod:`mmshbm.family.follower` for the whole picture and
docs/resonances.md for the definition, :func:`mmshbm.family.definition.on_family`)."""

from __future__ import annotations

import math

from .definition import FAMILY_RECORD, family_value, on_family
from .options import FamilyOptions

__all__ = ["FAMILY_RECORD", "FamilyGuard", "family_value"]

#: relative round-off of the guard's comparisons of amplitude and frequency (a value equal
#: to another within it neither rises nor falls)
_ROUNDOFF = 1e-9


class FamilyGuard:
    """Bookkeeping of the family's frontier along a branch (see the module docstring).

    A point is on the family when the fundamental harmonic carries at least
    ``family_share`` of the kinetic energy (:func:`family_value`), or when it continues the
    family from its frontier without folding: amplitude and frequency still growing,
    the frequency not locked (a *pending* stretch, where higher harmonics hold most of the
    kinetic energy while the backbone keeps rising). A pending stretch that folds back
    (amplitude or frequency turning) or locks its frequency was the climb into a tongue:
    its points
    are marked off the family after the fact and the frontier goes back to where the
    stretch began.

    Parameters
    ----------
    family_share : float
        Share of the kinetic energy in the fundamental harmonic above which a point is
        on the family.
    max_excursion : int
        Steps allowed off the family (or on it below the frontier) before a jump.
    options : FamilyOptions, optional
        The guard's other rules (``loop_drop``, ``reentry_tol``, ``lock_growth``,
        ``lock_frequency``, ``lock_at_bound``, ``origin_windows``); their defaults where
        not given.
    """

    def __init__(self, family_share: float, max_excursion: int, options: FamilyOptions | None = None):
        self.family_share = family_share
        self.max_excursion = max_excursion
        self.options = FamilyOptions() if options is None else options
        self.frontier = -math.inf  # largest amplitude on the family so far
        self.frontier_frequency = math.nan
        self.frontier_index = -1
        self.away = 0  # steps since the frontier last moved
        self.left = False  # the branch left the family since the frontier moved
        self.clean = []  # indices of frontier points (for extrapolation)
        self.shares = {}  # family measure of the frontier points
        self.pending = []  # (index, amplitude, frequency, record) of a pending stretch
        self.active = False  # the problem records the family measure
        self.reentries = []  # (amplitude, frequency) where excursions came back above the frontier

    def observe(self, index: int, rec: dict) -> str | None:
        """Register the accepted point ``index`` with record ``rec``; sets
        ``rec["on_family"]`` (and resets it on the points of a pending stretch that
        turns out to be a tongue) and returns ``"jump"`` when a jump is due, else None."""
        on = on_family(rec, self.family_share)
        if on is None:
            return None
        share = family_value(rec)
        self.active = True
        amplitude = float(rec["amplitude"])
        frequency = float(rec.get("frequency", math.nan))
        if self.pending:
            _, a_last, f_last, _ = self.pending[-1]
            # a fold turns the frequency back, or the amplitude with the frequency no
            # longer rising (a tongue's tip); an amplitude that wavers while the frequency
            # keeps rising is the backbone's own S-bend, not a tongue
            advancing = not frequency < f_last * (1 - _ROUNDOFF) and (
                amplitude >= a_last * (1 - _ROUNDOFF) or frequency > f_last * (1 + _ROUNDOFF))
            if advancing and not self._locked(amplitude, frequency):
                if not on:
                    self.pending.append((index, amplitude, frequency, rec))
                    rec["on_family"] = 1.0
                    return None
                self._confirm()
            else:
                self._revert()
        ahead = amplitude >= self.frontier * (1 - _ROUNDOFF)
        if on and ahead:
            if self.left and self._reentered(amplitude, frequency):
                rec["on_family"] = 0.0
                return "jump"  # back where an earlier excursion came back: a closed loop
            self._advance(index, rec, share)
            return None
        if (not on and ahead and self.away == 0 and not self.left and self.frontier_index >= 0
                and not frequency < self.frontier_frequency * (1 - _ROUNDOFF)):
            self.pending = [(index, amplitude, frequency, rec)]
            rec["on_family"] = 1.0
            return None
        rec["on_family"] = 1.0 if on else 0.0
        self.away += 1
        if not on:
            self.left = True
        elif self.left and amplitude < self.frontier * (1 - self.options.loop_drop):
            return "jump"  # back on the family well below the frontier: a loop
        if self.away > self.max_excursion:
            return "jump"
        return None

    def _reentered(self, amplitude: float, frequency: float) -> bool:
        """Whether an excursion comes back onto the family where an earlier one came back
        (amplitude and frequency within ``reentry_tol``): the branch goes round a closed
        loop, each round nudging the frontier by round-off. Registers the re-entry."""
        tol = self.options.reentry_tol
        for a, f in self.reentries:
            if abs(amplitude - a) <= tol * a and abs(frequency - f) <= tol * f:
                return True
        self.reentries.append((amplitude, frequency))
        return False

    def _advance(self, index: int, rec: dict, share: float) -> None:
        rec["on_family"] = 1.0
        self.frontier = float(rec["amplitude"])
        self.frontier_frequency = float(rec.get("frequency", math.nan))
        self.frontier_index = index
        self.away = 0
        self.left = False
        self.clean.append(index)
        self.shares[index] = float(share)

    def _locked(self, amplitude: float, frequency: float) -> bool:
        _, a0, f0, _ = self.pending[0]
        o = self.options
        return amplitude >= o.lock_growth * a0 and frequency <= f0 * (1 + o.lock_frequency)

    def locked_at_bound(self) -> bool:
        """Whether the pending stretch that reached the amplitude bound is a locked climb
        the bound cut short: grown by at least ``lock_at_bound`` but less than
        ``lock_growth`` (where the lock test itself applies), with the frequency rising
        more slowly than the lock's slope (``lock_frequency`` per ``lock_growth`` − 1 of
        amplitude). Such a stretch is marked off the family (as a tongue's climb that
        locks) and the frontier goes back to where it began."""
        if not self.pending:
            return False
        _, a0, f0, _ = self.pending[0]
        _, a1, f1, _ = self.pending[-1]
        o = self.options
        growth = a1 / a0 - 1.0
        slope = o.lock_frequency / (o.lock_growth - 1.0)
        if not (o.lock_at_bound * a0 <= a1 < o.lock_growth * a0 and f1 <= f0 * (1.0 + slope * growth)):
            return False
        self._revert()
        return True

    def _confirm(self) -> None:
        """The pending stretch came back to a fundamental majority without folding: it is
        the family (its last point becomes the frontier)."""
        for index, _, _, rec in self.pending:
            self._advance(index, rec, family_value(rec))
        self.pending = []

    def _revert(self) -> None:
        """The pending stretch folded or locked: it was a tongue's climb."""
        for _, _, _, rec in self.pending:
            rec["on_family"] = 0.0
        self.away = len(self.pending)
        self.left = True
        self.pending = []

    def jumped(self, index: int, rec: dict) -> None:
        """Register the point a jump landed on (a new frontier)."""
        self.pending = []
        share = family_value(rec)
        self._advance(index, rec, 1.0 if share is None else share)

    def origins(self, amplitudes) -> list[int]:
        """Frontier points to jump from, best first: in each of the amplitude windows
        between consecutive ``origin_windows`` edges (default [0.8, 1], [0.6, 0.8) and
        [0.4, 0.6) times the frontier), the point where the starting mode's share is
        largest (before an internal resonance drew energy from it), then the frontier
        itself. ``amplitudes`` maps a point index to its amplitude."""
        out = []
        edges = (1.0 + 1e-12,) + tuple(self.options.origin_windows)  # the top edge: the frontier itself
        for hi, lo in zip(edges[:-1], edges[1:], strict=False):
            window = [i for i in self.clean if lo * self.frontier <= amplitudes(i) < hi * self.frontier]
            if window:
                best = max(window, key=lambda i: (self.shares[i], i))
                if best not in out:
                    out.append(best)
        if self.frontier_index >= 0 and self.frontier_index not in out:
            out.append(self.frontier_index)
        return out
