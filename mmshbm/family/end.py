"""Why the family following ends a branch, as a value: :class:`FamilyEnd`.

A search beyond the frontier that finds no orbit of the family ends the branch. What it
tried (each pinned solve: the start, the amplitude, the outcome) and where the starting
mode's own orbit loses the definition's predicate (:func:`crossing`) are fields of a
:class:`FamilyEnd`; the branch's final status carries it
(:attr:`mmshbm.core.status.Status.cause`) and its text is built from it
(:meth:`FamilyEnd.detail`). Nothing reads the text back.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..core.pinned import PinnedFailure
from .definition import family_value, on_family
from .guard import FamilyGuard

__all__ = ["Attempt", "Crossing", "FamilyEnd", "FamilyEnded", "crossing", "turned_back"]


@dataclass(frozen=True)
class Attempt:
    """One Newton solve at a pinned amplitude beyond the frontier.

    Attributes
    ----------
    search : str
        The search that made it (``"deflated"``).
    start : str
        Where Newton started (``"extrapolated from the frontier"``, ``"linear mode"``,
        ...).
    amplitude : float
        The pinned amplitude (m).
    outcome : str
        ``"landed"`` (an orbit of the family), ``"off the family"`` (converged to an orbit
        that fails the predicate), ``"known"`` (converged to an orbit already found),
        ``"outside"`` (the start lies outside the trust region: nothing solved) or
        ``"failed"`` (Newton did not converge).
    frequency : float
        Hz of the converged orbit (nan when none).
    share : float
        Its fundamental share (nan when none).
    """

    search: str
    start: str
    amplitude: float
    outcome: str
    frequency: float = math.nan
    share: float = math.nan


@dataclass(frozen=True)
class Crossing:
    """Where the starting mode's orbit, continued from the frontier, loses the predicate:
    the crossing interpolated linearly in the share between the frontier point (amplitude
    ``amplitude_before`` m, share ``share_before``) and the next point of the branch
    (``amplitude_after``, ``share_after``). ``harmonic`` k >= 2 holds the most kinetic
    energy of the higher harmonics after it, near open-contact mode ``mode`` j
    (``detuning`` kΩ/ω_j − 1, ``mode_frequency`` f_j Hz); 0 / nan where not recorded."""

    amplitude: float
    frequency: float
    family_share: float
    amplitude_before: float
    share_before: float
    amplitude_after: float
    share_after: float
    harmonic: int = 0
    mode: int = 0
    detuning: float = math.nan
    mode_frequency: float = math.nan

    def sentence(self) -> str:
        """The crossing said in words."""
        lost = ("the fundamental's majority" if self.family_share == 0.5 else
                f"the family's fundamental share ({self.family_share:g})")
        text = (f"at amplitude {self.amplitude:.4g} ({self.frequency:.4g} Hz): the starting mode's orbit "
                f"loses {lost} there (fundamental share {self.share_before:.3f} at "
                f"{self.amplitude_before:.4g}, {self.share_after:.3f} at {self.amplitude_after:.4g})")
        if self.harmonic >= 2 and self.mode >= 1 and math.isfinite(self.detuning):
            f_j = self.mode_frequency
            at = f", f_{self.mode} = {f_j:.4g} Hz" if math.isfinite(f_j) else ""
            text += (f"; harmonic {self.harmonic} holds the most energy of the higher harmonics, near mode "
                     f"{self.mode} ({self.harmonic}Ω/f_{self.mode} = {1 + self.detuning:.4f}{at})")
        return text


@dataclass(frozen=True)
class FamilyEnd:
    """Why the family following ended a branch.

    Attributes
    ----------
    ended : bool
        True when the family ends: the starting mode's orbit, continued from the
        frontier, loses the predicate there (:attr:`crossing`) and the search found no
        orbit of the family beyond it up to :attr:`searched_to`. False when the search
        failed otherwise (the status kind is then ``"jump failed"``).
    frontier : float
        Largest amplitude (m) reached on the family.
    frontier_frequency : float
        Its frequency (Hz).
    searched_to : float
        Largest amplitude (m) the search sought the family at.
    crossing : Crossing or None
        Where the continued orbit loses the predicate (None when it does not).
    attempts : tuple of Attempt
        Every pinned solve the search made, in order.
    notes : str
        The search's account where the family does not end (the branch turning back at
        the frontier, then what was tried); "" where :attr:`attempts` alone tell it.
    """

    ended: bool
    frontier: float
    frontier_frequency: float
    searched_to: float
    crossing: Crossing | None = None
    attempts: tuple[Attempt, ...] = ()
    notes: str = ""

    def outcomes(self) -> dict[str, int]:
        """How many attempts ended in each outcome."""
        out: dict[str, int] = {}
        for a in self.attempts:
            out[a.outcome] = out.get(a.outcome, 0) + 1
        return out

    def tried(self) -> str:
        """The attempts summarised: their count, amplitudes and outcomes."""
        if not self.attempts:
            return "no pinned solve"
        amps = [a.amplitude for a in self.attempts]
        counts = ", ".join(f"{n} {k}" for k, n in sorted(self.outcomes().items()))
        return (f"{len(self.attempts)} pinned solves at {min(amps):.4g}..{max(amps):.4g} from "
                f"{len({a.start for a in self.attempts})} starts: {counts}")

    def detail(self) -> str:
        """The final status's detail, built from the fields."""
        account = self.notes or self.tried()
        if self.ended and self.crossing is not None:
            return (f"{self.crossing.sentence()}; no orbit on the family found beyond it up to "
                    f"{self.searched_to:.4g} ({account})")
        return account


class FamilyEnded(PinnedFailure):
    """A search beyond the frontier found nothing: ``end`` (a :class:`FamilyEnd`) says
    what was tried and whether the family ends there."""

    def __init__(self, end: FamilyEnd):
        super().__init__(end.detail())
        self.end = end


def crossing(recs: list, guard: FamilyGuard, problem) -> Crossing | None:
    """Where the branch continued from the frontier loses the predicate, or None when it
    does not. The point after the frontier on the branch is the frontier's orbit
    continued (path following); when it fails the predicate
    (:func:`mmshbm.family.definition.on_family`) while the frontier satisfies it, the
    starting mode's own orbit lost the family there."""
    i = guard.frontier_index
    if i < 0 or i + 1 >= len(recs):
        return None
    rec0, rec1 = recs[i], recs[i + 1]
    if on_family(rec1, guard.family_share) is not False or on_family(rec0, guard.family_share) is not True:
        return None
    s0, s1 = family_value(rec0), family_value(rec1)
    w = (s0 - guard.family_share) / (s0 - s1)
    amp = (1 - w) * float(rec0["amplitude"]) + w * float(rec1["amplitude"])
    f = (1 - w) * float(rec0.get("frequency", math.nan)) + w * float(rec1.get("frequency", math.nan))
    k, j = int(rec1.get("resonance_harmonic", 0) or 0), int(rec1.get("resonance_mode", 0) or 0)
    detuning = float(rec1.get("resonance_detuning", math.nan))
    freqs = problem.tracked_frequencies
    f_j = float(freqs[j - 1]) if freqs is not None and 1 <= j <= len(freqs) else math.nan
    return Crossing(amplitude=amp, frequency=f, family_share=guard.family_share,
                    amplitude_before=float(rec0["amplitude"]), share_before=s0,
                    amplitude_after=float(rec1["amplitude"]), share_after=s1, harmonic=k, mode=j,
                    detuning=detuning, mode_frequency=f_j)


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
