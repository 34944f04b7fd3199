"""What a study run with a tolerance (``run_study(..., tol=...)``, ``mmshbm study --tol``)
reports: the H that ``tol`` chose at each table cell, whether every run met it, and the
mesh error at the table's amplitudes (:mod:`mmshbm.analysis.mesh_error`).

With ``tol`` the study's ``harmonics`` axis is the start H of each run
(``start_harmonics`` of :func:`mmshbm.backbone`); the H a cell needed is that of its
branch's points at the cell's amplitude (:func:`cell_harmonics`).

The mesh error is computed for every series of runs that differ in their element count
only (three meshes or more), at every table amplitude, from the frequencies of the table.
"""

from __future__ import annotations

import numpy as np

from .mesh_error import MeshCriteria, MeshError, mesh_error

__all__ = ["cell_harmonics", "cell_estimates", "study_mesh_errors", "tolerance_lines", "mesh_error_lines"]


def cell_harmonics(study, amplitudes, unit: str = "gap") -> np.ndarray:
    """The H each run used at each amplitude, shape (n_runs, n_amplitudes): the larger H
    of the two family-front points around the amplitude (``records["harmonics"]``; the
    run's H without a tolerance); -1 where the front does not reach it."""
    return _cells(study, amplitudes, unit, lambda b: np.asarray(
        b.records.get("harmonics", np.full(len(b), b.harmonics)), dtype=int), -1, np.max).astype(int)


def cell_estimates(study, amplitudes, unit: str = "gap") -> np.ndarray:
    """The larger estimate (:func:`~mmshbm.results.tolerance_checks.point_estimate`) of
    the two family-front points around each amplitude, shape (n_runs, n_amplitudes); NaN
    where not estimated or not reached."""
    from ..results.tolerance_checks import point_estimate

    return _cells(study, amplitudes, unit, point_estimate, np.nan, lambda v: np.max(v))


def _cells(study, amplitudes, unit, per_point, fill, reduce) -> np.ndarray:
    amps = np.atleast_1d(np.asarray(amplitudes, dtype=float))
    out = np.full((len(study.branches), len(amps)), fill, dtype=float)
    for r, b in enumerate(study.branches):
        if not len(b):
            continue
        front = np.asarray(b.family_front(), dtype=int)
        a = np.asarray(b.amplitude, dtype=float)[front]
        H = np.asarray(per_point(b))[front]
        scale = float(b.gap) if unit == "gap" and b.gap else 1.0
        for j, x in enumerate(amps * scale):
            k = int(np.searchsorted(a, x))
            if 0 < k < len(a) or (k < len(a) and a[k] == x):
                out[r, j] = reduce(H[max(k - 1, 0):k + 1])
    return out


def study_mesh_errors(table, criteria: MeshCriteria | None = None) -> list[tuple[dict, float, MeshError]]:
    """(coordinates of the series without ``elements``, amplitude, MeshError) for every
    series of the table's runs that differ in their element count only, at every
    amplitude; empty without an ``elements`` axis or with fewer than three meshes."""
    if "elements" not in table.axes:
        return []
    groups: dict = {}
    for r, coords in enumerate(table.runs):
        key = _key(coords)
        groups.setdefault(key, []).append(r)
    out = []
    for rows in groups.values():
        if len(rows) < 3:
            continue
        rows = sorted(rows, key=lambda r: table.runs[r]["elements"])
        n = [int(table.runs[r]["elements"]) for r in rows]
        coords = {k: v for k, v in table.runs[rows[0]].items() if k != "elements"}
        for j, amp in enumerate(np.asarray(table.amplitudes, dtype=float)):
            out.append((coords, float(amp), mesh_error(n, table.frequency[rows, j], criteria)))
    return out


def tolerance_lines(study) -> list[str]:
    """One line per run computed with a tolerance
    (:func:`~mmshbm.results.tolerance_checks.tolerance_summary`), preceded by a count;
    empty when no run has one."""
    from ..results.tolerance_checks import tolerance_summary, unmet_points

    lines, met = [], 0
    for coords, b in zip(study.runs, study.branches, strict=True):
        s = tolerance_summary(b)
        if s is None:
            continue
        met += not len(unmet_points(b))
        lines.append(f"  {_coords(coords)}: {s}")
    if not lines:
        return []
    return [f"tolerance met at every point in {met} of {len(lines)} runs", *lines]


def mesh_error_lines(table, criteria: MeshCriteria | None = None, study=None) -> list[str]:
    """The mesh errors of :func:`study_mesh_errors`, one line per series and amplitude;
    with ``study`` (run with ``tol``), a series whose cells do not all meet the tolerance
    is flagged: its differences mix the truncation in H into the mesh's."""
    unit = "gaps" if table.unit == "gap" else "m"
    unmet = set()
    if study is not None:
        from ..results.tolerance_checks import tolerance_of

        est = cell_estimates(study, table.amplitudes, table.unit)
        for r, b in enumerate(study.branches):
            tol = tolerance_of(b)
            for j in range(len(table.amplitudes)):
                if tol is not None and not est[r, j] <= tol:
                    unmet.add((_key(study.runs[r]), j))
    lines = []
    for c, a, me in study_mesh_errors(table, criteria):
        j = int(np.flatnonzero(np.asarray(table.amplitudes, dtype=float) == a)[0])
        flag = ("; the tolerance is not met at every cell of the series: the differences include the "
                "truncation in H" if (_key(c), j) in unmet else "")
        lines.append(f"  {_coords(c)} at {a:g} {unit}: {me.describe()}{flag}")
    return lines


def _key(coords: dict) -> tuple:
    return tuple((k, repr(v)) for k, v in coords.items() if k != "elements")


def _coords(coords: dict) -> str:
    return ", ".join(f"{k}={v}" for k, v in coords.items())
