"""Branch files: bit-identical save/load, metadata enough to redo the run, CSV export."""

import numpy as np
import pytest
import scipy.sparse as sp

import mmshbm
from mmshbm.io import load
from mmshbm.results.branch import ARRAY_FIELDS, Branch

OSC = mmshbm.OneDofOscillator(m=1.0, k1=1.0, k2=4.0, gap=1.0)


@pytest.fixture(scope="module")
def beam_branch():
    branch = mmshbm.backbone(mmshbm.default_beam().model(6), harmonics=3, max_amplitude=3e-3)
    branch.records["floquet_max"] = np.linspace(1.0, 2.0, len(branch))
    branch.records["matrix_record"] = np.arange(2 * len(branch), dtype=np.int32).reshape(-1, 2)
    return branch


def _assert_identical(a: Branch, b: Branch):
    for name in ARRAY_FIELDS:
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and x.shape == y.shape, name
        assert x.tobytes() == y.tobytes(), name  # bit-identical, NaNs included
    assert (a.status, a.method, a.harmonics) == (b.status, b.method, b.harmonics)
    assert a.special_points == b.special_points
    assert sorted(a.records) == sorted(b.records)
    for name in a.records:
        assert a.records[name].dtype == b.records[name].dtype
        assert a.records[name].tobytes() == b.records[name].tobytes()
    assert len(a.residual_histories) == len(b.residual_histories)
    for h, g in zip(a.residual_histories, b.residual_histories, strict=True):
        assert np.asarray(h, float).tobytes() == g.tobytes()


def test_save_load_bit_identical(beam_branch, tmp_path):
    path = beam_branch.save(tmp_path / "b.npz")
    loaded = Branch.load(path)
    _assert_identical(beam_branch, loaded)
    assert loaded.attached_solver is None  # loading builds no solver; ``solver`` does, on first access
    again = Branch.load(loaded.save(tmp_path / "c.npz"))
    _assert_identical(beam_branch, again)
    assert isinstance(load(path), Branch)


def test_metadata_is_enough_to_redo_the_run(beam_branch, tmp_path):
    loaded = Branch.load(beam_branch.save(tmp_path / "b.npz"))
    meta = loaded.metadata
    assert meta["model"]["kind"] == "TimoshenkoBeam" and meta["model"]["n_elements"] == 6
    assert meta["method"] == "mmshbm" and meta["harmonics"] == 3 and meta["n_samples"] >= 7
    rerun = loaded.rerun()
    np.testing.assert_array_equal(rerun.states, beam_branch.states)
    np.testing.assert_array_equal(rerun.frequency, beam_branch.frequency)


def test_versions_are_saved(beam_branch, tmp_path):
    import json

    path = beam_branch.save(tmp_path / "b.npz")
    with np.load(path) as f:
        meta = json.loads(str(f["metadata"]))
    assert meta["saved_with"]["mmshbm"] == mmshbm.__version__
    assert {"numpy", "scipy", "numba", "python"} <= set(meta["saved_with"])
    assert meta["format"] == "mmshbm.Branch"


def test_loaded_branch_rebuilds_its_solver(beam_branch, tmp_path):
    loaded = Branch.load(beam_branch.save(tmp_path / "b.npz"))
    i = len(beam_branch) - 1
    t0, q0 = beam_branch.time_signals(i, n_samples=64)
    t1, q1 = loaded.time_signals(i, n_samples=64)
    np.testing.assert_array_equal(t0, t1)
    np.testing.assert_allclose(q1, q0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(loaded.contact_force(i, 64)[1], beam_branch.contact_force(i, 64)[1], atol=1e-9)


def test_user_matrices_are_stored(tmp_path):
    base = OSC.model()
    model = mmshbm.Model.from_matrices(base.M.toarray(), base.K.toarray(), base.contact_dof, base.gap)
    branch = mmshbm.backbone(model, harmonics=3, max_amplitude=2.0)
    loaded = Branch.load(branch.save(tmp_path / "u.npz"), attach_solver=True)
    assert (loaded.get_model().K != sp.csr_matrix(base.K)).nnz == 0
    assert loaded.get_model().gap == model.gap
    np.testing.assert_array_equal(loaded.rerun().states, branch.states)


def test_csv_export_full_precision(beam_branch, tmp_path):
    path = beam_branch.to_csv(tmp_path / "b.csv")
    header = path.read_text().splitlines()[0].split(",")
    assert header[:6] == ["frequency_hz", "amplitude_m", "energy_j", "contact_force_max_n",
                          "newton_iterations", "step_size"]
    assert header[6:] == [k for k, v in beam_branch.records.items() if np.ndim(v) == 1]  # 1-D records only
    assert "floquet_max" in header and "mode_share" in header
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    np.testing.assert_array_equal(data[:, 0], beam_branch.frequency)
    np.testing.assert_array_equal(data[:, 1], beam_branch.amplitude)
    np.testing.assert_array_equal(data[:, 4], beam_branch.newton_iterations)
    np.testing.assert_array_equal(data[:, header.index("floquet_max")], beam_branch.records["floquet_max"])


@pytest.mark.parametrize("content", [b"", b"not a zip", None])
def test_bad_files(tmp_path, content):
    path = tmp_path / "bad.npz"
    if content is None:
        np.savez(path, x=np.zeros(3))  # an npz without the metadata record
    else:
        path.write_bytes(content)
    with pytest.raises(ValueError, match="bad.npz"):
        Branch.load(path)
    with pytest.raises(ValueError):
        Branch.load(tmp_path / "missing.npz")


def test_index_checks(beam_branch):
    with pytest.raises(IndexError):
        beam_branch.harmonic_content(len(beam_branch))
    with pytest.raises(TypeError):
        beam_branch.contact_force(1.5)


def test_shooting_records_round_trip(tmp_path):
    branch = mmshbm.backbone(OSC.model(), method="shooting", max_amplitude=2.0)
    assert "floquet_max" in branch.records
    loaded = Branch.load(branch.save(tmp_path / "s.npz"))
    _assert_identical(branch, loaded)
    header = loaded.to_csv(tmp_path / "s.csv").read_text().splitlines()[0]
    assert "floquet_max" in header.split(",")
    # conservative system: the largest Floquet multiplier has modulus 1 (up to the time step)
    np.testing.assert_allclose(loaded.records["floquet_max"], 1.0, atol=1e-2)


def test_special_points_keep_their_data_through_files(tmp_path):
    from mmshbm.core.special_points import SpecialPoint

    branch = mmshbm.backbone(mmshbm.one_dof_oscillator(), harmonics=3, max_amplitude=3.0)
    branch.special_points.insert(2, SpecialPoint("internal_resonance", 3, k=5, j=2, ratio=1.0004))
    back = mmshbm.Branch.load(branch.save(tmp_path / "b.npz"))
    point = [p for p in back.special_points if p.kind == "internal_resonance"][0]
    assert point == ("internal_resonance", 3) and point.data == {"k": 5, "j": 2, "ratio": 1.0004}
    kind, index = point  # unpacks like the pairs of 0.1
    assert (kind, index) == ("internal_resonance", 3)
