"""Several contacts, clearances, amplitude DOF and damping on a Model."""

import numpy as np
import pytest
import scipy.sparse as sp

import mmshbm
from mmshbm import Model
from mmshbm.model.contact import Contact, admissible_intervals

# two identical uncoupled oscillators: masses on DOFs 0 and 2, massless nodes 1 and 3
M = np.diag([1.0, 0.0, 1.0, 0.0])
K = np.array([[5.0, -4, 0, 0], [-4, 4, 0, 0], [0, 0, 5, -4], [0, 0, -4, 4]])


def test_scalars_keep_the_names_of_one_contact():
    model = Model.from_matrices(M[:2, :2], K[:2, :2], 1, 0.5)
    assert model.contacts == (Contact(1, 0.5, 1),)
    assert (model.contact_dof, model.gap, model.stop_side, model.amplitude_dof) == (1, 0.5, 1, 1)


def test_sequences_build_several_contacts():
    model = Model.from_matrices(M, K, [1, 3], [1.0, 2.0], [1, -1], amplitude_dof=0)
    assert model.contacts == (Contact(1, 1.0, 1), Contact(3, 2.0, -1))
    assert model.n_contacts == 2 and model.gap == 1.0 and model.amplitude_dof == 0
    dofs, lo, hi = admissible_intervals(model.contacts)
    np.testing.assert_array_equal(dofs, [1, 3])
    np.testing.assert_array_equal(lo, [-np.inf, -2.0])
    np.testing.assert_array_equal(hi, [1.0, np.inf])
    for name in ("contact_dof", "stop_side"):
        with pytest.raises(ValueError, match="has 2 contacts"):
            getattr(model, name)


def test_a_clearance_is_one_dof_with_two_sides():
    model = Model.from_matrices(M[:2, :2], K[:2, :2], [1, 1], 0.3, [1, -1])
    dofs, lo, hi = admissible_intervals(model.contacts)
    assert dofs.tolist() == [1] and lo.tolist() == [-0.3] and hi.tolist() == [0.3]
    # the massless DOF between the stops cannot pass them: the amplitude is the mass's
    assert model.amplitude_dof == 0


@pytest.mark.parametrize("kwargs, match", [
    ({"contact_dof": [1, 3], "gap": [1.0, 2.0, 3.0], "stop_side": 1}, "equal lengths"),
    ({"contact_dof": [1, 1], "gap": 1.0, "stop_side": [1, 1]}, "both put a stop on the \\+ side of DOF 1"),
    ({"contact_dof": [1, 3], "gap": 1.0, "stop_side": [1, 0]}, r"stop_side\[1\] must be \+1 or -1"),
    ({"contact_dof": [1, 4], "gap": 1.0, "stop_side": 1}, r"contact_dof\[1\] must be in \[0, 3\], got 4"),
    ({"contact_dof": [], "gap": 1.0, "stop_side": 1}, "contact_dof is empty but gap is 1.0"),
    ({"contact_dof": [], "gap": [1.0], "stop_side": 1}, "contact_dof is empty but gap has 1 entries"),
    ({"contact_dof": [1, 3], "gap": [1.0, -1.0], "stop_side": 1}, r"gap\[1\] must be >= 0"),
    ({"contact_dof": [1, 3], "gap": 1.0, "stop_side": 1, "amplitude_dof": 9}, "amplitude_dof must be in"),
])
def test_bad_contact_data_is_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Model.from_matrices(M, K, **kwargs)


def test_files_round_trip_several_contacts_and_damping(tmp_path):
    C = sp.diags([0.1, 0.0, 0.2, 0.0])
    model = Model.from_matrices(M, K, [1, 3], [1.0, 2.0], [1, -1], damping=C, amplitude_dof=2)
    model.save_npz(tmp_path / "m.npz")
    back = Model.from_npz(tmp_path / "m.npz")
    assert back.same_as(model) and back.fingerprint() == model.fingerprint()
    assert back.amplitude_dof == 2 and back.damping is not None
    assert model.fingerprint() != model.with_gap([1.0, 2.5]).fingerprint()


def test_damping_must_leave_massless_dofs_static():
    C = np.zeros((4, 4))
    C[1, 1] = 0.1
    with pytest.raises(ValueError, match=r"damping acts on the massless DOFs \[1\]"):
        Model.from_matrices(M, K, [1, 3], 1.0, damping=C, amplitude_dof=0)


def test_mass_on_the_contact_dof_is_accepted_but_mmshbm_names_the_conversions():
    model = Model.from_matrices(np.diag([1.0, 0.5]), np.array([[5.0, -4], [-4, 4]]), 1, 0.5)
    assert not model.massless_contacts
    with pytest.raises(ValueError, match="with_contact_layer.*with_massless_contact"):
        mmshbm.backbone(model)
    with pytest.raises(ValueError, match="exact reference needs massless"):
        mmshbm.exact.periodic_orbit(model, amplitude=1.0)
