"""Tables of a study: frequencies at chosen amplitudes per run, and observed convergence
rates fitted on them (:meth:`mmshbm.analysis.studies.Study.table`, ``.convergence``)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..results.diagnostics import incomplete_reason

__all__ = ["FrequencyTable", "ConvergenceFit", "format_convergence", "summarize", "coords_text"]


@dataclass
class FrequencyTable:
    """Frequency (Hz) of each run at chosen amplitudes.

    Attributes
    ----------
    axes : list of str
        Coordinate names (columns before the frequencies).
    runs : list of dict
        Coordinates per row.
    amplitudes : ndarray, shape (n_amplitudes,)
    unit : {"gap", "m"}
        Unit of ``amplitudes``.
    frequency : ndarray, shape (n_runs, n_amplitudes)
        Hz; NaN where the branch never reaches the amplitude.
    status : list of str
        Each branch's status.
    """

    axes: list
    runs: list
    amplitudes: np.ndarray
    unit: str
    frequency: np.ndarray
    status: list

    def _amp_label(self, a: float) -> str:
        return f"f_at_{a:g}{'gap' if self.unit == 'gap' else 'm'}_hz"

    def to_csv(self, path) -> Path:
        """Write the table (one header line; frequencies with 10 significant digits)."""
        path = Path(path)
        header = [*self.axes, *(self._amp_label(a) for a in self.amplitudes), "status"]
        lines = [",".join(header)]
        for r, f, s in zip(self.runs, self.frequency, self.status, strict=True):
            lines.append(",".join([*(str(r.get(a, "")) for a in self.axes),
                                   *("nan" if not np.isfinite(x) else f"{x:.10g}" for x in f), s]))
        path.write_text("\n".join(lines) + "\n")
        return path

    def to_text(self) -> str:
        """A fixed-width text table."""
        unit = "gaps" if self.unit == "gap" else "m"
        head = [*self.axes, *(f"A={a:g}" for a in self.amplitudes), "status"]
        rows = [[*(str(r.get(a, "")) for a in self.axes),
                 *(f"{x:.3f}" if np.isfinite(x) else "-" for x in f), s]
                for r, f, s in zip(self.runs, self.frequency, self.status, strict=True)]
        widths = [max(len(h), *(len(row[i]) for row in rows)) if rows else len(h) for i, h in enumerate(head)]
        fmt = "  ".join(f"{{:>{w}}}" for w in widths)
        title = f"Frequency (Hz) at tip amplitude A ({unit}); '-' = not reached"
        return "\n".join([title, fmt.format(*head), *(fmt.format(*row) for row in rows)])

    def pivot(self, amplitude_index: int = 0, rows: str = "elements", columns: str = "harmonics") -> tuple:
        """The frequencies at one amplitude as a matrix over two coordinates.

        Runs that differ in any other coordinate must not collide (one value per cell).

        Returns
        -------
        row_values : list, shape (n_rows,)
        column_values : list, shape (n_columns,)
        frequency : ndarray, shape (n_rows, n_columns)
            Hz; NaN for missing runs or amplitudes not reached.

        Raises
        ------
        ValueError
            If ``rows`` or ``columns`` is not a coordinate, or two runs fall in one cell.
        """
        for name in (rows, columns):
            if name not in self.axes:
                raise ValueError(f"{name!r} is not a coordinate of the table; it has {self.axes}")
        rv = sorted({r[rows] for r in self.runs})
        cv = sorted({r[columns] for r in self.runs})
        f = np.full((len(rv), len(cv)), np.nan)
        seen = set()
        for r, row in zip(self.runs, self.frequency, strict=True):
            cell = (rv.index(r[rows]), cv.index(r[columns]))
            if cell in seen:
                raise ValueError(f"several runs have {rows}={r[rows]}, {columns}={r[columns]}: select first")
            seen.add(cell)
            f[cell] = row[amplitude_index]
        return rv, cv, f

    def pivot_text(self, rows: str = "elements", columns: str = "harmonics") -> str:
        """Text matrices (one per amplitude) of :meth:`pivot`, e.g. elements × H; empty
        when other coordinates vary too."""
        unit = "gaps" if self.unit == "gap" else "m"
        blocks = []
        for j, a in enumerate(self.amplitudes):
            try:
                rv, cv, f = self.pivot(j, rows, columns)
            except ValueError:
                return ""
            head = [f"{rows} \\ {columns}", *(str(c) for c in cv)]
            body = [[str(r), *(f"{x:.3f}" if np.isfinite(x) else "-" for x in fr)]
                    for r, fr in zip(rv, f, strict=True)]
            widths = [max(len(h), *(len(b[i]) for b in body)) for i, h in enumerate(head)]
            fmt = "  ".join(f"{{:>{w}}}" for w in widths)
            blocks.append("\n".join([f"f (Hz) at A = {a:g} {unit}", fmt.format(*head),
                                     *(fmt.format(*b) for b in body)]))
        return "\n\n".join(blocks)

    def __str__(self) -> str:
        return self.to_text()


@dataclass
class ConvergenceFit:
    """Observed convergence of one series of runs at one amplitude.

    Attributes
    ----------
    vary : {"harmonics", "elements"}
        The refined quantity.
    fixed : dict
        The other coordinates of the series.
    amplitude : float
        The amplitude (in ``unit``) the frequencies are taken at.
    unit : {"gap", "m"}
    values : ndarray, shape (n,)
        H or element counts, ascending; the last is the reference.
    frequency : ndarray, shape (n,)
        Frequencies (Hz) at ``amplitude``.
    difference : ndarray, shape (n,)
        |f − f_ref| (Hz); 0 for the reference.
    rate : float
        p in |f − f_ref| ∝ value^(−p), least squares in log–log over the non-reference
        runs; NaN with fewer than two usable runs.
    n_fit : int
        Number of runs in the fit.
    note : str
        Why runs are missing (e.g. the reference run stopped short of the amplitude).
    """

    vary: str
    fixed: dict
    amplitude: float
    unit: str
    values: np.ndarray
    frequency: np.ndarray
    difference: np.ndarray
    rate: float
    n_fit: int
    note: str = ""

    @classmethod
    def fit(cls, vary, fixed, amplitude, unit, values, frequency) -> ConvergenceFit:
        values = np.asarray(values, dtype=float)
        frequency = np.asarray(frequency, dtype=float)
        diff = np.abs(frequency - frequency[-1])
        use = np.isfinite(diff[:-1]) & (diff[:-1] > 1e-12 * abs(frequency[-1]))
        if not np.isfinite(frequency[-1]):
            use[:] = False
        rate = float("nan")
        if use.sum() >= 2:
            slope = np.polyfit(np.log(values[:-1][use]), np.log(diff[:-1][use]), 1)[0]
            rate = float(-slope)
        return cls(vary, dict(fixed), amplitude, unit, values, frequency, diff, rate, int(use.sum()))

    @property
    def reference(self) -> float:
        """The finest value of the series (the reference run)."""
        return float(self.values[-1])


def format_convergence(fits: Sequence[ConvergenceFit]) -> str:
    """Text table of convergence fits."""
    lines = ["Observed convergence rate p, |f - f_ref| ~ x^(-p), x = H or elements; reference = the finest "
             "run of each series (not the exact solution); p from a log-log least-squares fit "
             "(two points: a two-point slope)"]
    head = ("vary", "fixed", "A", "x", "|f - f_ref| (Hz)", "p", "note")
    rows = []
    for fit in fits:
        fixed = " ".join(f"{k}={v}" for k, v in fit.fixed.items())
        xs = ",".join(f"{v:g}" for v in fit.values)
        diffs = ",".join("-" if not np.isfinite(d) else f"{d:.3g}" for d in fit.difference[:-1])
        unit = "gap" if fit.unit == "gap" else "m"
        rows.append((fit.vary, fixed, f"{fit.amplitude:g} {unit}", xs, diffs,
                     "-" if math.isnan(fit.rate) else f"{fit.rate:.2f}", fit.note))
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(head)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    return "\n".join([lines[0], fmt.format(*head), *(fmt.format(*r) for r in rows)])


def coords_text(coords: dict) -> str:
    """``{"harmonics": 7, "elements": 21}`` -> ``"harmonics=7, elements=21"``."""
    return ", ".join(f"{k}={v}" for k, v in coords.items())


def summarize(runs: Sequence[dict], branches: Sequence) -> str:
    """How many runs reached their bounds, which did not and why (with the amplitude
    they stopped at), and what the branch checks found (``branch.findings``)."""
    done = sum(b.completed for b in branches)
    lines = [f"{len(runs)} runs: {done} reached their bounds, {len(runs) - done} incomplete"]
    for coords, b in zip(runs, branches, strict=True):
        if not b.completed:
            lines.append(f"  incomplete: {coords_text(coords)}: {_reached(b)}"
                         f"{incomplete_reason(b.status, b.metadata)} (status {b.status!r})")
    for coords, b in zip(runs, branches, strict=True):
        found = [_short(f) for f in b.findings if f.kind != "incomplete"]
        if found:
            lines.append(f"  checks: {coords_text(coords)}: {'; '.join(found)}")
    return "\n".join(lines)


def _short(finding) -> str:
    v = finding.value
    if finding.kind == "left_family":
        return f"left its mode's family at points {finding.first}..{finding.last} (share down to {v:.2g})"
    if finding.kind == "penetration":
        return f"contact DOF through the stop by up to {v:.3g} gaps"
    if finding.kind == "negative_force":
        return f"contact force pulls, down to {abs(v):.3g} of its peak"
    return finding.kind


def _reached(branch) -> str:
    if not len(branch):
        return "no point, "
    gap = branch.gap
    a = float(np.nanmax(branch.amplitude))
    return f"stopped at {a / gap:.3g} gaps, " if gap else f"stopped at {a:.3g} m, "


def missing_note(vary: str, runs: Sequence[dict], branches: Sequence, frequency) -> str:
    """Why runs of a convergence series have no frequency at the amplitude (NaN entries of
    ``frequency``): they never reach it, and why they stopped when they are incomplete."""
    notes = []
    for r, b, f in zip(runs, branches, frequency, strict=True):
        if not np.isfinite(f):
            why = "" if b.completed else f" ({incomplete_reason(b.status, b.metadata)})"
            notes.append(f"{vary}={r[vary]} does not reach it{why}")
    return "; ".join(notes)
