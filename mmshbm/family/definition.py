"""The definition of the first nonlinear mode's family, as a predicate on one orbit.

docs/resonances.md states it: a periodic orbit at amplitude A belongs to the family of the
starting mode when its fundamental harmonic carries at least ``family_share`` of the
period-mean kinetic energy,

    s(u) = T_1 / Σ_{k>=1} T_k  >=  family_share,

where T_k is the kinetic energy of harmonic k (all DOFs together), and its frequency lies
in the first mode's band, from the open-contact linear mode's to the first mode's with
every contact held (contacts only stiffen the structure; for one contact the band ends
below the second open-contact mode, by interlacing, which separates the second mode's
orbits whose fundamental also dominates), and, where its frequency lies above the next
open-contact mode's (several contacts can lift the band that far, and there the next
mode's own orbits with a dominant fundamental exist), the starting mode leads its
fundamental: of the open-contact modes, the starting mode holds the largest share of
the fundamental harmonic's kinetic energy (record ``"mode_leads"``: 1 or 0, NaN below
that frequency, where the condition is void). The measure is the
record ``"fundamental_share"`` of a converged point (MMS-HBM:
:meth:`mmshbm.methods.mms.family.FamilyMixin.fundamental_share`). It depends on the orbit
only: not on how the continuation reached it, and not on the time origin or the
direction of time (each T_k is invariant under a shift t -> t + τ, which multiplies the
complex amplitude of harmonic k by e^{ikΩτ}), and not on a common scale of all DOFs.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

__all__ = ["FAMILY_RECORD", "LEAD_RECORD", "family_value", "frequency_band", "on_family"]

#: the record that decides membership of the family: the fundamental harmonic's share of
#: the period-mean kinetic energy (MMS-HBM's ``fundamental_share``)
FAMILY_RECORD = "fundamental_share"

#: the record of the definition's third condition: 1.0 where the starting mode holds the
#: largest share of the fundamental harmonic's kinetic energy, 0.0 where another mode
#: does, NaN where the orbit's frequency lies below the next open-contact mode's (void)
LEAD_RECORD = "mode_leads"


def family_value(rec: Mapping) -> float | None:
    """The family measure of a point's record: ``rec["fundamental_share"]``, or the
    starting mode's share ``rec["mode_share"]`` for records without it (branches saved by
    earlier versions); None when the record has neither."""
    value = rec.get(FAMILY_RECORD)
    if value is None:
        value = rec.get("mode_share")
    return None if value is None else float(value)


def on_family(rec: Mapping, family_share: float, band: tuple[float, float] | None = None) -> bool | None:
    """The definition's predicate: whether the orbit with record ``rec`` belongs to the
    first mode's family: its fundamental share (:func:`family_value`) is at least
    ``family_share`` (0..1), the starting mode leads its fundamental where that is
    decided (``rec["mode_leads"]`` is not 0) and, given the first mode's frequency
    ``band`` (lo, hi) in Hz (:func:`frequency_band`), its ``rec["frequency"]`` lies in it.
    None when the record carries no family measure (a problem that does not record it:
    every orbit counts)."""
    value = family_value(rec)
    if value is None:
        return None
    if rec.get(LEAD_RECORD, math.nan) == 0.0:
        return False
    if band is not None:
        f = float(rec.get("frequency", math.nan))
        if not band[0] <= f <= band[1]:
            return False
    return bool(value >= family_share)


def frequency_band(problem, recs: list, slack: float) -> tuple[float, float]:
    """The first mode's frequency band (Hz), widened by ``slack`` (relative): from the
    branch's first point (the linear mode: contacts only stiffen the structure) to the
    problem's ``family_frequency_ceiling`` (the first mode with every contact DOF held;
    for one contact, by interlacing, at most the second open-contact mode). (0, inf)
    where the problem offers neither."""
    f0 = float(recs[0].get("frequency", math.nan)) if recs else math.nan
    lo = f0 * (1.0 - slack) if math.isfinite(f0) else 0.0
    ceiling = problem.family_frequency_ceiling or problem.family_frequency_limit
    hi = float(ceiling()) * (1.0 + slack) if ceiling is not None else math.inf
    return lo, hi
