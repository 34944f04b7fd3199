"""The options of the family following: every threshold of its decisions, in one object.

:class:`FamilyOptions` is built from a run's
:class:`~mmshbm.core.options.ContinuationOptions` (``follow="family"`` and its family fields) by
:meth:`FamilyOptions.of`. The definition it serves is in
docs/resonances.md and :mod:`mmshbm.family.definition`.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

from .. import _validate as check

__all__ = ["FamilyOptions"]

@dataclass(frozen=True)
class FamilyOptions:
    """Options of the family following (:mod:`mmshbm.family.follower`). Validated on creation.

    The first seven define the search beyond a frontier; the last six are the rules of the
    guard (:class:`~mmshbm.family.guard.FamilyGuard`) for the points just beyond the
    frontier where a higher harmonic holds most of the kinetic energy while the backbone
    keeps rising (a *pending* stretch), and for branches that come back onto the family.

    Attributes
    ----------
    family_share : float
        The definition's threshold (docs/resonances.md): an orbit belongs to the first
        mode's family when its fundamental harmonic carries at least this share (0..1) of
        the period-mean kinetic energy (:func:`mmshbm.family.definition.on_family`).
        Default 0.5, a majority.
    max_excursion : int
        Steps the branch may spend off the family (or below its frontier) before the
        search beyond the frontier; also the longest backfill. Default 60.
    jump_step : float
        Relative amplitude step of the first search target beyond the frontier; the
        targets are ``frontier·(1 + jump_step·2^i)``. Default 0.02.
    max_jumps : int
        Searches beyond a frontier allowed per branch. Default 50.
    target_ratio : float
        Largest ratio (> 1) of consecutive amplitude targets of the deflated search: the
        targets frontier·(1 + jump_step·2^i) double their step until consecutive ones are
        this far apart, then grow by this ratio, up to the amplitude bound (at most
        frontier/jump_step, 50 times the frontier by default, where the bound is higher).
        Default 1.1: whether Newton converges from a start that far from the branch is a
        matter of the target, and a family that comes back below the bound within a
        doubling step would otherwise get one or two tries.
    max_roots : int
        The deflated search's depth per start: from one start at most this many
        deflated solves (each orbit it reached at the target deflated, so Newton from the
        same start must go elsewhere), stopping at its first orbit of the family. Every
        start runs at every target (at most starts × max_roots solves). Default 3.
    band_slack : float
        Relative margin of the first mode's frequency band (the definition's second
        condition, :func:`mmshbm.family.definition.frequency_band`): an orbit of the
        family has its frequency between the linear mode's and the first mode's with
        every contact held, each widened by this (the truncated Fourier series of a
        contact orbit can lie slightly outside). Default 0.01.
    lock_growth, lock_frequency : float
        A pending stretch whose amplitude grows by the factor ``lock_growth`` (> 1) while
        its frequency grows by less than ``lock_frequency`` (relative) is locked onto a
        tongue ω_j/k (it climbs without folding): it is marked off the family. Defaults
        1.5 and 0.005.
    lock_at_bound : float
        A pending stretch that reaches the amplitude bound having grown by at least this
        factor (and less than ``lock_growth``) is judged there by the lock's slope
        (``lock_frequency`` per ``lock_growth`` − 1 of amplitude growth). Default 1.1.
    loop_drop : float
        A branch that left the family and comes back onto it this far (relative) below
        the frontier goes back down the family (a loop): the search beyond the frontier
        follows. A passage may dip less than this. Default 0.05.
    reentry_tol : float
        An excursion that comes back onto the family above the frontier within this
        (relative, in amplitude and in frequency) of where an earlier one came back goes
        round a closed loop: the search beyond the frontier follows. Default 1e-3.
    origin_windows : tuple of float
        Lower edges (descending, in (0, 1)) of the amplitude windows, relative to the
        frontier, in each of which the frontier point of largest fundamental share is an
        origin of the search's starts (below the top window's [edge, 1]). Default
        (0.8, 0.6, 0.4).
    """

    family_share: float = 0.5
    max_excursion: int = 60
    jump_step: float = 0.02
    max_jumps: int = 50
    target_ratio: float = 1.1
    max_roots: int = 3
    band_slack: float = 0.01
    lock_growth: float = 1.5
    lock_frequency: float = 0.005
    lock_at_bound: float = 1.1
    loop_drop: float = 0.05
    reentry_tol: float = 1e-3
    origin_windows: tuple[float, ...] = (0.8, 0.6, 0.4)

    def __post_init__(self):
        share = check.real_number("family_share", self.family_share)
        if not 0.0 < share < 1.0:
            raise ValueError(f"family_share must be in (0, 1), got {self.family_share!r}")
        check.integer("max_excursion", self.max_excursion, minimum=1)
        check.positive("jump_step", self.jump_step)
        check.integer("max_jumps", self.max_jumps, minimum=0)
        ratio = check.real_number("target_ratio", self.target_ratio)
        if not ratio > 1.0:
            raise ValueError(f"target_ratio must be > 1, got {self.target_ratio!r}")
        check.integer("max_roots", self.max_roots, minimum=1)
        check.non_negative("band_slack", self.band_slack)
        growth = check.real_number("lock_growth", self.lock_growth)
        if not growth > 1.0:
            raise ValueError(f"lock_growth must be > 1, got {self.lock_growth!r}")
        check.non_negative("lock_frequency", self.lock_frequency)
        at_bound = check.real_number("lock_at_bound", self.lock_at_bound)
        if not 1.0 < at_bound <= growth:
            raise ValueError(f"lock_at_bound must be in (1, lock_growth], got {self.lock_at_bound!r}")
        drop = check.real_number("loop_drop", self.loop_drop)
        if not 0.0 < drop < 1.0:
            raise ValueError(f"loop_drop must be in (0, 1), got {self.loop_drop!r}")
        check.positive("reentry_tol", self.reentry_tol)
        edges = tuple(float(e) for e in self.origin_windows)
        if not edges or not all(0.0 < e < 1.0 for e in edges) or list(edges) != sorted(edges, reverse=True):
            raise ValueError(f"origin_windows must be descending edges in (0, 1), "
                             f"got {self.origin_windows!r}")

    @classmethod
    def of(cls, options) -> FamilyOptions | None:
        """The family options of a run's :class:`~mmshbm.core.options.ContinuationOptions`
        (its fields ``family_share``, ``max_excursion``, ``jump_step``, ``max_jumps``; the
        others at their defaults); None for ``follow="path"``."""
        if options.follow != "family":
            return None
        return _of(options.family_share, options.max_excursion, options.jump_step, options.max_jumps)


@functools.lru_cache(maxsize=64)
def _of(family_share, max_excursion, jump_step, max_jumps) -> FamilyOptions:
    return FamilyOptions(family_share=family_share, max_excursion=max_excursion, jump_step=jump_step,
                         max_jumps=max_jumps)
