"""The benchmark tables of docs/validation.md and docs/benchmarks.md come from one recorded
asv run (python -m validation tables): the numbers of the results file, in the right cells."""

import json
import math

import pytest
from locations import ROOT

from validation import asv_tables
from validation.__main__ import main

COLUMNS = ["result", "params", "version", "started_at", "duration"]
GRID = [["'1'", "'15'"], ["'8'", "'200'"]]  # H x elements of a grid benchmark


def _results(tmp_path, date, time_10=0.0042, commit="abc1234def", extra=None, goals=True):
    """A results folder in asv's format (version 2) with some bench_goals figures (none
    with ``goals=False``), and the benchmarks of ``extra`` (name -> [results, params])."""
    models, methods = ["'oscillator'", "'beam21'"], ["'mmshbm'", "'penalty'", "'shooting'"]
    ratio = [1.0, 25.0, 350.0, 1.0, 9.0, 125.0]  # oscillator x 3, beam x 3 (product order)
    results = {
        "bench_goals.DefaultBackbone.time_backbone_to_10_gaps": [[time_10], [], "v"],
        "bench_goals.DefaultBackbone.track_evaluations_per_point": [[2.57], [], "v"],
        "bench_goals.EqualAccuracy.track_time_ratio": [ratio, [models, methods], "v"],
        "bench_goals.EqualAccuracy.track_harmonics": [[13, 25, 0, 5, 5, 0], [models, methods], "v"],
        "bench_goals.EqualAccuracy.track_penalty_factor": [[None, 1e4, None, None, 100.0, None],
                                                           [models, methods], "v"],
        "bench_goals.EqualAccuracy.track_samples": [[0, 0, 256, 0, 0, 128], [models, methods], "v"],
        "bench_goals.EqualAccuracy.track_target_met": [[1, 1, 1, 1, 0, 0], [models, methods], "v"],
        "bench_goals.WholeProcess.track_warm_s": [[0.95, 1.2], [["'1'", "'0'"]], "v"],
        # the grid's wall time, recorded once per cell: one figure
        "bench_studies.ConvergenceGrid.track_grid_wall_time": [[2.5, 2.5, 2.5, 2.5], GRID, "v"],
        "bench_studies.ConvergenceGrid.track_points": [[31, 37, 440, 369], GRID, "v"],
        "bench_studies.StudyThroughput.track_busy_share": [[0.99, 0.963, 0.949],
                                                           [["'serial'", "'process'", "'dask'"]], "v"],
    }
    if not goals:
        results = {}
    results.update({name: [*entry, "v"] for name, entry in (extra or {}).items()})
    folder = tmp_path / "results" / "vm"
    folder.mkdir(parents=True, exist_ok=True)
    data = {"commit_hash": commit, "env_name": "e", "date": date, "params": {"machine": "vm", "num_cpu": "2",
            "cpu": "AMD EPYC"}, "python": "3", "requirements": {}, "env_vars": {}, "result_columns": COLUMNS,
            "results": results, "durations": {}, "version": 2}
    path = folder / f"{commit[:8]}-e.json"
    path.write_text(json.dumps(data))
    (folder / "machine.json").write_text("{}")
    return path


def test_tables_hold_the_recorded_numbers(tmp_path):
    old = _results(tmp_path, 1_000, time_10=0.0099, commit="0000000000")
    new = _results(tmp_path, 2_000)
    assert asv_tables.find_results(tmp_path / "results") == new  # the newest run
    assert asv_tables.find_results(old) == old
    run = asv_tables.load_run(tmp_path / "results")
    assert run.value("DefaultBackbone.time_backbone_to_10_gaps") == 0.0042
    assert run.value("EqualAccuracy.track_time_ratio", "beam21", "shooting") == 125.0
    assert run.value("WholeProcess.track_warm_s", "0") == 1.2
    assert math.isnan(run.value("EqualAccuracy.track_rel_error", "beam21", "mmshbm"))  # not recorded
    assert math.isnan(run.value("EqualAccuracy.track_penalty_factor", "beam21", "mmshbm"))  # null
    text = asv_tables.tables(run)
    assert "commit abc1234d" in text
    assert "| default backbone (beam, 21 elements, H = 5) to 10 gaps, warm | 4.2 ms | ≤ 5 ms |" in text
    assert "| equal accuracy vs penalty-HBM (oscillator, 2 gaps, 1e-4, closed form) | 25× | ≥ 20× |" in text
    assert "| equal accuracy vs shooting (same) | 350× | ≥ 300× |" in text
    assert "0.95 s / n/a" in text
    assert "| penalty-HBM | H = 25, k_p = 1e+04 k_c |" in text
    assert "| shooting | 128 steps/period |" in text
    # the studies: one row per figure, not one per grid cell
    grid = "| 35-cell grid (H 1–15 × 8–200 elements) to 10 gaps, wall time of the runs, 2 workers"
    assert f"{grid} | 2.5 s | ≤ 4 s |" in text
    assert "| Monte-Carlo study, busy share per worker | process 0.96, dask 0.95 | ≥ 0.95 |" in text
    assert "track_points" not in text and text.count("2.5 s") == 1


def test_update_replaces_the_block_only(tmp_path, capsys):
    _results(tmp_path, 2_000)
    doc = tmp_path / "doc.md"
    quoted = f"write between `{asv_tables.BEGIN}` and `{asv_tables.END}`"  # quoted markers do not count
    doc.write_text(f"# Title\n{quoted}\n\n{asv_tables.BEGIN}\nold table\n{asv_tables.END}\n\ntail\n")
    no_runs = str(tmp_path / "no-runs")
    assert main(["tables", no_runs, "--asv", str(tmp_path / "results"), "--update", str(doc)]) == 0
    text = doc.read_text()
    assert "old table" not in text and "| 4.2 ms |" in text
    assert text.startswith(f"# Title\n{quoted}\n") and text.endswith(f"{asv_tables.END}\n\ntail\n")
    assert "updated" in capsys.readouterr().out
    assert not asv_tables.update_file(doc, asv_tables.tables(asv_tables.load_run(tmp_path / "results")))
    bare = tmp_path / "bare.md"
    bare.write_text("no markers\n")
    with pytest.raises(ValueError, match="no generated block"):
        asv_tables.update_file(bare, "x")
    assert main(["tables", no_runs, "--asv", str(tmp_path / "nothing")]) == 2


def test_default_reads_asv_folder_and_the_committed_record(tmp_path, monkeypatch):
    committed = _results(tmp_path / "benchmarks", 3_000, commit="cccccccccc")
    monkeypatch.chdir(tmp_path)
    assert asv_tables.find_results().resolve() == committed.resolve()  # no .asv folder: the record
    newer = _results(tmp_path / ".asv", 4_000, commit="dddddddddd")
    assert asv_tables.find_results().resolve() == newer.resolve()  # the newest of both
    assert asv_tables.load_run().commit == "dddddddddd"


MIB = 2**20
#: integer parameters, as asv writes them
ELEMENTS, HARMONICS = [["21", "1000", "10000"]], [["5", "10", "20", "30", "40"]]
#: the model-size and forced benchmarks of the goal table (outside bench_goals)
EXTRA = {
    "bench_backbone_scale.BackboneScaleRatios.track_backbone_10000_over_21": [[1.2936], []],
    "bench_backbone_scale.BackboneScaleRatios.track_backbone_2_gaps_10000_over_21": [[2.517], []],
    "bench_scale.ModalReductionScale.time_reduction": [[0.00412, 0.0387, 0.5812], ELEMENTS],
    "bench_scale.ModalReductionScale.peakmem_reduction": [[150 * MIB, 180.4 * MIB, 412.6 * MIB], ELEMENTS],
    "bench_scale.ModalReductionScale.track_modes_kept": [[12, 12, 12], ELEMENTS],
    "bench_scale.SolidScale.time_reduction": [[41.23], []],
    "bench_scale.SolidScale.peakmem_reduction": [[2.5 * 2**30], []],
    "bench_forced.ForcedHarmonics.time_response": [[0.104, 0.231, 0.655, 1.2914, 3.06], HARMONICS],
    "bench_forced.ForcedHarmonics.track_end_frequency": [[62.0, 62.0, 62.0, 62.0, 57.13], HARMONICS],
    "bench_forced.ForcedHarmonics.track_points": [[80, 81, 85, 90, 60], HARMONICS],
    "bench_forced.EPMCBudget.track_epmc_h20_max_gaps": [[3.612], []],
    "bench_forced.EPMCBudget.time_epmc_h20": [[2.084], []],
}
FORCED = ("forced response of the beam (0.5 % damping on mode 1, 5 % above; 5 N at the last node with mass, "
          "40–62 Hz, Floquet stability)")
SCALE_ROWS = [
    "| default backbone after the reduction, 10 000 / 21 elements, to 1.9 gaps (the same 31 points), in one "
    "process | 1.29× | ≤ 1.5× |",
    "| same to 2 gaps (on 10 000 elements the family guard also tries a jump over the 5:1 tongue) | 2.52× "
    "|  |",
    "| modal reduction of the beam (once per model), 21 / 1000 / 10000 elements: time; peak memory of the "
    "process | 0.00412 / 0.0387 / 0.581 s; 150 / 180 / 413 MiB |  |",
    "| modal reduction of the 3-D solid beam (≥ 10⁵ DOFs): time; peak memory of the process "
    "| 41.2 s; 2560 MiB |  |",
]
FORCED_ROWS = [
    f"| {FORCED}, H = 5 / 10 / 20: time, where it ends "
    "| 0.104 / 0.231 / 0.655 s, ends at 62 / 62 / 62 Hz |  |",
    "| same, H = 30: time, where it ends | 1.29 s, ends at 62 Hz | ≤ 2 s, to 62 Hz |",
    "| same, H = 40: time, where it ends | 3.06 s, ends at 57.13 Hz | ≤ 5 s, to 62 Hz |",
    "| EPMC backbone of the beam with 0.5 % / 5 % damping, H = 20, default step budget: amplitude reached, "
    "time | 3.61 gaps, 2.08 s | reaches 6 gaps |",
]


def test_model_size_and_forced_rows(tmp_path):
    path = _results(tmp_path, 2_000, extra=EXTRA)
    # a newer file without bench_goals figures (a run of other suites) is passed over
    _results(tmp_path, 3_000, commit="ffffffffff", extra=EXTRA, goals=False)
    assert asv_tables.find_results(tmp_path / "results") == path
    run = asv_tables.load_run(tmp_path / "results")
    assert run.value("bench_scale.ModalReductionScale.time_reduction", 1000) == 0.0387  # "1000" in the file
    assert run.value("bench_forced.ForcedHarmonics.time_response", "30") == 1.2914
    lines = asv_tables.goal_table(run).split("\n")
    i = lines.index("| branch checks of that branch | n/a |  |")
    assert lines[i + 1: i + 5] == SCALE_ROWS  # after the default backbone's rows
    j = lines.index(FORCED_ROWS[0])
    assert lines[j: j + 4] == FORCED_ROWS and lines[j + 4].startswith("| 35-cell grid")  # before the studies
    assert "modes_kept" not in "\n".join(lines) and "| 80" not in "\n".join(lines)


def test_rows_absent_when_not_recorded(tmp_path):
    text = asv_tables.goal_table(asv_tables.load_run(_results(tmp_path, 2_000)))
    for label in ("10 000 / 21 elements", "same to 2 gaps", "modal reduction", "forced response", "same, H",
                  "EPMC"):
        assert label not in text
    # part of a benchmark's parameters recorded, one solid figure failed (null): those rows only
    extra = {"bench_forced.ForcedHarmonics.time_response": [[1.5], [["30"]]],
             "bench_scale.SolidScale.time_reduction": [[None], []]}
    run = asv_tables.load_run(_results(tmp_path / "part", 2_000, extra=extra))
    lines = asv_tables.goal_table(run).split("\n")
    assert f"| {FORCED}, H = 30: time, where it ends | 1.5 s, ends at n/a | ≤ 2 s, to 62 Hz |" in lines
    solid = "modal reduction of the 3-D solid beam (≥ 10⁵ DOFs): time; peak memory of the process"
    assert f"| {solid} | n/a; n/a |  |" in lines
    assert not any("same, H" in line or "EPMC" in line or "10 000 / 21" in line for line in lines)


def test_record_command_selects_what_the_tables_read():
    """The ``--bench`` regex of the record command in docs/validation.md and
    docs/benchmarks.md selects the goal and study suites and, besides, exactly the
    benchmarks the rows read (asv matches with re.search, on ``name(params)`` for
    parameterized ones)."""
    import re

    root = ROOT
    regex = asv_tables.RECORD_BENCH
    for doc in ("docs/validation.md", "docs/benchmarks.md"):
        assert f'--bench "{regex}"' in (root / doc).read_text(), doc
    described = json.loads((root / "benchmarks/results/benchmarks.json").read_text())
    names = [k for k, v in described.items() if isinstance(v, dict) and "name" in v]
    selected = {n for n in names if re.search(regex, n)}
    suites = {n for n in names if n.startswith(("bench_goals.", "bench_studies."))}
    needed = set(EXTRA) - {"bench_scale.ModalReductionScale.track_modes_kept",
                           "bench_forced.ForcedHarmonics.track_points"}
    assert needed <= set(names) and len(suites) > 20  # the rows' benchmarks exist under these names
    assert selected == suites | needed
