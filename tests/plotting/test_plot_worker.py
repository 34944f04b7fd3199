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


def test_forked_child_draws_the_same_files_and_falls_back(branch, tmp_path, monkeypatch):
    """``draw_forked(jobs, here)``: a forked child draws ``jobs`` while this process draws
    ``here``; the warnings of the child's figures are issued here; a job that fails in
    the child is drawn again here, where it raises as usual."""
    import threading
    import warnings

    data = BranchData.of(branch)
    energy = "plot_frequency_energy"
    # (a thread another test left behind would turn forking off; this test forks anyway)
    monkeypatch.setattr(_plot_worker, "fork_enabled", lambda: True)
    assert _plot_worker.draw_forked([(energy, (data,), {"path": tmp_path / "child.png"})],
                                    here=[(energy, (data,), {"path": tmp_path / "here.png"})])
    assert (tmp_path / "child.png").read_bytes() == (tmp_path / "here.png").read_bytes()

    def warns(*args, path):
        warnings.warn("drawn in the child", mmshbm.BranchWarning, stacklevel=1)
        path.write_text("figure")

    plotting.warns_in_test = warns
    try:
        with pytest.warns(mmshbm.BranchWarning, match="drawn in the child"):
            assert _plot_worker.draw_forked([("warns_in_test", (), {"path": tmp_path / "w.txt"})])
    finally:
        del plotting.warns_in_test
    assert (tmp_path / "w.txt").read_text() == "figure"
    bad = [("plot_backbone", (data,), {"labels": ["one", "two"], "path": tmp_path / "x.png"})]
    with pytest.raises(ValueError, match="2 labels for 1"):
        _plot_worker.draw_forked(bad)  # fails in the child, raises here
    # another thread running: no fork, both drawn here
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    monkeypatch.undo()
    try:
        assert not _plot_worker.fork_enabled()
        assert not _plot_worker.draw_forked([(energy, (data,), {"path": tmp_path / "a.png"})],
                                            here=[(energy, (data,), {"path": tmp_path / "b.png"})])
    finally:
        stop.set()
        other.join()
    assert (tmp_path / "a.png").read_bytes() == (tmp_path / "here.png").read_bytes()


def test_study_figures_drawn_by_the_forked_child_equal_those_drawn_here(tmp_path, monkeypatch):
    from mmshbm.cli import main

    argv = ["study", "-H", "3", "5", "--elements", "4", "6", "--max-amplitude", "3", "--amplitudes", "2.3"]
    drawn = []
    forked = _plot_worker.draw_forked
    monkeypatch.setattr(_plot_worker, "draw_forked", lambda *a, **k: drawn.append(forked(*a, **k)))
    monkeypatch.setattr(_plot_worker, "fork_enabled", lambda: True)
    assert main([*argv, "--out", str(tmp_path / "forked")]) == 0
    assert drawn == [True]  # the family grid was drawn by the child
    monkeypatch.setattr(_plot_worker, "fork_enabled", lambda: False)
    assert main([*argv, "--out", str(tmp_path / "here")]) == 0
    for name in ("study.png", "study_convergence.png", "study_table.csv"):
        assert (tmp_path / "forked" / name).read_bytes() == (tmp_path / "here" / name).read_bytes(), name
