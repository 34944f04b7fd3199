"""The starting mode's backbone inside a branch: its family front and exact points on it.

A branch continued with ``follow="family"`` (:mod:`mmshbm.family`) holds, besides
the first-mode backbone, the points of the internal-resonance tongues it followed out and
back (``records["on_family"] = 0``). :func:`family_front` picks the backbone's points;
:func:`frequency_at` solves the backbone at a given amplitude, and returns NaN where the
family does not exist (its starting mode holds less than ``family_share`` of the energy)
or was not sampled (a jump), never a guess across a tongue.
"""

from __future__ import annotations

import logging
import math
import warnings

import numpy as np

from .._warnings import BranchWarning
from ..family.definition import family_value

__all__ = ["family_front", "frequency_at", "family_point", "amplitude_in_m", "warn_outside_front",
           "solve_at"]

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
    amplitude = np.asarray(branch.amplitude, dtype=float).tolist()
    on = np.asarray(on, dtype=bool).tolist()
    for i in range(len(branch)):
        if on[i] and amplitude[i] >= best * (1 - 1e-9):
            front.append(i)
            best = max(best, amplitude[i])
    return np.array(front, dtype=int)


def frequency_at(branch, amplitude: float, *, interpolate: bool = False, tol: float = 1e-10) -> float:
    """Frequency (Hz) of the backbone at ``amplitude`` (m); see
    :meth:`mmshbm.Branch.frequency_at`.

    Between two consecutive front points the point is solved (or interpolated) on that
    segment. Where the front skips (the branch went into a tongue or jumped), the segments
    of the path that leave the last front point and that arrive at the next one are tried:
    a point there counts when the starting mode still holds ``family_share`` of the
    kinetic energy (the family ends inside the segment, not at its sampled end)."""
    return family_point(branch, amplitude, interpolate=interpolate, tol=tol)[0]


def family_point(branch, amplitude: float, *, interpolate: bool = False,
                 tol: float = 1e-10) -> tuple[float, np.ndarray | None]:
    """(frequency (Hz), state) of the backbone at ``amplitude`` (m), found as
    :func:`frequency_at` finds it; the state is the solved point's unknowns (the branch's
    ``states`` layout, for ``branch.solver``'s signals), a stored point's when the
    amplitude is one, None with ``interpolate`` or where the frequency is NaN or was
    interpolated after a failed solve."""
    a = float(amplitude)
    front = family_front(branch)
    A = branch.amplitude
    hit = np.flatnonzero(np.isclose(np.asarray(A)[front], a, rtol=1e-9, atol=0))  # a stored point, the first
    if len(hit):
        i = front[hit[0]]
        return float(branch.frequency[i]), np.asarray(branch.states[i])
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
            if np.isfinite(value[0]):
                return value
        return float("nan"), None
    return float("nan"), None


def amplitude_in_m(branch, amplitude, unit: str) -> float:
    """``amplitude`` in m: as it is for ``unit="m"``, times the branch's gap for
    ``unit="gap"``."""
    if unit not in ("m", "gap"):
        raise ValueError(f"unit must be 'm' or 'gap', got {unit!r}")
    try:
        a = float(amplitude)
    except (TypeError, ValueError):
        raise TypeError(f"amplitude must be a number, got {amplitude!r}") from None
    if unit == "m":
        return a
    gap = branch.gap
    if not gap or gap <= 0:
        raise ValueError("unit='gap' needs a branch whose model has a positive gap; give the amplitude in m")
    return a * gap


def warn_outside_front(branch, amplitude: float, stacklevel: int = 3) -> bool:
    """Warn (:class:`~mmshbm.BranchWarning`) when ``amplitude`` (m) is outside the
    amplitude range of the branch's family front, naming that range in m and in gaps;
    returns whether it warned."""
    front = family_front(branch)
    a = float(amplitude)
    if len(front):
        lo, hi = float(np.min(branch.amplitude[front])), float(np.max(branch.amplitude[front]))
    else:
        lo = hi = math.nan
    if len(front) and math.isfinite(a) and lo * (1 - 1e-9) <= a <= hi * (1 + 1e-9):
        return False
    gap = branch.gap
    if not len(front):
        where = "the branch has no point on its family"
    else:
        where = f"the branch's family spans {lo:.4g}..{hi:.4g} m"
        if gap and gap > 0:
            where += f" ({lo / gap:.4g}..{hi / gap:.4g} gaps)"
    hint = ""
    if gap and gap > 0 and len(front) and math.isfinite(a) and lo <= a * gap <= hi:
        hint = f"; if you meant {a:g} gaps, pass unit='gap' (or {a * gap:.4g} m)"
    warnings.warn(f"frequency_at({a:.4g} m): outside the amplitude range of the backbone, the answer is NaN: "
                  f"{where}{hint}", BranchWarning, stacklevel=stacklevel)
    return True


def _share_record(branch):
    """The branch's family measure per point (:func:`mmshbm.family.definition.family_value`)."""
    from ..family.definition import FAMILY_RECORD

    share = branch.records.get(FAMILY_RECORD)
    return branch.records.get("mode_share") if share is None else share


def _family_share(branch) -> float:
    return float(dict(branch.metadata.get("continuation") or {}).get("family_share", 0.5))


def _on_segment(branch, i: int, j: int, a: float, interpolate: bool, tol: float, *,
                require_share: bool) -> tuple[float, np.ndarray | None]:
    """(frequency, state) of the point at amplitude ``a`` between the branch points i and j
    (A[i] != A[j]); with ``require_share``, NaN unless the starting mode holds the family's
    share there."""
    from ..core.pinned import PinnedFailure, solve_at_amplitude

    nan = (float("nan"), None)
    A, f = branch.amplitude, branch.frequency
    s = (a - A[i]) / (A[j] - A[i])
    share = _share_record(branch)
    if require_share and share is None:
        return nan
    if interpolate:
        if require_share and share[i] + s * (share[j] - share[i]) < _family_share(branch):
            return nan
        return float(f[i] + s * (f[j] - f[i])), None
    solver = branch._require_solver()
    u0 = branch.states[i] + s * (branch.states[j] - branch.states[i])
    try:
        u, _, _, _ = solve_at_amplitude(solver, u0, a, tol=tol, max_iter=30)
        record = solver.monitor(u)
    except (PinnedFailure, ArithmeticError, ValueError) as err:
        if require_share:
            return nan
        log.warning("frequency_at(%g): the pinned solve failed (%s); interpolating", a, err)
        return float(f[i] + s * (f[j] - f[i])), None
    if require_share and (family_value(record) or 0.0) < _family_share(branch):
        return nan
    return float(record["frequency"]), np.asarray(u)


def solve_at(branch, amplitudes, *, tol: float = 1e-10, stand_in: bool = False, stacklevel: int = 3):
    """The backbone's points at ``amplitudes`` (m), solved on the family front as
    :func:`frequency_at` solves them: a branch of the same type, one point per amplitude,
    sharing ``branch``'s solver and model (so its signals, contact force and harmonic
    content are those of the on-family orbits). ``records["requested_amplitude"]`` holds
    the amplitudes asked for, ``records["solved"]`` 1 for a solved point and 0 for one
    the front has not (beyond its ends, inside a skipped interval, or a failed solve).

    Where the front has no point, the entry is what :func:`frequency_at` answers there:
    NaN (frequency, amplitude, energy, force and state), with one
    :class:`~mmshbm.BranchWarning` naming those amplitudes and the front's range. With
    ``stand_in`` the front's stored point nearest in amplitude stands in instead, without
    a warning (the marked points of a plot), and a branch whose solver cannot be rebuilt
    (a file of a model that is not described) gets its stored front points, without a
    solver; without ``stand_in`` such a branch raises the solver's RuntimeError, as
    :func:`frequency_at` does."""
    from dataclasses import replace

    amps = np.atleast_1d(np.asarray(amplitudes, dtype=float))
    front = family_front(branch)
    if not len(front):
        raise ValueError("the branch has no point on its family to mark")
    try:
        solver = branch._require_solver() if len(amps) else None
    except RuntimeError:
        if not stand_in:
            raise
        return _stored_points(branch, front, amps)
    rows, states, solved = [], [], []
    for a in amps:
        f, u = family_point(branch, a, tol=tol) if math.isfinite(a) else (math.nan, None)
        if u is not None and math.isfinite(f):
            solved.append(1)
            states.append(np.asarray(u))
            rows.append(solver.monitor(u))
            continue
        solved.append(0)
        i = int(front[np.argmin(np.abs(branch.amplitude[front] - a))])
        stored = np.asarray(branch.states[i])
        states.append(stored if stand_in else np.full(stored.shape, np.nan))
        rows.append(solver.monitor(states[-1]) if stand_in else None)
    n = len(amps)
    missing = [float(a) for a, ok in zip(amps, solved, strict=True) if not ok]
    if missing and not stand_in:
        _warn_unsolved(branch, front, missing, stacklevel + 1)
    names = next((list(r) for r in rows if r is not None), [])

    def column(name):
        return np.array([math.nan if r is None else r[name] for r in rows], dtype=float)

    records = {"requested_amplitude": amps, "solved": np.array(solved, dtype=int)}
    for name in ("mode_share", "fundamental_share"):
        if name in names:
            records[name] = column(name)
            records["on_family"] = np.array(solved, dtype=float) if not stand_in else np.ones(n)
    return replace(branch, frequency=column("frequency"), amplitude=column("amplitude"),
                   energy=column("energy"), contact_force_max=column("contact_force_max"),
                   newton_iterations=np.zeros(n, dtype=int),
                   step_size=np.zeros(n), states=np.array(states).reshape(n, -1), special_points=[],
                   metadata=dict(branch.metadata), solver=solver, residual_histories=[], model=branch.model,
                   records=records)


def _warn_unsolved(branch, front, amplitudes: list, stacklevel: int) -> None:
    """One BranchWarning for the amplitudes (m) where :func:`solve_at` found no family point."""
    lo, hi = float(np.min(branch.amplitude[front])), float(np.max(branch.amplitude[front]))
    gap = branch.gap
    in_gaps = gap and gap > 0

    def both(a):
        return f"{a:.4g} m ({a / gap:.4g} gaps)" if in_gaps else f"{a:.4g} m"

    outside = [a for a in amplitudes if not (lo * (1 - 1e-9) <= a <= hi * (1 + 1e-9))]
    inside = [a for a in amplitudes if a not in outside]
    parts = []
    if outside:
        parts.append(f"{', '.join(both(a) for a in outside)} outside the amplitude range of the backbone "
                     f"(its family spans {both(lo)}..{both(hi)})")
    if inside:
        parts.append(f"{', '.join(both(a) for a in inside)} where the starting mode's family has no point "
                     "(an internal-resonance tongue the branch jumped or passed, or a failed solve)")
    warnings.warn(f"solve_at: no backbone point at {'; '.join(parts)}: those entries are NaN "
                  "(records['solved'] = 0); stand_in=True puts the nearest family point there instead",
                  BranchWarning, stacklevel=stacklevel)


def _stored_points(branch, front, amps):
    """solve_at without a solver: the front's stored points nearest to ``amps``."""
    from dataclasses import replace

    idx = np.array([int(front[np.argmin(np.abs(branch.amplitude[front] - a))]) for a in amps], dtype=int)
    n = len(idx)
    records = {"requested_amplitude": amps, "solved": np.zeros(n, dtype=int)}
    return replace(branch, frequency=branch.frequency[idx], amplitude=branch.amplitude[idx],
                   energy=branch.energy[idx], contact_force_max=branch.contact_force_max[idx],
                   newton_iterations=np.zeros(n, dtype=int), step_size=np.zeros(n),
                   states=np.asarray(branch.states)[idx].reshape(n, -1), special_points=[],
                   metadata=dict(branch.metadata), solver=None, residual_histories=[], model=branch.model,
                   records=records)
