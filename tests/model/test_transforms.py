"""Models as FE packages export them: the contact layer, the massless contact,
the Euler–Bernoulli cantilever of NLvib."""

import warnings

import numpy as np
import pytest
import scipy.sparse as sp

import mmshbm
from mmshbm import Model, ModelWarning
from mmshbm.fe.euler_bernoulli import cantilever, cantilever_model, element_matrices
from mmshbm.model.contact import Contact
from mmshbm.model.transforms import DEFAULT_LAYER_FACTOR, static_contact_stiffness
from mmshbm.results.branch import rebuild_model

# NLvib's 21-element cantilever with the default beam's geometry
L, B, H_SEC, E, RHO, GAP = 0.5, 0.020, 0.0135, 210e9, 7850.0, 1e-3
EI = E * B * H_SEC**3 / 12
K_P = 1e3 * 3 * EI / L**3


@pytest.fixture(scope="module")
def cantilever21():
    return cantilever_model(L, B, H_SEC, E, RHO, 21, GAP)


def quiet(fn, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        return fn(*args, **kwargs)


# ---------------------------------------------------------------------- the element
def test_hermite_element_is_the_textbook_one():
    Ke, Me = element_matrices([2.0], 3.0, 5.0, 7.0, 11.0)
    l = 2.0  # noqa: E741
    K_ref = 3.0 * 5.0 / l**3 * np.array([[12, 6 * l, -12, 6 * l], [6 * l, 4 * l**2, -6 * l, 2 * l**2],
                                         [-12, -6 * l, 12, -6 * l], [6 * l, 2 * l**2, -6 * l, 4 * l**2]])
    M_ref = 7.0 * 11.0 * l / 420 * np.array([[156, 22 * l, 54, -13 * l],
                                             [22 * l, 4 * l**2, 13 * l, -3 * l**2],
                                             [54, 13 * l, 156, -22 * l],
                                             [-13 * l, -3 * l**2, -22 * l, 4 * l**2]])
    np.testing.assert_allclose(Ke[0], K_ref, rtol=1e-15)
    np.testing.assert_allclose(Me[0], M_ref, rtol=1e-15)
    # a rigid translation carries the element's whole mass, and strains nothing
    u = np.array([1.0, 0, 1.0, 0])
    assert u @ Me[0] @ u == pytest.approx(7.0 * 11.0 * l, rel=1e-14)
    np.testing.assert_allclose(Ke[0] @ u, 0, atol=1e-12)


def test_cantilever_against_euler_bernoulli_theory(cantilever21):
    M, K, dofs = cantilever(L, B, H_SEC, E, RHO, 21)
    assert M.shape == K.shape == (42, 42)
    assert dofs[0].tolist() == [-1, -1] and dofs[-1].tolist() == [40, 41] and dofs[1].tolist() == [0, 1]
    # a cubic is exact for a tip load: the static tip stiffness is 3EI/L^3 to round-off (cond(K) ~ 1e8)
    assert static_contact_stiffness(cantilever21)[0] == pytest.approx(3 * EI / L**3, rel=1e-9)
    # clamped-free frequencies (beta_n L); 21 Hermite elements converge like h^4
    f = cantilever21.linear_frequencies(3)
    f_theory = mmshbm.default_beam().euler_bernoulli_frequencies(3)
    np.testing.assert_allclose(f, f_theory, rtol=2e-4)
    assert abs(f[0] / f_theory[0] - 1) < 1e-7
    # what NLvib prints for the same beam (its matrices are numerically integrated: 1e-9)
    assert f[0] == pytest.approx(45.1178981, rel=1e-8)


# ---------------------------------------------------------------------- the contact layer
def test_contact_layer_adds_a_massless_node_on_a_spring(cantilever21):
    k = 2.5e7
    model = cantilever21.with_contact_layer(k)
    n = cantilever21.n_dof
    assert model.n_dof == n + 1 and model.c.tolist() == [n]
    assert model.contacts == (Contact(n, GAP, 1),) and model.amplitude_dof == 40
    dK = (model.K[:n, :n] - cantilever21.K).toarray()
    expected = np.zeros((n, n))
    expected[40, 40] = k
    np.testing.assert_allclose(dK, expected, atol=1e-6)
    assert model.K[40, n] == -k and model.K[n, n] == k and model.K[n].nnz == 2
    assert (model.M[:n, :n] != cantilever21.M).nnz == 0 and model.M[n].nnz == 0
    # the node follows the tip statically: open-contact modes are those of the structure
    np.testing.assert_allclose(model.linear_frequencies(4), cantilever21.linear_frequencies(4), rtol=1e-12)
    assert model.description["transforms"] == [{"name": "with_contact_layer", "args": {"stiffness": k}}]
    layer = model.description["contact_layer"]
    assert layer["nodes"] == [n] and layer["attached_to"] == [40] and not layer["default"]
    assert layer["factor"][0] == pytest.approx(k / (3 * EI / L**3), rel=1e-10)


def test_default_layer_stiffness_is_a_multiple_of_the_static_stiffness(cantilever21):
    model = cantilever21.with_contact_layer()
    assert model.description["contact_layer"]["default"]
    assert model.K[model.n_dof - 1, model.n_dof - 1] == pytest.approx(DEFAULT_LAYER_FACTOR * 3 * EI / L**3,
                                                                      rel=1e-10)


def test_contact_layer_on_a_mass_is_the_one_dof_oscillator():
    """m on k1 with a rigid stop, plus a layer k2: the closed-form system of DESIGN §4.2."""
    bare = Model.from_matrices([[2.0]], [[3.0]], 0, 0.5)
    layered = bare.with_contact_layer(5.0)
    reference = mmshbm.OneDofOscillator(2.0, 3.0, 5.0, 0.5)
    ref = reference.model()
    assert (layered.M != ref.M).nnz == 0 and (layered.K != ref.K).nnz == 0
    assert layered.contacts == ref.contacts and layered.amplitude_dof == 0
    orbit = mmshbm.exact.periodic_orbit(layered, amplitude=1.5)
    assert orbit.converged
    assert orbit.frequency == pytest.approx(reference.frequency(1.5), rel=1e-12)


def test_one_layer_node_per_contact_of_a_clearance():
    bare = Model.from_matrices([[1.0, 0], [0, 2.0]], [[6.0, -4], [-4, 4]], [1, 1], [0.1, 0.2], [1, -1],
                               amplitude_dof=1)
    layered = bare.with_contact_layer([10.0, 20.0])
    assert layered.contacts == (Contact(2, 0.1, 1), Contact(3, 0.2, -1))
    assert layered.amplitude_dof == 1 and layered.c.tolist() == [2, 3]
    np.testing.assert_allclose(layered.K.toarray()[1], [-4, 34, -10, -20])
    np.testing.assert_allclose(layered.linear_frequencies(2), bare.linear_frequencies(2), rtol=1e-12)


def test_transforms_replay_and_round_trip(tmp_path):
    beam = mmshbm.default_beam()
    model = beam.model(8, massless_tip=False).with_contact_layer(1e7)
    assert rebuild_model(model.description).same_as(model)
    model.save_npz(tmp_path / "layer.npz")
    loaded = Model.from_npz(tmp_path / "layer.npz")
    assert loaded.same_as(model) and loaded.amplitude_dof == model.amplitude_dof
    massless = quiet(beam.model(8, massless_tip=False).with_massless_contact)
    assert quiet(rebuild_model, massless.description).same_as(massless)


@pytest.mark.parametrize("stiffness, error, match", [
    (0.0, ValueError, "stiffness must be positive and finite"),
    (-1e6, ValueError, "stiffness must be positive and finite"),
    (float("nan"), ValueError, "stiffness must be positive and finite"),
    (float("inf"), ValueError, "stiffness must be positive and finite"),
    ("1e6", TypeError, "stiffness must be a real number"),
    ([1e6, 2e6], ValueError, r"one number or one per contact \(1\), got 2"),
])
def test_bad_layer_stiffness_is_named(cantilever21, stiffness, error, match):
    with pytest.raises(error, match=match):
        cantilever21.with_contact_layer(stiffness)


def test_no_layer_on_a_massless_contact():
    with pytest.raises(ValueError, match=r"contact DOF \[40\] is already massless"):
        mmshbm.default_beam().model(21).with_contact_layer(1e7)


# ---------------------------------------------------------------------- the massless contact
def test_massless_contact_moves_f1_as_measured(cantilever21):
    """Zeroing the tip's mass moves f1 from 45.118 to 47.956 Hz (47.975 with the
    deflection alone), and says so."""
    with pytest.warns(ModelWarning, match=r"DOFs \[40, 41\].*f1 45\.118 -> 47\.956 Hz \(\+6\.29 %\)"):
        both = cantilever21.with_massless_contact([40, 41])
    with pytest.warns(ModelWarning, match=r"DOFs \[40\].*f1 45\.118 -> 47\.975 Hz"):
        deflection = cantilever21.with_massless_contact([40])
    assert both.linear_frequencies(1)[0] == pytest.approx(47.956, abs=5e-4)
    assert deflection.linear_frequencies(1)[0] == pytest.approx(47.975, abs=5e-4)
    report = both.description["massless_contact"]
    assert report["frequencies_before"][0] == pytest.approx(45.118, abs=5e-4)
    assert report["relative_shift"][0] == pytest.approx(47.956 / 45.118 - 1, abs=2e-5)
    # removed: the tip's rows and columns, u^T dM u = rhoA l (156 + 2*54)/420 of the uniform mesh
    rho_a, l = RHO * B * H_SEC, L / 21  # noqa: E741
    assert report["mass_measure"] == "rigid-body translation"
    assert report["mass_removed"] == pytest.approx(rho_a * l * 264 / 420, rel=1e-12)
    assert report["mass_fraction"] == pytest.approx(report["mass_removed"] / report["mass_total"], rel=1e-14)
    assert both.c.tolist() == [40, 41] and deflection.c.tolist() == [40]
    assert both.description["transforms"][-1] == {"name": "with_massless_contact", "args": {"dofs": [40, 41]}}
    # the default takes the contact node's DOFs from the description
    assert quiet(cantilever21.with_massless_contact).same_as(both)


def test_massless_contact_of_the_beam_is_the_massless_tip():
    beam = mmshbm.default_beam()
    with pytest.warns(ModelWarning, match=r"0\.86 %.*f1 45\.092 -> 45\.815 Hz \(\+1\.60 %\)"):
        converted = beam.model(21, massless_tip=False).with_massless_contact()
    reference = beam.model(21)
    assert (converted.M != reference.M).nnz == 0 and (converted.K != reference.K).nnz == 0
    assert converted.contacts == reference.contacts


def test_massless_contact_without_a_translation_measure_uses_the_trace():
    model = Model.from_matrices(np.diag([1.0, 3.0]), [[2.0, -1], [-1, 2]], 1, 0.1)
    with pytest.warns(ModelWarning, match="trace measure"):
        converted = model.with_massless_contact()
    assert converted.description["massless_contact"]["mass_fraction"] == pytest.approx(0.75, rel=1e-15)
    np.testing.assert_allclose(converted.linear_frequencies(1), np.sqrt(1.5) / (2 * np.pi), rtol=1e-14)


def test_massless_contact_zeroes_the_damping_of_the_node():
    model = Model.from_matrices(np.diag([1.0, 3.0]), [[2.0, -1], [-1, 2]], 1, 0.1,
                                damping=sp.diags([0.1, 0.2]))
    with pytest.warns(ModelWarning, match="and their damping"):
        converted = model.with_massless_contact([1])
    assert converted.damping.toarray().tolist() == [[0.1, 0.0], [0.0, 0.0]]


@pytest.mark.parametrize("dofs, error, match", [
    ([40, 40], ValueError, r"names DOF 40 twice \(dofs\[0\] and dofs\[1\]\)"),
    ([40, 42], ValueError, r"dofs\[1\] = 42 is out of range \[0, 41\]"),
    ([-1], ValueError, r"dofs\[0\] = -1 is out of range"),
    ([], ValueError, "dofs is empty"),
    ([40.0], TypeError, r"dofs\[0\] must be an integer"),
    ("40", TypeError, r"dofs\[0\] must be an integer"),
])
def test_bad_massless_dofs_are_named(cantilever21, dofs, error, match):
    with pytest.raises(error, match=match):
        cantilever21.with_massless_contact(dofs)


def test_nothing_to_remove_is_an_error():
    with pytest.raises(ValueError, match=r"dofs \[40, 41\] are massless already"):
        mmshbm.default_beam().model(21).with_massless_contact()
