"""Where a study's work is done: process pools started by fork or spawn, and table rows
computed by the workers right after their runs. Every path must give the numbers, notes,
warnings and saved files of the plain serial study with the table solved afterwards."""

import json
import threading
import warnings

import numpy as np
import pytest

from mmshbm._warnings import BranchWarning
from mmshbm.analysis import executors, studies, table_rows
from mmshbm.results.branch import read_archive

GRID = {"harmonics": (3, 5), "elements": (4, 6), "max_amplitude": 3.0, "unit": "gap", "warn": False}
AMPS = (1.5, 2.3)


def _saved(study, path):
    """The saved study's arrays and metadata, less the wall times."""
    arrays, meta = read_archive(study.save(path))
    for key in ("elapsed_s", "busy_s", "open_s", "executor"):
        meta["metadata"].pop(key, None)
    for branch in meta["branches"]:
        branch["metadata"].pop("elapsed_s", None)
    return arrays, json.dumps(meta, sort_keys=True, default=str)


def _same_tables(a, b):
    assert a.frequency.tobytes() == b.frequency.tobytes()
    np.testing.assert_array_equal(a.mode_share, b.mode_share)
    assert a.notes == b.notes and a.partner == b.partner and a.status == b.status


def test_rows_tabulated_by_the_workers_equal_the_parent_table(tmp_path):
    serial = studies.run_study(executor="serial", **GRID)
    pooled = studies.run_study(executor="process", workers=2, tabulate=(AMPS, "gap"), **GRID)
    rows = pooled._rows[(AMPS, "gap")]
    assert sorted(rows) == [0, 1, 2, 3]
    # at least one cell lies between stored points: its row rebuilt the model and solved there
    assert any(row.model for row in rows.values())
    _same_tables(serial.table(AMPS), pooled.table(AMPS))
    assert not pooled._rows  # used once; the table is cached
    assert np.isfinite(serial.table(AMPS).frequency).sum() >= 6
    a, meta_a = _saved(serial, tmp_path / "serial.npz")
    b, meta_b = _saved(pooled, tmp_path / "pooled.npz")
    assert meta_a == meta_b  # the models the table attached are recorded alike
    assert sorted(a) == sorted(b) and all(a[k].tobytes() == b[k].tobytes() for k in a)
    # another table is solved on the parent side as before
    _same_tables(serial.table((2.0,)), pooled.table((2.0,)))


def test_rows_keep_their_warnings_for_the_parent(monkeypatch):
    def row_values(branch, amplitudes, unit):
        warnings.warn("cell 0 is off the family", BranchWarning, stacklevel=1)
        return [50.0], [0.9], [None], [""]

    class Branch:
        model = solver = None

    monkeypatch.setattr(table_rows, "row_values", row_values)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        row = table_rows.tabulate(Branch(), [2.5], "gap")
    assert not caught  # kept in the row, not issued in the worker
    assert row.frequency == [50.0] and not row.model
    assert [m for m, *_ in row.warnings] == ["cell 0 is off the family"]
    with pytest.warns(BranchWarning, match="off the family"):
        table_rows.replay(row, Branch())

    def fails(branch, amplitudes, unit):
        raise ValueError("no gap")

    monkeypatch.setattr(table_rows, "row_values", fails)
    assert table_rows.tabulate(Branch(), [2.5], "gap") is None  # the parent computes it and raises there


def test_start_method_forks_only_without_other_threads(monkeypatch):
    monkeypatch.delenv("MMSHBM_START_METHOD", raising=False)
    monkeypatch.setattr(executors.sys, "platform", "linux")
    with monkeypatch.context() as m:  # (threads other tests left behind do not count here)
        m.setattr(executors.threading, "active_count", lambda: 1)
        assert executors.start_method() == "fork"
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    try:
        assert executors.start_method() == "spawn"
    finally:
        stop.set()
        other.join()
    monkeypatch.setattr(executors.sys, "platform", "darwin")
    assert executors.start_method() == "spawn"
    monkeypatch.setenv("MMSHBM_START_METHOD", "forkserver")
    assert executors.start_method() == "forkserver"
    monkeypatch.setenv("MMSHBM_START_METHOD", "thread")
    with pytest.raises(ValueError, match="MMSHBM_START_METHOD"):
        executors.start_method()


def test_spawned_forked_and_thread_workers_give_identical_numbers():
    import concurrent.futures as cf

    kw = {**GRID, "harmonics": (5,)}
    serial = studies.run_study(executor="serial", **kw)
    for method in ("spawn", "fork", "thread"):
        pool = cf.ThreadPoolExecutor(2) if method == "thread" else executors.process_pool(2, method)
        with pool:
            study = studies.run_study(executor=pool, tabulate=(AMPS, "gap"), **kw)
        for a, b in zip(serial.branches, study.branches, strict=True):
            assert a.states.tobytes() == b.states.tobytes() and a.frequency.tobytes() == b.frequency.tobytes()
        _same_tables(serial.table(AMPS), study.table(AMPS))


def test_auto_chunks_shrink_to_single_runs_for_large_studies():
    gaps = list(np.linspace(1e-3, 2e-3, 1000))
    specs = studies.grid_specs(harmonics=(3,), elements=(8,), samples={"gap": gaps})
    for workers in (2, 16):
        chunks = executors.plan_chunks(specs, workers)
        flat = [s.index for c in chunks for s in c]
        assert flat == [s.index for s in executors.longest_first(specs)]  # every spec once, in order
        sizes = [len(c) for c in chunks]
        assert sizes == sorted(sizes, reverse=True) and sizes[-workers:] == [1] * workers
        assert sizes[0] == 1000 // (2 * workers)  # half the work spread over the workers first
        # few tasks: about 2 workers ln(n / 2 workers) + 2 workers
        assert len(chunks) <= 2 * workers * (np.log(1000 / (2 * workers)) + 2)
        assert executors.auto_chunksize(1000, workers) == round(1000 / len(chunks))
    # small studies (runs of unequal cost): one run per task; an integer: chunks of that many
    assert [len(c) for c in executors.plan_chunks(specs[:63], 2)] == [1] * 63
    assert executors.auto_chunksize(63, 2) == 1
    assert [len(c) for c in executors.plan_chunks(specs[:10], 2, 4)] == [4, 4, 2]
    # unequal costs: the guided chunks hold about equal shares of the cost left, not of the count
    mixed = studies.grid_specs(harmonics=(1, 9), elements=(8,), samples={"gap": gaps[:40]})
    chunks = executors.plan_chunks(mixed, 2)
    assert len(chunks[0]) == 10 and {s.harmonics for s in chunks[0]} == {9}  # 40 H9 of cost 243: 1/4 of it
