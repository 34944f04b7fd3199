"""The benchmark tables of docs/validation.md and docs/benchmarks.md, from one recorded run of
the airspeed-velocity suite (``benchmarks/bench_goals.py``, ``bench_studies.py`` and the
model-size and forced benchmarks of :data:`RECORD_BENCH`).

``python -m validation tables`` prints them (with the other tables of docs/validation.md);
``--update docs/validation.md docs/benchmarks.md`` writes them between the markers
:data:`BEGIN` and :data:`END` of each file, so that the published figures are those of
one recorded run and say which (commit, machine, date)::

    OPENBLAS_NUM_THREADS=1 asv run --python=same --set-commit-hash $(git rev-parse HEAD) \\
        --bench "RECORD_BENCH"
    python -m validation tables --update docs/validation.md docs/benchmarks.md

with :data:`RECORD_BENCH` spelled out (docs/validation.md, docs/benchmarks.md). Rows of benchmarks
the run did not record are left out.

``RESULTS`` is an asv results file (``.asv/results/<machine>/<commit>-<env>.json``) or a
folder of them (default: the most recent file that holds the ``bench_goals`` figures
under ``.asv/results``, asv's own folder, ignored by git, and ``benchmarks/results``, the
recorded run the published tables come from, committed)::

    mkdir -p benchmarks/results/vm && cp .asv/results/benchmarks.json benchmarks/results/ \
        && cp .asv/results/vm/<commit>-<env>.json .asv/results/vm/machine.json benchmarks/results/vm/
"""

from __future__ import annotations

import ast
import datetime as _dt
import itertools
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["AsvRun", "DEFAULT_FOLDERS", "RECORD_BENCH", "find_results", "load_run", "goal_table",
           "equal_accuracy_table", "tables", "update_file", "BEGIN", "END"]

#: markers of the generated block in a Markdown file
BEGIN = "<!-- begin: tables from asv (python -m validation tables --update) -->"
END = "<!-- end: tables from asv -->"

#: the ``asv run --bench`` regex of the recorded run: the goal and study suites and the
#: model-size and forced benchmarks of the goal table
RECORD_BENCH = (r"bench_goals|bench_studies|BackboneScaleRatios"
                r"|(ModalReduction|Solid)Scale\.(time|peakmem)_reduction|ForcedHarmonics\.(time_response|track_end)|EPMCBudget\.(time|track_epmc_h20_max)")

_PREFIX = "bench_goals."
_METHODS = {"mmshbm": "MMS-HBM", "penalty": "penalty-HBM", "shooting": "shooting"}


@dataclass
class AsvRun:
    """The results of one ``asv run`` for one commit and environment."""

    path: Path
    commit: str
    date: _dt.datetime
    machine: dict
    values: dict = field(default_factory=dict)  # (benchmark name, params tuple) -> value
    units: dict = field(default_factory=dict)  # benchmark name -> unit

    def value(self, name: str, *params) -> float:
        """The result of ``name`` (without the ``bench_goals.`` prefix allowed) for
        ``params``; NaN when missing, skipped or failed."""
        if not name.startswith("bench_"):
            name = _PREFIX + name
        v = self.values.get((name, tuple(str(p) for p in params)))
        return float(v) if isinstance(v, int | float) else math.nan

    def names(self, prefix: str) -> list[str]:
        return sorted({n for n, _ in self.values if n.startswith(prefix)})


#: where the results are looked for by default: asv's folder, then the committed record
DEFAULT_FOLDERS = (Path(".asv/results"), Path("benchmarks/results"))


def find_results(path=None) -> Path:
    """The results file: ``path`` itself, or the most recent file under ``path`` (default
    :data:`DEFAULT_FOLDERS`, those that exist) that holds ``bench_goals`` figures."""
    if path is None:
        folders = [f for f in DEFAULT_FOLDERS if f.is_dir()]
        if not folders:
            raise FileNotFoundError(f"no asv results in {' or '.join(map(str, DEFAULT_FOLDERS))} (run asv "
                                    "first, see docs/benchmarks.md)")
    else:
        path = Path(path)
        if path.is_file():
            return path
        if not path.is_dir():
            raise FileNotFoundError(f"no asv results at {path} (run asv first, see docs/benchmarks.md)")
        folders = [path]
    best, best_date = None, -1
    for f in (f for folder in folders for f in folder.rglob("*.json")):
        if f.name in ("machine.json", "benchmarks.json"):
            continue
        try:
            data = json.loads(f.read_text())
        except (OSError, ValueError):
            continue
        if any(k.startswith(_PREFIX) for k in data.get("results", {})) and data.get("date", 0) > best_date:
            best, best_date = f, data.get("date", 0)
    if best is None:
        where = " or ".join(map(str, folders))
        raise FileNotFoundError(f"no asv results with bench_goals figures under {where}")
    return best


def _param(text: str):
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return text


def load_run(path=None) -> AsvRun:
    """Read an asv results file (format version 2) and the units of its benchmarks."""
    f = find_results(path)
    data = json.loads(f.read_text())
    if data.get("version") != 2:
        raise ValueError(f"{f}: asv results format version {data.get('version')!r}, expected 2")
    columns = data["result_columns"]
    i_result, i_params = columns.index("result"), columns.index("params")
    values = {}
    for name, entry in data["results"].items():
        results = entry[i_result]
        params = entry[i_params] or []
        combos = list(itertools.product(*params)) if params else [()]
        if not isinstance(results, list):
            results = [results]
        for combo, v in zip(combos, results, strict=False):
            values[(name, tuple(str(_param(p)) for p in combo))] = v
    units = {}
    meta = f.parent.parent / "benchmarks.json"
    if meta.is_file():
        try:
            described = json.loads(meta.read_text())
            units = {k: v.get("unit", "") for k, v in described.items() if isinstance(v, dict)}
        except ValueError:
            units = {}
    date = _dt.datetime.fromtimestamp(data.get("date", 0) / 1000, tz=_dt.UTC)
    return AsvRun(f, data.get("commit_hash", "?"), date, dict(data.get("params", {})), values, units)


# ---------------------------------------------------------------------- tables
def _fmt(v: float, spec: str, unit: str = "") -> str:
    return "n/a" if not math.isfinite(v) else f"{v:{spec}}{unit}"


def _setting(run: AsvRun, model: str, method: str) -> str:
    H = run.value("EqualAccuracy.track_harmonics", model, method)
    N = run.value("EqualAccuracy.track_samples", model, method)
    if method == "shooting":
        return _fmt(N, ".0f", " steps/period")
    parts = [f"H = {_fmt(H, '.0f')}"]
    if method == "mmshbm" and math.isfinite(N) and N > 0:
        parts.append(f"N = {N:.0f}")
    if method == "penalty":
        k = run.value("EqualAccuracy.track_penalty_factor", model, method)
        parts.append(f"k_p = {k:.0e} k_c" if math.isfinite(k) else "k_p = n/a")
    return ", ".join(parts)


def equal_accuracy_table(run: AsvRun, model: str) -> str:
    """``mmshbm bench``'s table for ``model`` ("oscillator" or "beam21")."""
    lines = ["| method | setting | unknowns | time (ms) | × MMS-HBM | Newton it. | f (Hz) | rel. error "
             "| target met |", "|---|---|---|---|---|---|---|---|---|"]
    for method, label in _METHODS.items():
        tracks = ("target_met", "unknowns", "time_ms", "time_ratio", "newton_iterations", "frequency_hz",
                  "rel_error")
        v = {what: run.value(f"EqualAccuracy.track_{what}", model, method) for what in tracks}
        met = v["target_met"]
        cells = [label, _setting(run, model, method), _fmt(v["unknowns"], ".0f"), _fmt(v["time_ms"], ".3g"),
                 _fmt(v["time_ratio"], ".3g"), _fmt(v["newton_iterations"], ".0f"),
                 _fmt(v["frequency_hz"], ".6f"), _fmt(v["rel_error"], ".1e"),
                 "n/a" if not math.isfinite(met) else ("yes" if met else "no")]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def goal_table(run: AsvRun) -> str:
    """The speed goals' table with the measured figures."""
    t10 = run.value("DefaultBackbone.time_backbone_to_10_gaps")
    evals = run.value("DefaultBackbone.track_evaluations_per_point")
    checks = run.value("DefaultBackbone.time_branch_checks")
    pen = run.value("EqualAccuracy.track_time_ratio", "oscillator", "penalty")
    sho = run.value("EqualAccuracy.track_time_ratio", "oscillator", "shooting")
    bpen = run.value("EqualAccuracy.track_time_ratio", "beam21", "penalty")
    bsho = run.value("EqualAccuracy.track_time_ratio", "beam21", "shooting")
    bamp = run.value("EqualAccuracy.track_amplitude_gaps", "beam21", "mmshbm")
    beam = (f"beam, {_fmt(bamp, 'g')} gaps, equal H = 5: penalty-HBM / shooting cost (no common converged "
            "reference)")
    rows = [
        ("default backbone (beam, 21 elements, H = 5) to 10 gaps, warm", _fmt(1e3 * t10, ".3g", " ms"),
         "≤ 5 ms"),
        ("residual + Jacobian evaluations per point (same branch)", _fmt(evals, ".2f"), "≤ 3"),
        ("branch checks of that branch", _fmt(1e3 * checks, ".2g", " ms"), ""),
        *_scale_rows(run),
        ("equal accuracy vs penalty-HBM (oscillator, 2 gaps, 1e-4, closed form)", _fmt(pen, ".3g", "×"),
         "≥ 20×"),
        ("equal accuracy vs shooting (same)", _fmt(sho, ".3g", "×"), "≥ 300×"),
        (beam, f"{_fmt(bpen, '.3g', '×')} / {_fmt(bsho, '.3g', '×')}", ""),
    ]
    for worker, what in (("1", "figures drawn by a child process"), ("0", "figures drawn in the process")):
        warm = run.value("WholeProcess.track_warm_s", worker)
        first = run.value("WholeProcess.track_first_run_s", worker)
        cold = run.value("WholeProcess.track_cold_s", worker)
        if math.isfinite(warm) or math.isfinite(first) or math.isfinite(cold):
            rows.append((f"`mmshbm backbone` whole process, warm / first run after `pip install .` / "
                         f"nothing compiled ({what})",
                         " / ".join(_fmt(v, ".2f", " s") for v in (warm, first, cold)),
                         "≤ 1 s / ≤ 3 s / –"))
    rows += _forced_rows(run)
    rows += _study_rows(run)
    lines = ["| figure | measured | goal |", "|---|---|---|"]
    lines += [f"| {a} | {b} | {c} |" for a, b, c in rows]
    return "\n".join(lines)


def _recorded(run: AsvRun, *names: str) -> list[tuple]:
    """The parameter combinations any of ``names`` (full benchmark names) was recorded
    for, in the order of the results file."""
    return list(dict.fromkeys(p for n, p in run.values if n in names))


def _cells(run: AsvRun, name: str, params: list[tuple], spec: str, unit: str, scale: float = 1.0) -> str:
    """``name``'s values at ``params`` joined by " / ", then ``unit`` ("n/a" when none is
    recorded)."""
    values = [scale * run.value(name, *p) for p in params]
    if not any(math.isfinite(v) for v in values):
        return "n/a"
    return " / ".join(_fmt(v, spec) for v in values) + unit


_SCALE = "bench_backbone_scale.BackboneScaleRatios."
_REDUCTION = "bench_scale.ModalReductionScale."
_SOLID = "bench_scale.SolidScale."
_MIB = 1 / 2**20  # bytes -> MiB


def _scale_rows(run: AsvRun) -> list[tuple[str, str, str]]:
    """The model-size rows, where the run recorded them: the whole backbone on 10 000 /
    21 elements (one process, after the reduction), the beam's one-time modal reduction
    (time, peak memory of the process) per size, and the 3-D solid's (>= 1e5 DOFs)."""
    rows = []
    for track, label, goal in (
            ("track_backbone_10000_over_21", "default backbone after the reduction, 10 000 / 21 elements, to "
             "1.9 gaps (the same 31 points), in one process", "≤ 1.5×"),
            ("track_backbone_2_gaps_10000_over_21", "same to 2 gaps (on 10 000 elements the family guard "
             "also tries a jump over the 5:1 tongue)", "")):
        if _recorded(run, _SCALE + track):
            rows.append((label, _fmt(run.value(_SCALE + track), ".2f", "×"), goal))
    sizes = _recorded(run, _REDUCTION + "time_reduction", _REDUCTION + "peakmem_reduction")
    if sizes:
        beams = " / ".join(p[0] for p in sizes)
        rows.append((f"modal reduction of the beam (once per model), {beams} elements: time; peak memory of "
                     "the process",
                     _cells(run, _REDUCTION + "time_reduction", sizes, ".3g", " s") + "; "
                     + _cells(run, _REDUCTION + "peakmem_reduction", sizes, ".0f", " MiB", _MIB), ""))
    if _recorded(run, _SOLID + "time_reduction", _SOLID + "peakmem_reduction"):
        rows.append(("modal reduction of the 3-D solid beam (≥ 10⁵ DOFs): time; peak memory of the process",
                     f"{_fmt(run.value(_SOLID + 'time_reduction'), '.3g', ' s')}; "
                     f"{_fmt(_MIB * run.value(_SOLID + 'peakmem_reduction'), '.0f', ' MiB')}", ""))
    return rows


_FORCED = "bench_forced.ForcedHarmonics."
_EPMC = "bench_forced.EPMCBudget."
#: the forced response's rows: harmonics shown together in one row, goal
_FORCED_GROUPS = ((("5", "10", "20"), ""), (("30",), "≤ 2 s, to 62 Hz"), (("40",), "≤ 5 s, to 62 Hz"))


def _forced_rows(run: AsvRun) -> list[tuple[str, str, str]]:
    """The forced rows, where the run recorded them: the damped beam's frequency response
    (time and where it ends) per H, and its EPMC backbone at H = 20 (amplitude reached
    within the default step budget, time)."""
    recorded = _recorded(run, _FORCED + "time_response", _FORCED + "track_end_frequency")
    rows = []
    for group, goal in _FORCED_GROUPS:
        hs = [p for p in recorded if p and p[0] in group]
        if not hs:
            continue
        what = ("forced response of the beam (0.5 % damping on mode 1, 5 % above; 5 N at the last node with "
                "mass, 40–62 Hz, Floquet stability)" if not rows else "same")
        rows.append((f"{what}, H = {' / '.join(p[0] for p in hs)}: time, where it ends",
                     _cells(run, _FORCED + "time_response", hs, ".3g", " s") + ", ends at "
                     + _cells(run, _FORCED + "track_end_frequency", hs, ".4g", " Hz"), goal))
    if _recorded(run, _EPMC + "track_epmc_h20_max_gaps", _EPMC + "time_epmc_h20"):
        rows.append(("EPMC backbone of the beam with 0.5 % / 5 % damping, H = 20, default step budget: "
                     "amplitude reached, time",
                     f"{_fmt(run.value(_EPMC + 'track_epmc_h20_max_gaps'), '.3g', ' gaps')}, "
                     f"{_fmt(run.value(_EPMC + 'time_epmc_h20'), '.3g', ' s')}", "reaches 6 gaps"))
    return rows


#: the study figures of the goal table: (benchmark, label, format, goal); the grid's wall
#: time is one figure recorded once per cell, the throughput's once per executor
_STUDY_ROWS = (
    ("bench_studies.ConvergenceGrid.track_grid_wall_time",
     "35-cell grid (H 1–15 × 8–200 elements) to 10 gaps, wall time of the runs, 2 workers", ".3g", "≤ 4 s"),
    ("bench_studies.StudyThroughput.track_busy_share", "Monte-Carlo study, busy share per worker", ".2f",
     "≥ 0.95"),
    ("bench_studies.StudyThroughput.track_parallel_efficiency", "Monte-Carlo study, parallel efficiency",
     ".2f", ""),
    ("bench_studies.StudyThroughput.track_backbones_per_second", "Monte-Carlo study, backbones per second",
     ".3g", ""),
)


def _study_rows(run: AsvRun) -> list[tuple[str, str, str]]:
    """The goal table's study rows (grid wall time; busy share, efficiency and rate per
    executor of the throughput benchmark), where the run recorded them."""
    rows = []
    for name, label, fmt, goal in _STUDY_ROWS:
        params_of = [p for n, p in run.values if n == name]
        if not params_of:
            continue
        if name.endswith("track_grid_wall_time"):
            rows.append((label, _fmt(run.value(name, *params_of[0]), fmt, " s"), goal))
            continue
        cells = [f"{p[0]} {_fmt(run.value(name, *p), fmt)}" for p in params_of if p and p[0] != "serial"]
        if cells:
            rows.append((label, ", ".join(cells), goal))
    return rows


def tables(run: AsvRun) -> str:
    """The whole generated block: where the figures come from, the goal table and the
    two equal-accuracy tables."""
    m = run.machine
    where = (f"asv run of commit {run.commit[:8]} on machine `{m.get('machine', '?')}` "
             f"({m.get('num_cpu', '?')} CPUs, {m.get('cpu', '?')}), {run.date:%Y-%m-%d %H:%M} UTC; "
             "wall-clock times on a shared machine: read the ratios, repeat before trusting absolute "
             "figures.")
    osc_ref = run.value("EqualAccuracy.track_reference_hz", "oscillator", "mmshbm")
    beam_ref = run.value("EqualAccuracy.track_reference_hz", "beam21", "mmshbm")
    beam_amp = run.value("EqualAccuracy.track_amplitude_gaps", "beam21", "mmshbm")
    return "\n".join([
        where, "", goal_table(run), "",
        f"One-DOF oscillator, 2 gaps, target 1e-4 against the closed form ({_fmt(osc_ref, '.9g')} Hz): "
        "every method tuned to the target, whole backbone from half a gap, fastest of 3:", "",
        equal_accuracy_table(run, "oscillator"), "",
        f"Default beam, 21 elements, {_fmt(beam_amp, 'g')} gaps: no converged reference exists (the exact "
        "orbits rattle, the frequency is not converged in H), so this is cost at equal H = 5, not at equal "
        f"accuracy: the reference is MMS-HBM's own H = 5 solution with N = 1024 ({_fmt(beam_ref, '.9g')} Hz; "
        "with the exact projection of the contact law N does not change it, hence MMS-HBM's zero error), "
        "penalty-HBM tuned in k_p, shooting (which does not truncate harmonics) against the same number:",
        "",
        equal_accuracy_table(run, "beam21"),
    ])


def update_file(path, block: str) -> bool:
    """Replace the lines between the line :data:`BEGIN` and the next line :data:`END` in
    ``path`` by ``block``; True when the file changed. Raises ValueError when the marker
    lines are missing (markers quoted inside other lines do not count)."""
    path = Path(path)
    text = path.read_text()
    lines = text.split("\n")
    try:
        i = next(k for k, line in enumerate(lines) if line.strip() == BEGIN)
        j = next(k for k in range(i + 1, len(lines)) if lines[k].strip() == END)
    except StopIteration:
        raise ValueError(f"{path}: no generated block (a line {BEGIN!r}, later a line {END!r})") from None
    new = "\n".join(lines[: i + 1] + block.strip().split("\n") + lines[j:])
    if new != text:
        path.write_text(new)
    return new != text
