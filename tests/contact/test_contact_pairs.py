"""3-D node-to-node contact pairs (mmshbm.model.contact_pairs): one pair against the normal
stop and two coupled Coulomb sliders built with the existing API, rotation invariance,
the bonded normal in full stick against the linear bonded structure, and bad input."""

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.spatial.transform import Rotation

from mmshbm.methods.mms.friction_forced import FrictionForcedProblem
from mmshbm.model.contact_pairs import fe_pair_dofs, pair_dofs, pair_frames, with_contact_pairs
from mmshbm.model.friction import with_slider
from mmshbm.model.model import Model
from mmshbm.model.readers.fematrices import FEMatrices

# a 3-D point mass on an anisotropic spring, pressed by a pair against the ground
_M = np.diag([1.0, 1.3, 0.8])
_K = np.array([[3.0, 0.4, 0.2], [0.4, 2.5, 0.3], [0.2, 0.3, 4.0]]) * 1e4
_KN, _KT, _MU, _N0 = 2e5, 1e5, 0.3, 5.0
_F = np.array([3.0, 2.0, 40.0])  # N: the stop closes and opens, the tangents slip part of the period
_HZ = 30.0
# Newton stops at the scaled residual 1e-11 (solve_at); the scaled Jacobians of these
# 6-DOF problems have condition numbers below 1e3, so the unknowns agree to ~1e-8 relative
_TOL = 1e-8


def _mass(Q=None):
    Q = np.eye(3) if Q is None else Q
    return Model.from_matrices(sp.csr_matrix(Q @ _M @ Q.T), sp.csr_matrix(Q @ _K @ Q.T), [], [], [],
                               amplitude_dof=0)


def _pair_model(Q=None, normal="unilateral"):
    Q = np.eye(3) if Q is None else Q
    return with_contact_pairs(_mass(Q), [[0, 1, 2]], Q @ [0.0, 0.0, 1.0], tangents=Q @ [1.0, 0.0, 0.0],
                              mu=_MU, preload=_N0, normal_stiffness=_KN, tangential_stiffness=_KT,
                              normal=normal).with_damping(modal_ratio=0.02)


def _solve(model, force):
    P = FrictionForcedProblem(model, np.concatenate([force, np.zeros(model.n_dof - 3)]), harmonics=5)
    u = P.start_point(_HZ)
    x, omega = P.unpack(u)
    assert np.abs(P.residual_parts(x, omega, 1.0, False)[0] / P.rowscale).max() < 1e-10
    return P, u, x, omega


def test_one_pair_is_the_normal_stop_with_two_coupled_sliders():
    s_model, s_n = with_slider(_mass(), 2, _KN)
    ref = Model.from_matrices(s_model.M, s_model.K, [s_n], [0.0], [-1], amplitude_dof=0)
    for d in (0, 1):
        ref = ref.with_friction(d, _MU, normal_contact=0, preload=_N0, tangential_stiffness=_KT)
    ref = ref.with_damping(modal_ratio=0.02)
    new = _pair_model()
    assert new.contacts == ref.contacts and new.friction == ref.friction
    assert abs(new.K - ref.K).max() <= 1e-14 * abs(ref.K).max()
    P, _, x, omega = _solve(new, _F)
    _, _, x_ref, _ = _solve(ref, _F)
    assert np.abs(x - x_ref).max() <= _TOL * np.abs(x_ref).max()
    rec = P._record(x, omega, 1.0)
    # the orbit exercises the laws: the stop closes, the tangents slip part of the period
    assert rec["contact_force_max"] > 10 * _N0 and 0.01 < rec["slip_fraction"] < 0.99


def test_pair_response_is_invariant_under_a_rotation_of_the_whole_problem():
    Q = Rotation.from_rotvec([0.4, -0.7, 0.25]).as_matrix()
    P0, u0, x0, _ = _solve(_pair_model(), _F)
    P1, u1, x1, _ = _solve(_pair_model(Q), Q @ _F)
    # the slip DOFs are frame quantities: equal; the mass's displacement turns with Q
    assert np.abs(x1 - x0).max() <= _TOL * np.abs(x0).max()
    q0, q1 = P0.coefficients(u0)[:3], P1.coefficients(u1)[:3]
    assert np.abs(q1 - Q @ q0).max() <= _TOL * np.abs(q0).max()


def test_bonded_pair_in_full_stick_is_the_linear_bonded_structure():
    model = with_contact_pairs(_mass(), [[0, 1, 2]], [0, 0, 1], mu=100.0, preload=_N0, normal="bonded",
                               normal_stiffness=_KN, tangential_stiffness=_KT).with_damping(modal_ratio=0.02)
    assert model.contacts == () and pair_dofs(model).tolist() == [[3, 4]]
    P, u, x, omega = _solve(model, _F)
    assert P._record(x, omega, 1.0)["slip_fraction"] == 0.0
    # bonded: every interface spring on the mass, damping of the DOFs with mass
    Kb = _K + np.diag([_KT, _KT, _KN])
    C = model.damping.toarray()[:3, :3]
    q_lin = np.linalg.solve(Kb - omega**2 * _M + 1j * omega * C, _F)
    q = P.coefficients(u)[:3]
    assert np.abs((q[:, 1] - 1j * q[:, 2]) - q_lin).max() <= _TOL * np.abs(q_lin).max()
    assert np.abs(q[:, 3:]).max() <= _TOL * np.abs(q_lin).max()


def test_two_node_pair_frames_and_dofs():
    base = Model.from_matrices(sp.identity(6, format="csr"),
                               sp.csr_matrix(np.eye(6) * 2.0 - np.eye(6, k=3) - np.eye(6, k=-3)), [], [], [],
                               amplitude_dof=0)
    model = with_contact_pairs(base, [[3, 4, 5]], [1.0, 1.0, 0.0], dofs_a=[[0, 1, 2]], gap=1e-3,
                               normal_stiffness=1e3, tangential_stiffness=5e2)
    R = pair_frames([1.0, 1.0, 0.0])[0]
    assert np.allclose(R @ R.T, np.eye(3), atol=1e-15) and np.isclose(np.linalg.det(R), 1.0)
    assert pair_dofs(model).tolist() == [[6, 7, 8]]
    assert model.contacts[0].dof == 6 and model.contacts[0].side == -1 and model.contacts[0].gap == 1e-3
    assert [fc.dof for fc in model.friction] == [7, 8]
    assert all(fc.normal_contact == 0 for fc in model.friction)
    # a rigid translation of both nodes leaves the interface unloaded
    K = model.K.toarray()
    t = np.array([0.3, -0.2, 0.5])
    assert np.abs(K[6:, :6] @ np.concatenate([t, t])).max() <= 1e-12 * 1e3
    # the recorded friction steps index the final DOFs (saved results get them back)
    steps = [s for s in model.description["transforms"] if s["name"] == "with_friction"]
    assert [s["args"]["dof"] for s in steps] == [7, 8]


def test_fe_pair_dofs_by_node_id():
    dofs = np.array([[10, 1], [10, 2], [10, 3], [20, 1], [20, 2], [20, 3]])
    fe = FEMatrices(sp.identity(6, format="csr"), sp.identity(6, format="csr"), None, dofs)
    assert fe_pair_dofs(fe, [20, 10]).tolist() == [[3, 4, 5], [0, 1, 2]]
    with pytest.raises(ValueError, match="node 30"):
        fe_pair_dofs(fe, [30])


@pytest.mark.parametrize("kwargs, match", [
    ({"dofs_b": [[0, 1]]}, "dofs_b"),
    ({"dofs_b": [[0, 1, 7]]}, "outside"),
    ({"dofs_b": [[0, 1, 2]], "dofs_a": [[2, 1, 0]]}, "more than one pair"),
    ({"normals": [0.0, 0.0, 0.0]}, "non-zero"),
    ({"tangents": [0.0, 0.0, 2.0]}, "parallel"),
    ({"gap": -1.0}, "gap"),
    ({"normal_stiffness": 0.0}, "normal_stiffness"),
    ({"normal": "glued"}, "normal"),
])
def test_bad_pair_input_is_named(kwargs, match):
    args = {"dofs_b": [[0, 1, 2]], "normals": [0.0, 0.0, 1.0], "normal_stiffness": 1.0,
            "tangential_stiffness": 1.0}
    args.update(kwargs)
    with pytest.raises((ValueError, TypeError), match=match):
        with_contact_pairs(_mass(), args.pop("dofs_b"), args.pop("normals"), **args)
