"""Tables of a study: frequencies at chosen amplitudes per run, with the reason for every
empty cell and a caution where a value sits next to a jump of the family
(:meth:`mmshbm.analysis.studies.Study.table`), and a summary per run of what its
continuation met (:func:`format_cells`). Convergence fits: :mod:`mmshbm.analysis.convergence`."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.status import Status
from ..results.diagnostics import incomplete_reason

__all__ = ["FrequencyTable", "format_cells", "summarize", "coords_text", "series_note"]


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
        Hz; NaN where the branch's family front has no value (not reached, or inside a
        skipped internal-resonance tongue: see ``notes``).
    status : list of str
        Each branch's status.
    notes : list of list of str, shape (n_runs, n_amplitudes)
        Why a cell is NaN (which named resonance it lies in, or why the run stopped), or a
        caution for a finite value next to a discontinuity of the family; "" otherwise
        (:func:`mmshbm.analysis.skips.explain`).
    mode_share : ndarray, shape (n_runs, n_amplitudes)
        The starting mode's share of the kinetic energy at the cell (interpolated between
        the neighbouring front points); NaN where unknown.
    partner : list of list, shape (n_runs, n_amplitudes)
        The strongest other mode at the cell, (k, j, share): harmonic k of mode j holds
        that share of the kinetic energy (e.g. (5, 2, 0.32) on the 5:2 internal
        resonance); None where unknown.
    """

    axes: list
    runs: list
    amplitudes: np.ndarray
    unit: str
    frequency: np.ndarray
    status: list
    notes: list = field(default_factory=list)
    mode_share: np.ndarray | None = None
    partner: list = field(default_factory=list)

    def __post_init__(self):
        n, m = np.shape(self.frequency)
        if not self.notes:
            self.notes = [[""] * m for _ in range(n)]
        if not self.partner:
            self.partner = [[None] * m for _ in range(n)]
        if self.mode_share is None:
            self.mode_share = np.full((n, m), np.nan)

    def _amp_label(self, a: float) -> str:
        return f"{a:g}{'gap' if self.unit == 'gap' else 'm'}"

    def to_csv(self, path) -> Path:
        """Write the table: coordinates, ``f_at_<A>_hz`` per amplitude (10 significant
        digits, ``nan`` for empty cells), status, ``mode_share_at_<A>``, ``partner_at_<A>``
        ("k:j share", the strongest other mode) and ``note_at_<A>`` (why a cell is empty, or
        a caution; quoted)."""
        path = Path(path)
        labels = [self._amp_label(a) for a in self.amplitudes]
        header = [*self.axes, *(f"f_at_{x}_hz" for x in labels), "status",
                  *(f"mode_share_at_{x}" for x in labels), *(f"partner_at_{x}" for x in labels),
                  *(f"note_at_{x}" for x in labels)]
        lines = [",".join(header)]
        for r, f, s, sh, pa, nt in zip(self.runs, self.frequency, self.status, self.mode_share, self.partner,
                                       self.notes, strict=True):
            lines.append(",".join([*(str(r.get(a, "")) for a in self.axes),
                                   *("nan" if not np.isfinite(x) else f"{x:.10g}" for x in f), _quote(s),
                                   *("nan" if not np.isfinite(x) else f"{x:.4f}" for x in sh),
                                   *(_partner(p) for p in pa), *(_quote(t) for t in nt)]))
        path.write_text("\n".join(lines) + "\n")
        return path

    def to_text(self) -> str:
        """A fixed-width text table, one row per run, with a note column."""
        unit = "gaps" if self.unit == "gap" else "m"
        head = [*self.axes, *(f"A={a:g}" for a in self.amplitudes), "status", "notes"]
        rows = []
        for r, f, s, nt in zip(self.runs, self.frequency, self.status, self.notes, strict=True):
            notes = "; ".join(f"A={a:g}: {t}" for a, t in zip(self.amplitudes, nt, strict=True) if t)
            rows.append([*(str(r.get(a, "")) for a in self.axes),
                         *(_cell(x, t) for x, t in zip(f, nt, strict=True)), s, notes])
        widths = [max(len(h), *(len(row[i]) for row in rows)) if rows else len(h) for i, h in enumerate(head)]
        fmt = "  ".join(f"{{:>{w}}}" for w in widths[:-1]) + "  {}"
        title = (f"Frequency (Hz) at tip amplitude A ({unit}) on the family front; '-' = no value "
                 "(see notes), '*' = next to a jump of the family")
        return "\n".join([title, fmt.format(*head), *(fmt.format(*row).rstrip() for row in rows)])

    def pivot(self, amplitude_index: int = 0, rows: str = "elements", columns: str = "harmonics") -> tuple:
        """The frequencies at one amplitude as a matrix over two coordinates.

        Runs that differ in any other coordinate must not collide (one value per cell).

        Returns
        -------
        row_values : list, shape (n_rows,)
        column_values : list, shape (n_columns,)
        frequency : ndarray, shape (n_rows, n_columns)
            Hz; NaN for missing runs or cells without a value.

        Raises
        ------
        ValueError
            If ``rows`` or ``columns`` is not a coordinate, or two runs fall in one cell.
        """
        rv, cv, cells = self._cells(rows, columns)
        f = np.full((len(rv), len(cv)), np.nan)
        for cell, k in cells.items():
            f[cell] = self.frequency[k, amplitude_index]
        return rv, cv, f

    def _cells(self, rows: str, columns: str) -> tuple:
        for name in (rows, columns):
            if name not in self.axes:
                raise ValueError(f"{name!r} is not a coordinate of the table; it has {self.axes}")
        rv = sorted({r[rows] for r in self.runs})
        cv = sorted({r[columns] for r in self.runs})
        cells: dict = {}
        for k, r in enumerate(self.runs):
            cell = (rv.index(r[rows]), cv.index(r[columns]))
            if cell in cells:
                raise ValueError(f"several runs have {rows}={r[rows]}, {columns}={r[columns]}: select first")
            cells[cell] = k
        return rv, cv, cells

    def pivot_text(self, rows: str = "elements", columns: str = "harmonics", *,
                   markdown: bool = False) -> str:
        """Matrices (one per amplitude) of :meth:`pivot`, e.g. elements × H, with numbered
        footnotes for empty cells (why) and cautioned values; "" when other coordinates
        vary too. ``markdown`` gives Markdown tables."""
        unit = "gaps" if self.unit == "gap" else "m"
        try:
            rv, cv, cells = self._cells(rows, columns)
        except ValueError:
            return ""
        blocks = []
        for j, a in enumerate(self.amplitudes):
            notes: list[str] = []
            body = []
            for r_i, r in enumerate(rv):
                line = [str(r)]
                for c_i in range(len(cv)):
                    k = cells.get((r_i, c_i))
                    if k is None:
                        line.append("")
                        continue
                    x, t = self.frequency[k, j], self.notes[k][j]
                    text = f"{x:.3f}" if np.isfinite(x) else ("—" if markdown else "-")
                    if t:
                        notes.append(f"[{len(notes) + 1}] {columns}={self.runs[k][columns]}, "
                                     f"{rows}={self.runs[k][rows]}: {t}")
                        text += f"[{len(notes)}]"
                    line.append(text)
                body.append(line)
            head = [f"{rows} \\ {columns}", *(str(c) for c in cv)]
            title = f"f (Hz) at A = {a:g} {unit}"
            shares = [[str(r)] + [_share(self, cells.get((r_i, c_i)), j) for c_i in range(len(cv))]
                      for r_i, r in enumerate(rv)]
            share_title = (f"first mode's share of the kinetic energy at A = {a:g} {unit} "
                           "(strongest other: harmonic k of mode j, k:j, and its share)")
            if markdown:
                blocks.append("\n".join([f"**{title}**", "", *_markdown(head, body), "", *notes]))
            else:
                blocks.append("\n".join([title, *_fixed(head, body), *notes, "", share_title,
                                         *_fixed(head, shares)]))
        return "\n\n".join(blocks)

    def __str__(self) -> str:
        return self.to_text()


def _fixed(head: list, body: list) -> list[str]:
    widths = [max(len(h), *(len(b[i]) for b in body)) for i, h in enumerate(head)]
    fmt = "  ".join(f"{{:>{w}}}" for w in widths)
    return [fmt.format(*head), *(fmt.format(*b) for b in body)]


def _markdown(head: list, body: list) -> list[str]:
    return ["| " + " | ".join(head) + " |", "|" + "---|" * len(head),
            *("| " + " | ".join(b) + " |" for b in body)]


def _share(table: FrequencyTable, k, j: int) -> str:
    if k is None or not np.isfinite(table.mode_share[k, j]):
        return "-"
    p = table.partner[k][j]
    return f"{table.mode_share[k, j]:.2f}" + (f" ({p[0]}:{p[1]} {p[2]:.2f})" if p and p[2] >= 0.01 else "")


def _partner(p) -> str:
    return "" if p is None else f"{p[0]}:{p[1]} {p[2]:.4f}"


def _cell(x: float, note: str) -> str:
    if not np.isfinite(x):
        return "-"
    return f"{x:.3f}" + ("*" if note else "")


def _quote(text: str) -> str:
    if any(c in text for c in ',"\n'):
        return '"' + text.replace('"', '""') + '"'
    return text


def format_cells(runs: Sequence[dict], branches: Sequence, axes: Sequence[str]) -> str:
    """Text table, one row per run: points (on the family), jumps, the skipped amplitude
    intervals wider than 0.1 % of their end (gaps, with the internal resonance k:j found in
    each), the internal resonances named along the branch (k:j: harmonic k meets mode j),
    the run's wall time and status (:func:`mmshbm.analysis.skips.cell_summary`)."""
    from .skips import cell_summary

    head = [*axes, "points", "on family", "jumps", "skipped (gaps, k:j)", "resonances k:j", "time (s)",
            "status"]
    rows = []
    for r, b in zip(runs, branches, strict=True):
        c = cell_summary(b)
        skipped = ", ".join(f"{lo:.3g}-{hi:.3g}" + (f" ({kj[0]}:{kj[1]})" if kj else "")
                            for lo, hi, kj in c["skipped"]) or "-"
        rows.append([*(str(r.get(a, "")) for a in axes), str(c["points"]), str(c["on_family"]),
                     str(c["jumps"]), skipped, " ".join(c["resonances"]) or "-",
                     "-" if not np.isfinite(c["elapsed_s"]) else f"{c['elapsed_s']:.2f}", c["status"]])
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(head)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    title = ("Per run: points on the family, jumps, amplitude intervals the family front skips "
             "(frequency_at is NaN inside), internal resonances named (k:j: harmonic k meets mode j)")
    return "\n".join([title, fmt.format(*head).rstrip(), *(fmt.format(*r).rstrip() for r in rows)])


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


def series_note(vary: str, runs: Sequence[dict], frequency, notes: Sequence[str]) -> str:
    """The table's notes on the cells of a convergence series: why runs have no frequency
    at the amplitude, and cautions on values next to a jump of the family."""
    out = []
    for r, f, note in zip(runs, frequency, notes, strict=True):
        if not np.isfinite(f) or note:
            out.append(f"{vary}={r[vary]}: {note or 'no value'}")
    return "; ".join(out)


# ---------------------------------------------------------------------- findings
def run_label(coords: dict, axes: Sequence[str]) -> str:
    """The short name of a run by the coordinates that vary, e.g. "H5, 21 el."."""
    parts = []
    for k in axes:
        v = coords.get(k)
        parts.append(f"H{v}" if k == "harmonics" else f"{v} el." if k == "elements" else
                     str(v) if k == "method" else f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}")
    return ", ".join(parts) or "run"


def findings_table(runs: Sequence[dict], branches: Sequence, axes: Sequence[str]) -> str:
    """One row per run, what a reader must know before using it: status (complete, or
    where and why it stopped), family (points off the starting mode's family, kept in the
    arrays and left out of the backbone), truncation effects of the Fourier series (the
    contact DOF through the stop, in gaps; the contact force pulling, as a share of its
    peak), skipped amplitude intervals of the family front (gaps, with the internal
    resonance k:j), and the count of the run's other warnings (in :func:`run_details`). A run
    whose family front stops short of its end is named "another family above A gaps"."""
    from .skips import cell_summary

    head = ["run", "status", "family", "truncation effects", "skipped (gaps)", "notes"]
    rows = []
    for coords, b in zip(runs, branches, strict=True):
        kinds = {f.kind: f for f in b.findings}
        c = cell_summary(b)
        status = "complete" if b.completed else f"short: {_reached(b).removesuffix(', ')}, {_short_status(b)}"
        off = c["points"] - c["on_family"] if "on_family" in b.records else 0
        if not off and "left_family" in kinds:
            f = kinds["left_family"]
            off = f.last - f.first + 1
        family = f"{off} of {c['points']} points off" if off else "on"
        front = b.family_front() if len(b) else []
        if len(front) and b.amplitude[front].max() < b.amplitude.max() * (1 - 1e-9):
            top = float(b.amplitude[front].max())
            family = f"another family above {top / b.gap:.3g} gaps" if b.gap else \
                f"another family above {top:.3g} m"
        trunc = []
        if "penetration" in kinds:
            trunc.append(f"stop passed {kinds['penetration'].value:.2g} gaps")
        if "negative_force" in kinds:
            trunc.append(f"λ pulls {abs(kinds['negative_force'].value):.2g} of peak")
        skipped = [f"{lo:.3g}-{hi:.3g}" + (f" ({kj[0]}:{kj[1]})" if kj else "")
                   for lo, hi, kj in c["skipped"]]
        if len(skipped) > 2:
            skipped = [*skipped[:2], f"+{len(skipped) - 2}"]
        extra = len(b.metadata.get("run_warnings", ()))
        rows.append([run_label(coords, axes), status, family, ", ".join(trunc) or "-",
                     ", ".join(skipped) or "-", f"{extra} warning{'s' * (extra != 1)}" if extra else "-"])
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(head)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    return "\n".join(fmt.format(*r).rstrip() for r in [head, *rows])


def findings_count(runs: Sequence[dict], branches: Sequence) -> str:
    """One line: runs that reached their bounds, incomplete, off the family, with
    truncation effects, with skipped intervals, with other warnings."""
    from .skips import cell_summary

    n = len(runs)
    done = sum(b.completed for b in branches)
    kinds = [{f.kind for f in b.findings} for b in branches]
    parts = [f"{n} runs: {done} reached their bounds, {n - done} incomplete"]
    counts = [("{} left the family (excursions kept in the arrays)", sum("left_family" in k for k in kinds)),
              ("{} with truncation effects", sum(bool({"penetration", "negative_force"} & k) for k in kinds)),
              ("{} with skipped intervals", sum(bool(cell_summary(b)["skipped"]) for b in branches)),
              ("{} with other warnings", sum(bool(b.metadata.get("run_warnings")) for b in branches))]
    parts += [what.format(count) for what, count in counts if count]
    return "; ".join(parts)


def run_details(runs: Sequence[dict], branches: Sequence) -> str:
    """Every finding and every other warning of every run, one line each, under the run's
    coordinates (the study's details, written to its report)."""
    lines = ["Details per run: what the checks found and the run's other warnings"]
    for coords, b in zip(runs, branches, strict=True):
        found = [f.message for f in b.findings] + list(b.metadata.get("run_warnings", ()))
        if found:
            lines.append(f"run {coords_text(coords)}:")
            lines += [f"  {m}" for m in found]
    return "\n".join(lines) if len(lines) > 1 else ""


def _short_status(branch) -> str:
    key = Status.parse(branch.status).kind
    return "step budget" if key == "max_steps" else key.replace("_", " ")
