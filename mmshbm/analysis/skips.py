"""Where a backbone has no value, and why: the skipped intervals of a branch's family front.

A backbone continued along the family of its starting mode (``follow="family"``, the
default) leaves out the internal-resonance tongues it jumps over or passes through:
:meth:`Branch.family_front <mmshbm.results.branch.Branch.family_front>` keeps the points on
the family whose amplitude is at least every earlier family point's, and
:meth:`Branch.frequency_at` is NaN inside the amplitude intervals between two front
points that are not neighbours on the branch (an excursion into a tongue lies between
them) or that a ``"jump"`` special point separates. This module names those intervals
(:func:`skips`), says for a table cell why it is empty or what to beware of
(:func:`explain`), and summarises a branch for the study tables (:func:`cell_summary`).

Amplitudes are in m (the branch's unit) unless a name says gaps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..results.diagnostics import incomplete_reason

__all__ = ["Skip", "skips", "explain", "caution", "mode_share_at", "partner_at", "cell_summary"]

#: a jump whose frequency changes by more than this (relative) across its interval is a
#: discontinuity of the front; table values within JUMP_NEIGHBOURHOOD of it get a caution
JUMP_DISCONTINUITY = 5e-3
#: relative amplitude distance from a discontinuous jump within which a value is cautioned
JUMP_NEIGHBOURHOOD = 0.02
#: skipped intervals narrower than this (relative to their upper end) are not listed by
#: :func:`cell_summary` (a jump that landed and filled the family back to the frontier)
WIDE = 1e-3


@dataclass(frozen=True)
class Skip:
    """An amplitude interval of a branch's family front without family points.

    Attributes
    ----------
    lo, hi : float
        Amplitudes (m) of the front points on either side (``hi`` may equal ``lo`` when a
        jump landed and filled the family back down to the frontier).
    index_lo, index_hi : int
        Those points' indices on the branch.
    f_lo, f_hi : float
        Their frequencies (Hz).
    kind : {"jump", "passage"}
        A ``"jump"`` special point at ``index_hi`` (the continuation was restarted beyond
        the tongue), or a *passage*: the branch left the family and came back above the
        frontier by itself.
    reason : str
        The jump's reason ("excursion", "loop", "tongue reached the bound", ...) or "".
    resonances : tuple of (k, j, ratio, mode_frequency)
        Internal resonances named on the excursion points between the two (harmonic k,
        mode j 1-based, kΩ/ω_j, ω_j/2π in Hz), strongest first; the strongest modal
        share off the starting mode when no ``"internal_resonance"`` point lies there.
    excursion : int
        Number of branch points between the two (off the family, or back below the frontier).
    """

    lo: float
    hi: float
    index_lo: int
    index_hi: int
    f_lo: float
    f_hi: float
    kind: str
    reason: str
    resonances: tuple
    excursion: int

    @property
    def width(self) -> float:
        """hi − lo (m)."""
        return self.hi - self.lo

    @property
    def discontinuous(self) -> bool:
        """The frequency changes across the interval by more than :data:`JUMP_DISCONTINUITY`."""
        return abs(self.f_hi - self.f_lo) > JUMP_DISCONTINUITY * abs(self.f_lo)

    def resonance_text(self) -> str:
        """E.g. "5Ω ≈ ω2 (k:j = 5:2, 286.1 Hz)" for the strongest resonance, or ""."""
        if not self.resonances:
            return ""
        k, j, ratio, fj = self.resonances[0]
        more = f" and {', '.join(f'{kk}:{jj}' for kk, jj, _, _ in self.resonances[1:])}" \
            if len(self.resonances) > 1 else ""
        return f"{k}Ω ≈ ω{j} (k:j = {k}:{j}, f{j} = {fj:.1f} Hz, kΩ/ω = {ratio:.3f}){more}"


def skips(branch) -> list[Skip]:
    """The skipped intervals of ``branch``'s family front, in order of amplitude."""
    front = branch.family_front()
    if len(front) < 2:
        return []
    A, f = np.asarray(branch.amplitude, dtype=float), np.asarray(branch.frequency, dtype=float)
    jumps = {int(s[1]): s for s in branch.special_points if s[0] == "jump"}
    out = []
    for i, j in zip(front[:-1], front[1:], strict=True):
        i, j = int(i), int(j)
        if j == i + 1 and j not in jumps:
            continue
        jump = jumps.get(j)
        reason = str(getattr(jump, "data", {}).get("reason", "")) if jump is not None else ""
        out.append(Skip(lo=float(A[i]), hi=float(A[j]), index_lo=i, index_hi=j, f_lo=float(f[i]),
                        f_hi=float(f[j]), kind="jump" if jump is not None else "passage", reason=reason,
                        resonances=_resonances(branch, i, j), excursion=j - i - 1))
    return out


def _resonances(branch, i: int, j: int) -> tuple:
    found = [s for s in branch.special_points if s[0] == "internal_resonance" and i < int(s[1]) < j]
    if found:
        found.sort(key=lambda s: -float(s.data.get("share", 0.0)))
        seen, out = set(), []
        for s in found:
            key = (int(s.data["k"]), int(s.data["j"]))
            if key not in seen:
                seen.add(key)
                out.append((*key, float(s.data.get("ratio", math.nan)),
                            float(s.data.get("mode_frequency", math.nan))))
        return tuple(out)
    shares = branch.records.get("modal_shares")
    if shares is None or j - i < 2:
        return ()
    shares = np.asarray(shares, dtype=float)[i + 1:j]
    shares = shares.copy()
    shares[:, 0, :] = -1.0  # not the starting mode (mode 1)
    p, jj, kk = np.unravel_index(np.argmax(shares), shares.shape)
    if kk == 0 or shares[p, jj, kk] <= 0:
        return ()
    try:
        fj = float(branch.get_model().linear_frequencies(jj + 1)[jj])
    except (ValueError, RuntimeError):
        fj = math.nan
    ratio = kk * float(branch.frequency[i + 1 + p]) / fj if fj > 0 else math.nan
    return ((int(kk), int(jj + 1), ratio, fj),)


def _gaps(branch) -> float:
    gap = branch.gap
    return float(gap) if gap else 1.0


def _amp(value: float, gap: float) -> str:
    return f"{value / gap:.3g} gaps" if gap != 1.0 else f"{value:.3g} m"


def _interval(lo: float, hi: float, gap: float) -> str:
    return f"{lo / gap:.3g}–{hi / gap:.3g} gaps" if gap != 1.0 else f"{lo:.3g}–{hi:.3g} m"


def explain(branch, amplitude: float, frequency: float, intervals: list[Skip] | None = None) -> str:
    """Why the table cell of ``branch`` at ``amplitude`` (m) is NaN, or a caution about its
    finite ``frequency``; "" when there is nothing to say.

    NaN cells: the branch does not reach the amplitude (and why it stopped), reaches it
    only off its family, or the amplitude lies inside a skipped interval (named by its
    internal resonance). Finite cells: :func:`caution`.
    """
    intervals = skips(branch) if intervals is None else intervals
    if np.isfinite(frequency):
        return caution(branch, amplitude, intervals)
    gap = _gaps(branch)
    if len(branch) == 0:
        return f"no point ({branch.status})"
    for s in intervals:
        if s.lo <= amplitude <= s.hi and s.width > 0:
            what = s.resonance_text() or "an excursion off the family"
            how = "jumped" if s.kind == "jump" else "passed"
            return f"inside {what}: {how} {_interval(s.lo, s.hi, gap)} ({s.excursion} points off the front)"
    front = branch.family_front()
    a_front = float(np.max(branch.amplitude[front])) if len(front) else -math.inf
    a_all = float(np.nanmax(branch.amplitude))
    if amplitude > a_front:
        if a_all >= amplitude:
            return f"reached only off the family (the family front ends at {_amp(a_front, gap)})"
        if not branch.completed:
            return (f"not reached: stopped at {_amp(a_all, gap)}, "
                    f"{incomplete_reason(branch.status, branch.metadata)}")
        return f"beyond the branch (it ends at {_amp(a_all, gap)})"
    if len(front) and amplitude < float(branch.amplitude[front[0]]):
        return f"below the first point ({_amp(float(branch.amplitude[front[0]]), gap)})"
    return "the pinned solve did not give a value"


def caution(branch, amplitude: float, intervals: list[Skip] | None = None) -> str:
    """A warning for a finite table value at ``amplitude`` (m): it lies inside a skipped
    interval (found on the path segment next to the front, where the starting mode still
    holds its family share: the edge of a tongue), or within :data:`JUMP_NEIGHBOURHOOD` of
    a skipped interval across which the frequency jumps (the front is discontinuous there,
    and which side a cell lands on depends on where the jump happened to land). ""
    otherwise."""
    intervals = skips(branch) if intervals is None else intervals
    gap = _gaps(branch)
    for s in intervals:
        if s.lo < amplitude < s.hi and s.width > WIDE * s.hi:
            what = s.resonance_text() or "an excursion off the family"
            return (f"at the edge of {what}: inside the interval {_interval(s.lo, s.hi, gap)} the front "
                    "skips, on the path next to it where the first mode still holds its family share")
    for s in intervals:
        near = s.lo * (1 - JUMP_NEIGHBOURHOOD) <= amplitude <= s.hi * (1 + JUMP_NEIGHBOURHOOD)
        if near and s.discontinuous:
            where = _amp(s.lo, gap) if s.width <= WIDE * s.hi else _interval(s.lo, s.hi, gap)
            return (f"next to a discontinuity of the family at {where}: f {s.f_lo:.2f} → {s.f_hi:.2f} Hz "
                    f"({s.kind}{', ' + s.reason if s.reason else ''}); the value depends on the side")
    return ""


def _family_share(branch) -> float:
    return float(dict(branch.metadata.get("continuation") or {}).get("family_share", 0.5))


def _weights(branch, amplitude: float):
    """(i, j, s) with the point at ``amplitude`` (m) ≈ (1 − s)·point i + s·point j where
    :meth:`Branch.frequency_at` finds it: on the segment between two neighbouring front
    points, or, inside a skipped interval, on the path segment that leaves the last front
    point or arrives at the next one while the starting mode keeps its family share
    (interpolated); None where the front has no value."""
    front = branch.family_front()
    A = np.asarray(branch.amplitude, dtype=float)
    hit = np.flatnonzero(np.isclose(A[front], amplitude, rtol=1e-9, atol=0))  # a stored point, the first
    if len(hit):
        i = int(front[hit[0]])
        return i, i, 0.0
    jumps = {int(p[1]) for p in branch.special_points if p[0] == "jump"}
    share = branch.records.get("mode_share")
    for i, j in zip(front[:-1], front[1:], strict=False):
        i, j = int(i), int(j)
        if not A[i] <= amplitude <= A[j] or A[j] == A[i]:
            continue
        if j == i + 1 and j not in jumps:
            return i, j, float((amplitude - A[i]) / (A[j] - A[i]))
        edges = []
        if i + 1 not in jumps and A[i] <= amplitude <= A[i + 1]:
            edges.append((i, i + 1))
        if j not in jumps and j - 1 != i and A[j - 1] <= amplitude <= A[j]:
            edges.append((j - 1, j))
        for p, q in edges:
            t = float((amplitude - A[p]) / (A[q] - A[p]))
            if share is not None and (1 - t) * share[p] + t * share[q] >= _family_share(branch):
                return p, q, t
        return None
    return None


def mode_share_at(branch, amplitude: float) -> float:
    """The starting mode's kinetic-energy share (0..1) at ``amplitude`` (m) on the family
    front, interpolated linearly between the neighbouring front points; NaN where the
    front has no value or the branch has no ``records["mode_share"]``."""
    share = branch.records.get("mode_share")
    w = _weights(branch, amplitude)
    if share is None or w is None:
        return math.nan
    i, j, s = w
    return float((1 - s) * share[i] + s * share[j])


def partner_at(branch, amplitude: float) -> tuple:
    """The strongest other mode at ``amplitude`` (m) on the family front: (k, j, share)
    with harmonic k, mode j (1-based, not the starting mode 1) and its share of the
    kinetic energy (interpolated like :func:`mode_share_at`); None where unknown."""
    shares = branch.records.get("modal_shares")
    w = _weights(branch, amplitude)
    if shares is None or w is None:
        return None
    i, j, s = w
    m = (1 - s) * np.asarray(shares[i], dtype=float) + s * np.asarray(shares[j], dtype=float)
    m[0, :] = -1.0
    jj, kk = np.unravel_index(np.argmax(m), m.shape)
    return int(kk), int(jj + 1), float(m[jj, kk])


def cell_summary(branch) -> dict:
    """Facts about one run for the study report.

    Returns
    -------
    dict
        ``points``, ``on_family`` (points on the family), ``jumps``, ``skipped``
        (intervals wider than :data:`WIDE` of their upper end, as (lo, hi, (k, j) or None)
        with lo/hi in gaps, or m without a gap),
        ``skipped_total`` (summed width, same unit), ``resonances`` (named k:j pairs, in
        order of appearance), ``elapsed_s`` and ``status``.
    """
    gap = _gaps(branch)
    on = branch.records.get("on_family")
    intervals = skips(branch)
    wide = [s for s in intervals if s.width > WIDE * s.hi]
    names: list[str] = []
    for s in branch.special_points:
        if s[0] == "internal_resonance":
            name = f"{s.data.get('k')}:{s.data.get('j')}"
            if name not in names:
                names.append(name)
    return {"points": len(branch),
            "on_family": int(np.sum(np.asarray(on) > 0.5)) if on is not None else len(branch),
            "jumps": sum(s[0] == "jump" for s in branch.special_points),
            "skipped": [(s.lo / gap, s.hi / gap, s.resonances[0][:2] if s.resonances else None)
                        for s in wide],
            "skipped_total": float(sum(s.width for s in wide) / gap),
            "resonances": names,
            "elapsed_s": float(branch.metadata.get("elapsed_s", math.nan)),
            "status": branch.status}
