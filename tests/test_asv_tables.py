"""The README's and docs' benchmark tables come from one recorded asv run
(mmshbm bench --from-asv): the numbers of the results file, in the right cells."""

import json
import math

import pytest

from mmshbm.analysis import asv_tables
from mmshbm.cli import main

COLUMNS = ["result", "params", "version", "started_at", "duration"]
GRID = [["'1'", "'15'"], ["'8'", "'200'"]]  # H x elements of a grid benchmark


def _results(tmp_path, date, time_10=0.0042, commit="abc1234def"):
    """A results folder in asv's format (version 2) with some bench_goals figures."""
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
    assert main(["bench", "--from-asv", str(tmp_path / "results"), "--update", str(doc)]) == 0
    text = doc.read_text()
    assert "old table" not in text and "| 4.2 ms |" in text
    assert text.startswith(f"# Title\n{quoted}\n") and text.endswith(f"{asv_tables.END}\n\ntail\n")
    assert "updated" in capsys.readouterr().out
    assert not asv_tables.update_file(doc, asv_tables.tables(asv_tables.load_run(tmp_path / "results")))
    bare = tmp_path / "bare.md"
    bare.write_text("no markers\n")
    with pytest.raises(ValueError, match="no generated block"):
        asv_tables.update_file(bare, "x")
    assert main(["bench", "--update", str(doc)]) == 2
    assert main(["bench", "--from-asv", str(tmp_path / "nothing")]) == 2


def test_default_reads_asv_folder_and_the_committed_record(tmp_path, monkeypatch):
    committed = _results(tmp_path / "benchmarks", 3_000, commit="cccccccccc")
    monkeypatch.chdir(tmp_path)
    assert asv_tables.find_results().resolve() == committed.resolve()  # no .asv folder: the record
    newer = _results(tmp_path / ".asv", 4_000, commit="dddddddddd")
    assert asv_tables.find_results().resolve() == newer.resolve()  # the newest of both
    assert asv_tables.load_run().commit == "dddddddddd"
