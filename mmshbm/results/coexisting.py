"""Where other orbits coexist with the starting mode's backbone at the same amplitude.

A branch followed with ``follow="family"`` holds, besides its family front (the
backbone, :func:`mmshbm.results.family_points.family_front`), the points of the tongues
it went into and of the loops it came back down. Wherever such a point's amplitude lies
on a stretch the front covers continuously, two periodic orbits of the same amplitude
exist: the backbone's and the excursion's (e.g. a tongue that leaves the frontier, folds
and comes back below it; a jump that lands at the frontier's amplitude at another
frequency). :func:`coexisting_intervals` names those amplitude intervals, so a result
that reports the backbone's frequency there also says that it is not the only orbit.
"""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["Coexistence", "coexisting_intervals"]

#: relative tolerance on amplitudes (the Newton tolerance of the continuation is 1e-10;
#: bound refinement and jumps land within 1e-9 of their targets)
_RTOL = 1e-9


@dataclasses.dataclass(frozen=True)
class Coexistence:
    """An amplitude interval where the backbone and other orbits of the branch coexist.

    Attributes
    ----------
    lo, hi : float
        The interval (amplitude unit of the branch, m); ``lo == hi`` for one amplitude.
    points : tuple of int
        The branch points off the family front whose amplitude lies in it (for a jump
        that landed at the frontier's amplitude: the frontier and the landing).
    frequency_other : (float, float)
        The frequency range (Hz) of those points.
    frequency_family : (float, float)
        The family front's frequency range (Hz) over the interval (its points within
        the interval and the two that enclose it).
    """

    lo: float
    hi: float
    points: tuple
    frequency_other: tuple
    frequency_family: tuple


def _covered(branch, front: np.ndarray) -> list[tuple[float, float, int, int]]:
    """The stretches the front covers continuously: consecutive front points not
    separated by a jump (a jump's first point starts a new stretch; the interval it
    skipped is not covered)."""
    jumps = {int(s[1]) for s in branch.special_points if s[0] == "jump"}
    A = np.asarray(branch.amplitude, dtype=float).tolist()
    idx = np.asarray(front, dtype=int).tolist()
    return [(A[i], A[j], i, j) for i, j in zip(idx[:-1], idx[1:], strict=False) if j not in jumps]


def coexisting_intervals(branch) -> list[Coexistence]:
    """The amplitude intervals where points of ``branch`` off its family front coexist
    with the front (module docstring), in increasing amplitude; empty for a branch
    without ``records["on_family"]`` (plain path following: no front to compare with)
    or without excursions."""
    from .family_points import family_front

    if "on_family" not in branch.records or len(branch) < 2:
        return []
    front = family_front(branch)
    if len(front) == len(branch) and not any(s[0] == "jump" for s in branch.special_points):
        return []  # every point on the front and no jump: nothing off it, nothing landed
    off_mask = np.ones(len(branch), dtype=bool)
    off_mask[front] = False
    off = np.flatnonzero(off_mask)  # np.setdiff1d(np.arange(len(branch)), front)
    A, f = np.asarray(branch.amplitude, dtype=float), np.asarray(branch.frequency, dtype=float)
    covered = []  # maximal intervals the front covers continuously
    for lo_s, hi_s, _, _ in _covered(branch, front):
        if covered and lo_s <= covered[-1][1] * (1 + _RTOL):
            covered[-1][1] = max(covered[-1][1], hi_s)
        else:
            covered.append([lo_s, hi_s])
    raw = []  # (lo, hi, other point indices)
    # each excursion (a run of consecutive points off the front) is a continuous piece of
    # the path: it has an orbit at every amplitude between its smallest and largest, and
    # between it and the point it left or reached without a jump (the path's segment
    # from the last front point to the first point off it holds orbits of every
    # amplitude in between, none of them the front's)
    jumps = {int(s[1]) for s in branch.special_points if s[0] == "jump"}
    runs = np.split(off, np.flatnonzero(np.diff(off) > 1) + 1) if len(off) else []
    for run in runs:
        span = A[run]
        if run[0] > 0 and int(run[0]) not in jumps:
            span = np.append(span, A[run[0] - 1])
        if run[-1] + 1 < len(branch) and int(run[-1]) + 1 not in jumps:
            span = np.append(span, A[run[-1] + 1])
        p_lo, p_hi = float(A[run].min()), float(A[run].max())
        a_lo, a_hi = float(span.min()), float(span.max())
        for lo_s, hi_s in covered:
            lo, hi = max(a_lo, lo_s), min(a_hi, hi_s)
            points_inside = max(p_lo, lo_s) <= min(p_hi, hi_s) * (1 + _RTOL)
            # a segment's end alone (a front point the path left) is the front's own orbit
            if points_inside or hi > lo * (1 + _RTOL):
                pts = run[(A[run] >= lo * (1 - _RTOL)) & (A[run] <= hi * (1 + _RTOL))]
                raw.append((lo, max(lo, hi), set((pts if len(pts) else run).tolist())))
    # a jump that lands at the frontier's amplitude (nothing skipped) at another frequency:
    # the frontier's orbit and the landing's coexist there
    for s in branch.special_points:
        if s[0] != "jump" or not 0 < int(s[1]) < len(branch):
            continue
        j = int(s[1])
        before = front[front < j]
        if not len(before):
            continue
        i = int(before[-1])
        if abs(A[j] - A[i]) <= _RTOL * A[i] and abs(f[j] - f[i]) > 1e-6 * abs(f[i]):
            raw.append((float(A[i]), float(A[i]), {i, j}))
    if not raw:
        return []
    raw.sort(key=lambda r: r[0])
    merged = [list(raw[0])]
    for lo, hi, pts in raw[1:]:
        if lo <= merged[-1][1] * (1 + _RTOL):
            merged[-1][1] = max(merged[-1][1], hi)
            merged[-1][2] |= pts
        else:
            merged.append([lo, hi, set(pts)])
    out = []
    for lo, hi, pts in merged:
        idx = np.array(sorted(pts), dtype=int)
        inside = front[(A[front] >= lo * (1 - _RTOL)) & (A[front] <= hi * (1 + _RTOL))]
        below, above = front[A[front] < lo * (1 - _RTOL)], front[A[front] > hi * (1 + _RTOL)]
        fam = np.concatenate([below[-1:], inside, above[:1]])
        out.append(Coexistence(lo, hi, tuple(int(i) for i in idx), (float(f[idx].min()), float(f[idx].max())),
                               (float(f[fam].min()), float(f[fam].max()))))
    return out
