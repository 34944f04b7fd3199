"""mmshbm.Model: validation, file round trips, linear modes; beam and oscillator inputs."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.io
import scipy.linalg
import scipy.sparse as sp

import mmshbm
from mmshbm import Model, OneDofOscillator, TimoshenkoBeam, default_beam

M2 = np.diag([1.0, 0.0])
K2 = np.array([[5.0, -4.0], [-4.0, 4.0]])  # the one-DOF oscillator, m = k1 = 1, k2 = 4


def test_from_matrices_accepts_dense_and_sparse():
    for M, K in ((M2, K2), (sp.csr_matrix(M2), sp.coo_matrix(K2))):
        model = Model.from_matrices(M, K, contact_dof=1, gap=0.1)
        assert sp.issparse(model.M) and model.M.shape == (2, 2)
        assert model.c.tolist() == [1] and model.l.tolist() == [0]
        assert model.contact_index == 0 and model.w_c.tolist() == [-1.0]


@pytest.mark.parametrize("M, K, kwargs, error, match", [
    (np.ones((2, 3)), K2, {}, ValueError, "M must be square"),
    (M2, np.ones((3, 2)), {}, ValueError, "K must be square"),
    (np.ones(3), K2, {}, ValueError, "M must be 2-D"),
    ([["a", "b"], ["c", "d"]], K2, {}, TypeError, "M must be a 2-D array"),
    (np.zeros((0, 0)), K2, {}, ValueError, "M is empty"),
    (M2, np.array([[5.0, -4.0], [-3.0, 4.0]]), {}, ValueError, "K must be symmetric"),
    (np.array([[1.0, 0.5], [0.0, 0.0]]), K2, {}, ValueError, "M must be symmetric"),
    (M2, np.array([[np.nan, -4.0], [-4.0, 4.0]]), {}, ValueError, "K has a non-finite entry"),
    (np.diag([np.inf, 0.0]), K2, {}, ValueError, "M has a non-finite entry"),
    (np.diag([1.0, 0.0, 0.0]), K2, {}, ValueError, "M and K must have the same shape"),
    (M2, K2, {"contact_dof": 2}, ValueError, r"contact_dof must be in \[0, 1\]"),
    (M2, K2, {"contact_dof": -1}, ValueError, "contact_dof must be in"),
    (M2, K2, {"contact_dof": 1.0}, TypeError, "contact_dof must be an integer"),
    (M2, K2, {"gap": -1e-3}, ValueError, "gap must be >= 0"),
    (M2, K2, {"gap": np.nan}, ValueError, "gap must be finite"),
    (M2, K2, {"stop_side": 0}, ValueError, "stop_side must be"),
    (M2, K2, {"stop_side": 2}, ValueError, "stop_side must be"),
    (M2, K2, {"stop_side": True}, ValueError, "stop_side must be"),
    (np.zeros((2, 2)), K2, {}, ValueError, "no DOF with mass"),
    # free-floating mass: the condensed stiffness vanishes
    (M2, np.array([[4.0, -4.0], [-4.0, 4.0]]), {}, ValueError, "condensed .* singular .*fixed"),
    # a massless DOF with no stiffness
    (np.diag([1.0, 0.0, 0.0]), np.diag([1.0, 1.0, 0.0]), {}, ValueError, "massless DOFs is singular"),
    (M2, -K2, {}, ValueError, "indefinite"),
    (np.diag([-1.0, 0.0]), K2, {}, ValueError, "M restricted to the DOFs with mass is indefinite"),
])
def test_from_matrices_rejects_bad_input(M, K, kwargs, error, match):
    args = {"contact_dof": 1, "gap": 0.1, **kwargs}
    with pytest.raises(error, match=match):
        Model.from_matrices(M, K, **args)


def test_unfixed_beam_is_rejected():
    beam = default_beam()
    n = 4
    M, K = beam.matrices(n, 10.0, clamped=False)  # free-free: two rigid-body modes
    tip = np.ones(M.shape[0])
    tip[[2 * n, 2 * n + 1]] = 0.0
    D = sp.diags(tip)
    with pytest.raises(ValueError, match="singular"):
        Model.from_matrices(D @ M @ D, K, contact_dof=2 * n, gap=1e-3)


# ---------------------------------------------------------------------------- files
def test_npz_round_trip(tmp_path):
    model = default_beam().model(8)
    path = tmp_path / "beam.npz"
    model.save_npz(path)
    again = Model.from_npz(path)
    assert (again.M != model.M).nnz == 0 and (again.K != model.K).nnz == 0
    assert (again.contact_dof, again.gap, again.stop_side) == (model.contact_dof, model.gap, model.stop_side)
    assert again.description == model.description
    assert np.allclose(again.linear_frequencies(2), model.linear_frequencies(2), rtol=1e-14)
    other = Model.from_npz(path, gap=2e-3, stop_side=-1)  # arguments override the file
    assert other.gap == 2e-3 and other.stop_side == -1


def test_npz_with_dense_arrays_and_missing_entries(tmp_path):
    path = tmp_path / "dense.npz"
    np.savez(path, M=M2, K=K2)
    with pytest.raises(ValueError, match="has no 'contact_dof'"):
        Model.from_npz(path)
    model = Model.from_npz(path, contact_dof=1, gap=0.5)
    assert model.gap == 0.5 and model.stop_side == 1
    np.savez(path, M=M2, contact_dof=1, gap=0.5)
    with pytest.raises(ValueError, match="has no matrix 'K'"):
        Model.from_npz(path)


@pytest.mark.parametrize("content", [b"not a model at all", b"PK\x03\x04 truncated zip", None, "npy"])
def test_unreadable_npz_raises_value_error(tmp_path, content):
    path = tmp_path / "bad.npz"
    if content == "npy":
        with open(path, "wb") as f:
            np.save(f, np.eye(2))
    elif content is not None:
        path.write_bytes(content)
    with pytest.raises(ValueError, match="cannot read model file"):
        Model.from_npz(path)


def test_truncated_npz_raises_value_error(tmp_path):
    path = tmp_path / "beam.npz"
    default_beam().model(4).save_npz(path)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(ValueError, match="cannot read model file"):
        Model.from_npz(path)


def test_matrix_market_round_trip(tmp_path):
    model = default_beam().model(8)
    mp, kp = tmp_path / "M.mtx", tmp_path / "K.mtx"
    scipy.io.mmwrite(str(mp), model.M, precision=17)
    scipy.io.mmwrite(str(kp), model.K, precision=17)
    again = Model.from_matrix_market(mp, kp, contact_dof=model.contact_dof, gap=model.gap)
    assert abs(again.M - model.M).max() == 0 and abs(again.K - model.K).max() == 0
    assert np.allclose(again.linear_frequencies(3), model.linear_frequencies(3), rtol=1e-14)


def test_malformed_matrix_market_raises_value_error(tmp_path):
    good = tmp_path / "K.mtx"
    scipy.io.mmwrite(str(good), sp.csr_matrix(K2))
    bad = tmp_path / "M.mtx"
    bad.write_text("this is not a matrix market file\n")
    with pytest.raises(ValueError, match="cannot read M"):
        Model.from_matrix_market(bad, good, contact_dof=1, gap=0.1)
    with pytest.raises(ValueError, match="cannot read K"):
        Model.from_matrix_market(good, tmp_path / "missing.mtx", contact_dof=1, gap=0.1)


# ---------------------------------------------------------------------------- linear modes
@pytest.mark.parametrize("model", [default_beam().model(21), default_beam().model(8, 1.0),
                                   mmshbm.one_dof_oscillator()], ids=["beam21", "beam8", "oscillator"])
def test_linear_modes_mass_normalised_with_static_massless_dofs(model):
    n = min(3, len(model.l))
    f, modes = model.linear_modes(n)
    assert modes.shape == (model.n_dof, n) and np.all(np.diff(f) > 0)
    M, K = model.M.toarray(), model.K.toarray()
    assert np.allclose(modes.T @ M @ modes, np.eye(n), atol=1e-10)
    c, l = model.c, model.l
    # massless DOFs follow statically: K_cl q_l + K_cc q_c = 0
    static = K[np.ix_(c, l)] @ modes[l] + K[np.ix_(c, c)] @ modes[c]
    assert np.abs(static).max() <= 1e-10 * np.abs(K).max() * np.abs(modes).max()
    # and the whole system satisfies K φ = ω² M φ
    omega2 = (2 * np.pi * f) ** 2
    assert np.allclose(K @ modes, M @ modes * omega2, rtol=0, atol=1e-9 * np.abs(K @ modes).max())
    # each mode's contact DOF moves toward the stop first
    assert np.all(modes[model.contact_dof] * model.stop_side > 0)
    assert np.allclose(model.linear_frequencies(n), f, rtol=1e-14)


def test_linear_modes_sparse_path_agrees_with_dense():
    model = default_beam().model(400, 1.0)  # 798 DOFs with mass: Lanczos in shift-invert
    f_sparse, modes = model.linear_modes(3)
    M_ll, K_red = model.blocks["M_ll"].toarray(), model.reduced_stiffness.toarray()
    mu = scipy.linalg.eigh(M_ll, K_red, eigvals_only=True)[::-1][:3]  # μ = 1/ω², largest first
    assert np.allclose(f_sparse, 1 / np.sqrt(mu) / (2 * np.pi), rtol=1e-9)
    assert np.allclose(modes.T @ model.M @ modes, np.eye(3), atol=1e-9)


def test_linear_modes_rejects_bad_n():
    model = mmshbm.one_dof_oscillator()
    with pytest.raises(ValueError, match="n must be <="):
        model.linear_modes(2)
    with pytest.raises(ValueError, match="n must be >= 1"):
        model.linear_modes(0)


def test_one_dof_oscillator_frequencies():
    osc = OneDofOscillator(m=2.0, k1=3.0, k2=5.0, gap=0.1)
    model = osc.model()
    w1, w2 = np.sqrt(3.0 / 2.0), np.sqrt(8.0 / 2.0)
    assert np.isclose(model.linear_frequencies(1)[0], w1 / (2 * np.pi), rtol=1e-14)
    assert np.isclose(model.zero_gap_frequency(), 1 / (np.pi / w1 + np.pi / w2), rtol=1e-14)
    assert np.isclose(osc.zero_gap_frequency(), model.zero_gap_frequency(), rtol=1e-14)
    # the closed-form backbone: linear below the gap, bilinear limit far above it
    assert np.isclose(osc.frequency(0.05), w1 / (2 * np.pi), rtol=1e-14)
    assert np.isclose(osc.frequency(1e9), osc.zero_gap_frequency(), rtol=1e-6)


def test_beam_zero_gap_frequency_lies_between_open_and_closed():
    model = default_beam().model(8)
    f_open = model.linear_frequencies(1)[0]
    f0 = model.zero_gap_frequency()
    assert f_open < f0 < 2 * f_open


def test_with_gap_and_repr():
    model = mmshbm.one_dof_oscillator(gap=1.0)
    other = model.with_gap(0.25)
    assert other.gap == 0.25 and model.gap == 1.0 and other.K is model.K
    with pytest.raises(ValueError, match="gap must be >= 0"):
        model.with_gap(-1.0)
    assert "contact_dof=1" in repr(model)


# ---------------------------------------------------------------------------- beam validation
GOOD = {"length": 0.5, "width": 0.02, "height": 0.0135, "E": 210e9, "rho": 7850.0}


@pytest.mark.parametrize("field", ["length", "width", "height", "E", "rho", "shear_factor"])
@pytest.mark.parametrize("value", [0.0, -1.0])
def test_beam_rejects_non_positive_data(field, value):
    with pytest.raises(ValueError, match=f"{field} must be positive, got {value}"):
        TimoshenkoBeam(**{**GOOD, field: value})


@pytest.mark.parametrize("kwargs, error, match", [
    ({"nu": 0.5}, ValueError, r"nu must be in \(-1, 0.5\)"),
    ({"nu": -1.0}, ValueError, "nu must be in"),
    ({"nu": float("nan")}, ValueError, "nu must be finite"),
    ({"gap": -1e-3}, ValueError, "gap must be >= 0, got -0.001"),
    ({"E": "210e9"}, TypeError, "E must be a real number"),
    ({"length": float("inf")}, ValueError, "length must be finite"),
])
def test_beam_rejects_bad_data(kwargs, error, match):
    with pytest.raises(error, match=match):
        TimoshenkoBeam(**{**GOOD, **kwargs})


@pytest.mark.parametrize("kwargs, error, match", [
    ({"n_elements": 0}, ValueError, "n_elements must be >= 1, got 0"),
    ({"n_elements": 2.5}, TypeError, "n_elements must be an integer"),
    ({"n_elements": 4, "grading": 0.0}, ValueError, "grading must be positive"),
    ({"n_elements": 4, "grading": -3.0}, ValueError, "grading must be positive"),
    ({"n_elements": 4, "massless_tip": "yes"}, TypeError, "massless_tip must be a bool"),
])
def test_beam_model_rejects_bad_mesh(kwargs, error, match):
    with pytest.raises(error, match=match):
        default_beam().model(**kwargs)


def test_beam_section_and_defaults():
    beam = default_beam()
    assert beam == TimoshenkoBeam(**GOOD, nu=0.3, shear_factor=5 / 6, gap=1e-3)
    assert np.isclose(beam.area, 0.02 * 0.0135) and np.isclose(beam.inertia, 0.02 * 0.0135**3 / 12)
    assert np.isclose(beam.shear_modulus, 210e9 / 2.6)
    assert isinstance(beam.length, float)
    model = beam.model(1, massless_tip=False)  # one element, tip keeps its mass: linear only
    assert model.n_dof == 2 and len(model.c) == 0
    assert 0 < model.linear_frequencies(1)[0] < 1.1 * beam.euler_bernoulli_frequencies(1)[0]
    with pytest.raises(ValueError, match="not of a TimoshenkoBeam"):
        TimoshenkoBeam.rebuild({"kind": "OneDofOscillator"})
    with pytest.raises(ValueError, match="lacks the entry 'grading'"):
        TimoshenkoBeam.rebuild({"kind": "TimoshenkoBeam", **GOOD, "nu": 0.3, "shear_factor": 0.8,
                                "gap": 0.0, "n_elements": 3})
