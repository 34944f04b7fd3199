"""The command line's figures drawn by a child process: the same files as drawn in the
process, and the process draws them itself whenever the child fails."""

import pytest

import mmshbm
from mmshbm import plotting
from mmshbm.cli import _plot_worker
from mmshbm.plotting.data import BranchData, reference_frequencies

pytestmark = pytest.mark.filterwarnings("ignore::mmshbm.BranchWarning")


@pytest.fixture(scope="module")
def branch():
    # the default beam at H = 5 to 4 gaps: an excursion into the 5:1 tongue (off the
    # family, drawn thin), folds, an internal resonance
    return mmshbm.backbone(mmshbm.default_beam().model(21), harmonics=5, max_amplitude=4e-3)


def test_branch_data_draws_the_branch_figures(branch, tmp_path):
    """A BranchData with the reference frequencies draws byte for byte the figures of the
    Branch with its model (Agg output is deterministic)."""
    model = branch.get_model()
    data = BranchData.of(branch)
    assert len(data) == len(branch) and data.gap == model.gap
    assert not branch.records["on_family"].all()  # the family front differs from the branch
    plotting.plot_backbone(branch, model=model, path=tmp_path / "a.png")
    plotting.plot_backbone(data, model=reference_frequencies(model), path=tmp_path / "b.png")
    assert (tmp_path / "a.png").read_bytes() == (tmp_path / "b.png").read_bytes()
    plotting.plot_frequency_energy(branch, path=tmp_path / "c.png")
    plotting.plot_frequency_energy(data, path=tmp_path / "d.png")
    assert (tmp_path / "c.png").read_bytes() == (tmp_path / "d.png").read_bytes()


def test_worker_draws_the_same_files_and_falls_back(branch, tmp_path):
    model = branch.get_model()
    data = BranchData.of(branch)
    jobs = [("plot_backbone", (data,), {"model": reference_frequencies(model), "path": tmp_path / "w.png"})]
    with _plot_worker.PlotWorker(start=True) as worker:
        assert worker.running
        assert worker.draw(jobs)  # drawn by the child
        assert not worker.running
    plotting.plot_backbone(data, model=reference_frequencies(model), path=tmp_path / "p.png")
    assert (tmp_path / "w.png").read_bytes() == (tmp_path / "p.png").read_bytes()
    # a job that fails in the child is drawn again here, where it raises as usual
    bad = [("plot_backbone", (data,), {"labels": ["one", "two"], "path": tmp_path / "x.png"})]
    with _plot_worker.PlotWorker(start=True) as worker, pytest.raises(ValueError, match="2 labels for 1"):
        worker.draw(bad)  # fails in the child, raises here
    # without a child the jobs are drawn here
    with _plot_worker.PlotWorker(start=False) as worker:
        assert not worker.running
        assert not worker.draw([("plot_frequency_energy", (data,), {"path": tmp_path / "e.png"})])
    assert (tmp_path / "e.png").stat().st_size > 10_000


def test_worker_switch(monkeypatch):
    monkeypatch.setenv("MMSHBM_PLOT_WORKER", "0")
    assert not _plot_worker.enabled()
    monkeypatch.setattr(_plot_worker, "_cores", lambda: 2)
    monkeypatch.setenv("MMSHBM_PLOT_WORKER", "1")
    assert _plot_worker.enabled()
    monkeypatch.delenv("MMSHBM_PLOT_WORKER")
    monkeypatch.setattr(_plot_worker, "_idle_cores", lambda: 0.1)  # a busy machine: draw here
    assert not _plot_worker.enabled()
    monkeypatch.setattr(_plot_worker, "_idle_cores", lambda: 1.5)
    assert _plot_worker.enabled()
    monkeypatch.setattr(_plot_worker, "_cores", lambda: 1)
    assert not _plot_worker.enabled()


def test_worker_and_this_process_draw_at_once(branch, tmp_path):
    """``draw(jobs, here)``: the child draws ``jobs`` while this process draws ``here``;
    the child reads one pickle, so a write end of its stdin held elsewhere (a process
    forked after it started) does not keep it waiting."""
    import os

    data = BranchData.of(branch)
    with _plot_worker.PlotWorker(start=True, modules=("backbones",)) as worker:
        held = os.dup(worker._proc.stdin.fileno())  # as a forked pool worker would hold it
        try:
            assert worker.draw([("plot_frequency_energy", (data,), {"path": tmp_path / "child.png"})],
                               here=[("plot_frequency_energy", (data,), {"path": tmp_path / "here.png"})])
        finally:
            os.close(held)
    assert (tmp_path / "child.png").read_bytes() == (tmp_path / "here.png").read_bytes()
    with _plot_worker.PlotWorker(start=False) as worker:  # no child: both drawn here
        assert not worker.draw([("plot_frequency_energy", (data,), {"path": tmp_path / "a.png"})],
                               here=[("plot_frequency_energy", (data,), {"path": tmp_path / "b.png"})])
    assert (tmp_path / "a.png").read_bytes() == (tmp_path / "b.png").read_bytes()


def test_study_figures_drawn_by_the_worker_equal_those_drawn_here(tmp_path, monkeypatch):
    from mmshbm.cli import main

    argv = ["study", "-H", "3", "5", "--elements", "4", "6", "--max-amplitude", "3", "--amplitudes", "2.3"]
    for flag in ("1", "0"):
        monkeypatch.setenv("MMSHBM_PLOT_WORKER", flag)
        assert main([*argv, "--out", str(tmp_path / flag)]) == 0
    for name in ("study.png", "study_convergence.png", "study_table.csv"):
        assert (tmp_path / "1" / name).read_bytes() == (tmp_path / "0" / name).read_bytes(), name
