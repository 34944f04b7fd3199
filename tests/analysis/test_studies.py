"""Studies: identical numbers whatever the executor, grids over parameters, tables and
observed convergence rates, files."""

import concurrent.futures as cf

import numpy as np
import pytest

import mmshbm
from mmshbm.analysis import studies
from mmshbm.io import load

GRID = {"harmonics": (1, 3), "elements": (4, 6), "max_amplitude": 3.0, "unit": "gap"}


@pytest.fixture(scope="module")
def serial():
    return studies.run_study(executor="serial", **GRID)


def _same(a, b):
    assert a.runs == b.runs
    for x, y in zip(a.branches, b.branches, strict=True):
        assert x.states.tobytes() == y.states.tobytes()
        assert x.frequency.tobytes() == y.frequency.tobytes()
        assert x.status == y.status


def test_grid_order_and_coordinates(serial):
    assert [(r["elements"], r["harmonics"]) for r in serial.runs] == [(4, 1), (4, 3), (6, 1), (6, 3)]
    assert all(r["method"] == "mmshbm" for r in serial.runs)
    assert all(b.completed for b in serial.branches)
    assert serial.branch(elements=6, harmonics=3).metadata["model"]["n_elements"] == 6
    with pytest.raises(KeyError):
        serial.branch(harmonics=3)


def test_process_pool_gives_identical_numbers(serial):
    _same(serial, studies.run_study(executor="process", workers=2, **GRID))
    with cf.ThreadPoolExecutor(2) as pool:  # any Executor
        _same(serial, studies.run_study(executor=pool, **GRID))


def test_dask_local_cluster_gives_identical_numbers(serial):
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        _same(serial, studies.run_study(executor=client.get_executor(), **GRID))
        via_client = studies.run_study(executor=client, **GRID)
    _same(serial, via_client)
    assert via_client.metadata["executor"].startswith("dask client")
    local = studies.run_study(executor="dask", workers=1, **GRID)  # a local cluster of its own
    _same(serial, local)
    assert local.metadata["executor"] == "dask local cluster (1 workers)"


def test_table_is_frequency_at_amplitude(serial):
    table = serial.table([1.5, 2.5], unit="gap")
    assert table.frequency.shape == (4, 2)
    for row, b in zip(table.frequency, serial.branches, strict=True):
        gap = b.get_model().gap
        assert row[0] == b.frequency_at(1.5 * gap) and row[1] == b.frequency_at(2.5 * gap)
        assert np.all(np.isfinite(row))
    assert np.isnan(serial.table([5.0]).frequency).all()  # beyond max_amplitude: not reached


def test_pivot_matrix(serial):
    table = serial.table([1.5, 2.5])
    rows, cols, f = table.pivot(1)
    assert (rows, cols) == ([4, 6], [1, 3])
    assert f[1, 0] == serial.branch(elements=6, harmonics=1).frequency_at(2.5 * 1e-3)
    assert "f (Hz) at A = 2.5 gaps" in serial.report([1.5, 2.5])
    with pytest.raises(ValueError, match="gap"):
        table.pivot(0, rows="gap")


def test_progress_lines_when_not_a_terminal(capsys):
    studies.run_study(harmonics=(1,), elements=(4,), executor="serial", verbose=True, max_amplitude=2.0,
                      unit="gap", warn=False)
    lines = capsys.readouterr().err.splitlines()  # pytest's stderr is not a terminal: plain lines, no bar
    assert lines[0].startswith("study: 1/1 run, method=mmshbm elements=4 harmonics=1 [")
    assert lines[-1].startswith("study: 1/1 run, method=mmshbm elements=4 harmonics=1, done [")
    assert not any("\r" in line for line in lines)


def test_convergence_rate_recovers_a_known_power_law():
    H = np.array([1.0, 2.0, 4.0, 8.0, 64.0])  # uneven refinement ratios
    f = 50.0 + 3.0 * H**-2.5
    fit = studies.ConvergenceFit.fit("harmonics", {}, 1.0, "gap", H, f)
    np.testing.assert_allclose(fit.local_rates, 2.5, rtol=1e-8)  # exact for a pure power law
    assert fit.rate == pytest.approx(2.5, rel=1e-8) and fit.n_fit == 4 and fit.rate_note == ""
    # the Richardson estimate is the finest run's true error
    assert fit.error_estimate == pytest.approx(3.0 * 64.0**-2.5, rel=1e-6)
    assert fit.spread == pytest.approx(f[2] - f[4])
    assert np.isnan(studies.ConvergenceFit.fit("elements", {}, 1.0, "gap", H[:2], f[:2]).rate)


def test_convergence_series(serial):
    fits = serial.convergence([2.0])
    by = {(f.vary, tuple(sorted(f.fixed.items()))) for f in fits}
    assert ("harmonics", (("elements", 4), ("method", "mmshbm"))) in by
    assert ("elements", (("harmonics", 3), ("method", "mmshbm"))) in by
    for fit in fits:
        assert fit.difference[-1] == 0 and np.isfinite(fit.difference).all()
    assert "Convergence: steps between successive runs" in serial.report([2.0])


def test_parameter_axis_scales_frequency_exactly():
    """K is proportional to E: quadrupling E doubles every frequency of the backbone at
    the same amplitude (in gaps), a check the grid cannot fake."""
    E0 = mmshbm.default_beam().E
    st = studies.run_study(harmonics=(3,), elements=(4,), params={"E": [E0, 4 * E0]}, executor="serial",
                           max_amplitude=3.0, unit="gap")
    assert [r["E"] for r in st.runs] == [E0, 4 * E0]
    f = st.table([0.5, 1.5, 2.5]).frequency
    np.testing.assert_allclose(f[1] / f[0], 2.0, rtol=1e-7)


def test_option_axis_and_user_model():
    osc = mmshbm.OneDofOscillator()
    st = studies.run_study(model=osc.model(), harmonics=(5,),
                           params={"gap": [1.0, 2.0], "n_samples": [32, 64]},
                           executor="serial", max_amplitude=3.0, unit="gap")
    assert len(st) == 4
    assert [b.metadata["n_samples"] for b in st.branches] == [32, 64, 32, 64]
    # the backbone in gaps does not depend on the gap (piecewise-linear system)
    f = st.table([2.0]).frequency[:, 0]
    np.testing.assert_allclose(f[2:], f[:2], rtol=1e-9)
    exact = osc.frequency(2.0)
    assert abs(f[1] - exact) / exact < 2e-2


def test_save_load(serial, tmp_path):
    path = serial.save(tmp_path / "s.npz")
    again = load(path)
    assert isinstance(again, studies.Study)
    _same(serial, again)
    assert again.metadata["grid"]["elements"] == [4, 6]
    np.testing.assert_array_equal(again.table([2.0]).frequency, serial.table([2.0]).frequency)
    table = serial.to_csv(tmp_path / "t.csv", [2.0])
    lines = table.read_text().splitlines()
    assert lines[0].startswith("method,elements,harmonics,f_at_2gap_hz") and len(lines) == 5


@pytest.mark.parametrize("kwargs, error", [
    ({"methods": ("nope",)}, ValueError),
    ({"executor": "threads"}, TypeError),
    ({"harmonics": 3}, TypeError),
    ({"harmonics": ()}, ValueError),
    ({"params": {"harmonics": [1]}}, ValueError),
    ({"params": {"E": [-1.0]}}, ValueError),
    ({"unit": "mm"}, ValueError),
])
def test_bad_grids(kwargs, error):
    args = {"executor": "serial", "elements": (4,), **kwargs}
    with pytest.raises(error):
        studies.run_study(**args)


def test_method_axis_in_grid_order():
    specs = studies.grid_specs(harmonics=(1, 3), elements=(8,), methods=("mmshbm", "penalty"),
                               params={"grading": [5.0, 10.0]})
    assert [(s.method, s.harmonics, s.source["grading"]) for s in specs] == [
        ("mmshbm", 1, 5.0), ("mmshbm", 1, 10.0), ("mmshbm", 3, 5.0), ("mmshbm", 3, 10.0),
        ("penalty", 1, 5.0), ("penalty", 1, 10.0), ("penalty", 3, 5.0), ("penalty", 3, 10.0)]
    assert [s.index for s in specs] == list(range(8))
    assert all("grading" not in s.options for s in specs)  # a mesh parameter, not a solver option


def test_model_and_beam_exclusive():
    with pytest.raises(ValueError, match="not both"):
        studies.grid_specs(mmshbm.default_beam(), model=mmshbm.OneDofOscillator().model())
    with pytest.raises(ValueError, match="elements"):
        studies.grid_specs(model=mmshbm.OneDofOscillator().model(), elements=(4,))


def test_pool_gets_the_longest_runs_first():
    from mmshbm.analysis.executors import longest_first
    from mmshbm.analysis.studies import grid_specs

    specs = grid_specs(harmonics=(1, 15, 5), elements=(8, 200))
    order = [(s.coords["harmonics"], s.coords["elements"]) for s in longest_first(specs)]
    assert order == [(15, 200), (15, 8), (5, 200), (5, 8), (1, 200), (1, 8)]
    assert sorted(s.index for s in longest_first(specs)) == list(range(len(specs)))
