"""The starting mode's backbone inside a branch: its family front and exact points on it.

A branch continued with ``follow="family"`` (:mod:`mmshbm.core.family`) holds, besides
the first-mode backbone, the points of the internal-resonance tongues it followed out and
back (``records["on_family"] = 0``). :func:`family_front` picks the backbone's points;
:func:`frequency_at` solves the backbone at a given amplitude, and returns NaN where the
family does not exist (its starting mode holds less than ``family_share`` of the energy)
or was not sampled (a jump), never a guess across a tongue.
"""

from __future__ import annotations

import logging

import numpy as np

from ..core.family import family_value

__all__ = ["family_front", "frequency_at"]

log = logging.getLogger(__name__)


def family_front(branch) -> np.ndarray:
    """Indices of the points that make up the backbone of the starting mode's family:
    points on the family whose amplitude is at least every earlier family point's.
    Excursions into internal-resonance tongues, and the way back down a loop, are left
    out. On the family: ``records["on_family"]`` (set by the continuation's family guard);
    for a branch without it (plain path following, the baselines) the family measure
    (``records["fundamental_share"]``, else ``records["mode_share"]``) is at least
    ``family_share``; all points when
    the branch has neither record."""
    if "on_family" in branch.records:
        on = np.asarray(branch.records["on_family"], dtype=float) > 0.5
    elif _share_record(branch) is not None:
        on = np.asarray(_share_record(branch), dtype=float) >= _family_share(branch)
    else:
        on = np.ones(len(branch), dtype=bool)
    front, best = [], -np.inf
    for i in range(len(branch)):
        if on[i] and branch.amplitude[i] >= best * (1 - 1e-9):
            front.append(i)
            best = max(best, float(branch.amplitude[i]))
    return np.array(front, dtype=int)


def frequency_at(branch, amplitude: float, *, interpolate: bool = False, tol: float = 1e-10) -> float:
    """Frequency (Hz) of the backbone at ``amplitude`` (m); see
    :meth:`mmshbm.Branch.frequency_at`.

    Between two consecutive front points the point is solved (or interpolated) on that
    segment. Where the front skips (the branch went into a tongue or jumped), the segments
    of the path that leave the last front point and that arrive at the next one are tried:
    a point there counts when the starting mode still holds ``family_share`` of the
    kinetic energy (the family ends inside the segment, not at its sampled end)."""
    a = float(amplitude)
    front = family_front(branch)
    A, f = branch.amplitude, branch.frequency
    for i in front:
        if np.isclose(A[i], a, rtol=1e-9, atol=0):
            return float(f[i])
    jumps = {int(s[1]) for s in branch.special_points if s[0] == "jump"}
    for i, j in zip(front[:-1], front[1:], strict=False):
        if not (min(A[i], A[j]) <= a <= max(A[i], A[j])) or A[i] == A[j]:
            continue
        if j == i + 1 and j not in jumps:
            return _on_segment(branch, i, j, a, interpolate, tol, require_share=False)
        # a skipped interval: the family's edges lie on the path's segments next to the front
        edges = []
        if i + 1 not in jumps and A[i] <= a <= A[i + 1]:
            edges.append((i, i + 1))
        if j not in jumps and A[j - 1] <= a <= A[j] and j - 1 != i:
            edges.append((j - 1, j))
        for p, q in edges:
            value = _on_segment(branch, p, q, a, interpolate, tol, require_share=True)
            if np.isfinite(value):
                return value
        return float("nan")
    return float("nan")


def _share_record(branch):
    """The branch's family measure per point (:func:`mmshbm.core.family.family_value`)."""
    from ..core.family import FAMILY_RECORD

    share = branch.records.get(FAMILY_RECORD)
    return branch.records.get("mode_share") if share is None else share


def _family_share(branch) -> float:
    return float(dict(branch.metadata.get("continuation") or {}).get("family_share", 0.5))


def _on_segment(branch, i: int, j: int, a: float, interpolate: bool, tol: float, *,
                require_share: bool) -> float:
    """The point at amplitude ``a`` between the branch points i and j (A[i] != A[j]); with
    ``require_share``, NaN unless the starting mode holds the family's share there."""
    from ..core.pinned import PinnedFailure, solve_at_amplitude

    A, f = branch.amplitude, branch.frequency
    s = (a - A[i]) / (A[j] - A[i])
    share = _share_record(branch)
    if require_share and share is None:
        return float("nan")
    if interpolate:
        if require_share and share[i] + s * (share[j] - share[i]) < _family_share(branch):
            return float("nan")
        return float(f[i] + s * (f[j] - f[i]))
    solver = branch._require_solver()
    u0 = branch.states[i] + s * (branch.states[j] - branch.states[i])
    try:
        u, _, _, _ = solve_at_amplitude(solver, u0, a, tol=tol, max_iter=30)
        record = solver.monitor(u)
    except (PinnedFailure, ArithmeticError, ValueError) as err:
        if require_share:
            return float("nan")
        log.warning("frequency_at(%g): the pinned solve failed (%s); interpolating", a, err)
        return float(f[i] + s * (f[j] - f[i]))
    if require_share and (family_value(record) or 0.0) < _family_share(branch):
        return float("nan")
    return float(record["frequency"])
