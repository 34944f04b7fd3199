"""Where a failed jump says the family ends (:mod:`mmshbm.core.family`): the starting
mode's own orbit, continued from the frontier, loses the fundamental's share of the
kinetic energy, or turns back in amplitude with it (docs/resonances.md, "Where the family
ends")."""

from __future__ import annotations

import math

from .family_guard import FamilyGuard, family_value
from .pinned import PinnedFailure

__all__ = ["FamilyEnded", "end_of_family", "turned_back"]


class FamilyEnded(PinnedFailure):
    """A jump found nothing beyond a frontier where the starting mode's own orbit loses
    the fundamental's majority (the message says where): the family ends there."""



def end_of_family(recs: list, guard: FamilyGuard, problem) -> str:
    """Where the branch continued from the frontier loses the fundamental's majority,
    said in a sentence, or "" when it does not. The point after the frontier on the
    branch is the frontier's orbit continued (path following); when its fundamental holds
    less than ``family_share`` of the kinetic energy, the starting mode's own orbit lost
    the majority there: the family, as defined (docs/resonances.md), ends at the
    frontier unless another orbit with the majority exists beyond, which the jump's
    searches then did not find. The sentence names the crossing (interpolated linearly
    in the share between the two points), the harmonic k >= 2 that holds the most
    kinetic energy after it and the open-contact mode j nearest to kΩ (the point's
    ``resonance_harmonic``, ``resonance_mode``, ``resonance_detuning`` records)."""
    i = guard.frontier_index
    if i < 0 or i + 1 >= len(recs):
        return ""
    rec0, rec1 = recs[i], recs[i + 1]
    s0, s1 = family_value(rec0), family_value(rec1)
    if s0 is None or s1 is None or not s1 < guard.family_share <= s0:
        return ""
    w = (s0 - guard.family_share) / (s0 - s1)
    amp = (1 - w) * float(rec0["amplitude"]) + w * float(rec1["amplitude"])
    f = (1 - w) * float(rec0.get("frequency", math.nan)) + w * float(rec1.get("frequency", math.nan))
    lost = ("the fundamental's majority" if guard.family_share == 0.5 else
            f"the family's fundamental share ({guard.family_share:g})")
    text = (f"family ended at amplitude {amp:.4g} ({f:.4g} Hz): the starting mode's orbit loses {lost} "
            f"there (fundamental share {s0:.3f} at {float(rec0['amplitude']):.4g}, "
            f"{s1:.3f} at {float(rec1['amplitude']):.4g})")
    k, j = int(rec1.get("resonance_harmonic", 0) or 0), int(rec1.get("resonance_mode", 0) or 0)
    detuning = float(rec1.get("resonance_detuning", math.nan))
    if k >= 2 and j >= 1 and math.isfinite(detuning):
        freqs = problem.tracked_frequencies
        f_j = float(freqs[j - 1]) if freqs is not None and j <= len(freqs) else math.nan
        at = f", f_{j} = {f_j:.4g} Hz" if math.isfinite(f_j) else ""
        text += (f"; harmonic {k} holds the most energy of the higher harmonics, near mode {j} "
                 f"({k}Ω/f_{j} = {1 + detuning:.4f}{at})")
    return text


def turned_back(recs: list, guard: FamilyGuard) -> str:
    """A sentence (ending in "; ") when the branch, continued from the frontier, turns back
    in amplitude there with the fundamental still holding ``family_share`` of the kinetic
    energy (no internal resonance took the energy: the backbone itself folds in the
    measured amplitude); "" otherwise."""
    i = guard.frontier_index
    if i < 0 or i + 1 >= len(recs):
        return ""
    rec0, rec1 = recs[i], recs[i + 1]
    s1 = family_value(rec1)
    if s1 is None or s1 < guard.family_share or not float(rec1["amplitude"]) < float(rec0["amplitude"]):
        return ""
    return (f"the branch turns back in amplitude at the frontier, {float(rec0['amplitude']):.4g} "
            f"({float(rec0.get('frequency', math.nan)):.4g} Hz), with the fundamental's share at {s1:.3f}; ")
