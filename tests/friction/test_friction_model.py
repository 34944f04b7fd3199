"""Models with Coulomb friction contacts: building, validation, saving and loading."""

import numpy as np
import pytest

import mmshbm
from mmshbm.model.friction import FrictionContact


def jenkins(m=1.0, k1=1.0, k2=2.0):
    M = np.diag([m, 0.0])
    K = np.array([[k1 + k2, -k2], [-k2, k2]])
    return mmshbm.Model.from_matrices(M, K, contact_dof=[], gap=[], stop_side=[], amplitude_dof=0)


def test_a_model_without_unilateral_contact():
    model = jenkins()
    assert model.contacts == () and model.friction == ()
    assert model.linear_frequencies(1)[0] == pytest.approx(1.0 / (2 * np.pi), rel=1e-14)  # node free: k1
    with pytest.raises(ValueError, match="contact_dof is empty but gap"):
        mmshbm.Model.from_matrices(np.diag([1.0, 0.0]), np.eye(2), contact_dof=[], gap=[1e-3], stop_side=[])


def test_with_friction_adds_contacts_and_keeps_the_original():
    M = np.diag([1.0, 1.0, 0.0, 0.0])
    K = np.array([[3.0, -1, -1, 0], [-1, 3, 0, -1], [-1, 0, 2, 0], [0, -1, 0, 2]])
    base = mmshbm.Model.from_matrices(M, K, [], [], [], amplitude_dof=0)
    one = base.with_friction(2, 0.3, normal_load=5.0)
    two = one.with_friction(3, 0.1, normal_load=0.0)
    assert base.friction == ()
    assert two.friction == (FrictionContact(2, 0.3, 5.0), FrictionContact(3, 0.1, 0.0))
    assert two.friction[0].slip_force == pytest.approx(1.5)
    assert not two.same_as(one) and two.fingerprint() != one.fingerprint()
    with pytest.raises(ValueError, match="already carries a friction"):
        two.with_friction(2, 0.3, normal_load=1.0)


@pytest.mark.parametrize("kwargs,match", [
    ({"dof": 1, "mu": -0.1, "normal_load": 1.0}, "mu must be >= 0"),
    ({"dof": 1, "mu": 0.1, "normal_load": -1.0}, "normal_load must be >= 0"),
    ({"dof": 0, "mu": 0.1, "normal_load": 1.0}, "dof 0 carries mass"),
    ({"dof": 5, "mu": 0.1, "normal_load": 1.0}, "dof must be in"),
    ({"dof": 1, "mu": 0.1}, "exactly one of normal_load"),
    ({"dof": 1, "mu": 0.1, "normal_load": 1.0, "normal_contact": 0}, "exactly one of normal_load"),
    ({"dof": 1, "mu": 0.1, "normal_contact": 0}, "normal_contact must index"),
    ({"dof": 1, "mu": 0.1, "normal_load": 1.0, "preload": 1.0}, "preload= goes with normal_contact"),
])
def test_bad_friction_input_is_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        jenkins().with_friction(**kwargs)


def test_friction_coupled_to_a_unilateral_contact_is_stored():
    M = np.diag([1.0, 0.0, 0.0])
    K = np.array([[3.0, -1, -1], [-1, 2, 0], [-1, 0, 2]])
    model = mmshbm.Model.from_matrices(M, K, 1, 1e-3, amplitude_dof=0).with_friction(
        2, 0.2, normal_contact=0, preload=0.5)
    assert model.friction == (FrictionContact(2, 0.2, None, 0, 0.5),)
    with pytest.raises(ValueError, match="varies in time"):
        _ = model.friction[0].slip_force
    with pytest.raises(ValueError, match="carries a unilateral contact"):
        model.with_friction(1, 0.2, normal_load=1.0)


def test_friction_is_saved_and_loaded(tmp_path):
    model = jenkins().with_damping(modal_ratio=0.02).with_friction(1, 0.3, normal_load=2.0)
    path = tmp_path / "jenkins.npz"
    model.save_npz(path)
    back = mmshbm.Model.from_npz(path)
    assert back.same_as(model) and back.fingerprint() == model.fingerprint()
    assert back.friction == model.friction
    assert back.description == model.description  # loading does not record the transform twice


def test_transforms_keep_the_friction_contacts():
    M = np.diag([1.0, 1.0, 0.0])
    K = np.array([[3.0, -1.0, -1.0], [-1.0, 3.0, 0.0], [-1.0, 0.0, 2.0]])
    model = mmshbm.Model.from_matrices(M, K, [], [], [], amplitude_dof=0)
    model = model.with_friction(2, 0.3, normal_load=1.0)
    with pytest.warns(mmshbm.ModelWarning):
        lighter = model.with_massless_contact([1])
    assert lighter.friction == model.friction and 1 in lighter.c.tolist()
