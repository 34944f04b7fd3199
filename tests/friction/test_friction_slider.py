"""Friction at a DOF with mass: ``Model.with_friction(..., tangential_stiffness=k_t)`` joins a
massless slider by k_t; the contact layer of a friction-only model says where to go; the
Jenkins baseline takes the model's own tangential spring by default and says what it adds
where there is none."""

import warnings

import numpy as np
import pytest

import mmshbm
from mmshbm.methods.mms.friction_forced import FrictionForcedProblem
from mmshbm.methods.penalty.jenkins import DEFAULT_TANGENTIAL_FACTOR, JenkinsForcedProblem

M_, K1, K2, C_, F_ = 1.0, 1.0, 2.0, 0.05, 0.1


def one_mass():
    """A mass on a spring k1 to ground, nothing else (1 DOF, with mass)."""
    return mmshbm.Model.from_matrices(np.diag([M_]), np.array([[K1]]), [], [], [], damping=np.diag([C_]),
                                      amplitude_dof=0)


def hand_built_jenkins(normal_load):
    """The same Jenkins oscillator written by hand: the slider as DOF 1."""
    M = np.diag([M_, 0.0])
    K = np.array([[K1 + K2, -K2], [-K2, K2]])
    base = mmshbm.Model.from_matrices(M, K, [], [], [], damping=np.diag([C_, 0.0]), amplitude_dof=0)
    return base.with_friction(1, 0.5, normal_load=normal_load)


def test_the_slider_is_the_hand_built_jenkins_element():
    model = one_mass().with_friction(0, 0.5, normal_load=0.2, tangential_stiffness=K2)
    ref = hand_built_jenkins(0.2)
    assert model.n_dof == 2 and model.friction[0].dof == 1 and model.c.tolist() == [1]
    # the same matrices entry for entry: the slider adds k_t (e_0 − e_1)(e_0 − e_1)ᵀ
    for a, b in ((model.K, ref.K), (model.M, ref.M), (model.damping, ref.damping)):
        assert np.array_equal(a.toarray(), b.toarray())
    assert model.amplitude_dof == 0
    step = model.description["transforms"][-1]
    assert step["args"]["tangential_stiffness"] == K2 and step["slider"] == 1
    # and the same orbit (one computation repeated on equal inputs)
    f = 0.2
    p, q = (FrictionForcedProblem(m, [F_, 0.0], 7) for m in (model, ref))
    up, uq = p.start_point(f), q.start_point(f)
    np.testing.assert_allclose(p.coefficients(up), q.coefficients(uq), rtol=0, atol=1e-12 * F_ / K1)


def test_a_slider_model_is_saved_and_loaded(tmp_path):
    model = one_mass().with_friction(0, 0.5, normal_load=0.2, tangential_stiffness=K2)
    r = mmshbm.frequency_response(model, [F_, 0.0], (0.18, 0.2), harmonics=5)
    path = tmp_path / "r.npz"
    r.save(path)
    back = mmshbm.load(path)
    assert back.model.n_dof == 2 and back.model.friction == model.friction


def test_rigid_friction_at_a_dof_with_mass_is_refused_by_name():
    with pytest.raises(ValueError, match=r"dof 0 carries mass.*tangential_stiffness=k_t"):
        one_mass().with_friction(0, 0.5, normal_load=0.2)
    for bad in (0.0, -1.0, np.inf):
        with pytest.raises(ValueError, match="tangential_stiffness"):
            one_mass().with_friction(0, 0.5, normal_load=0.2, tangential_stiffness=bad)
    with pytest.raises(ValueError, match=r"dof must be in \[0, 0\]"):
        one_mass().with_friction(3, 0.5, normal_load=0.2, tangential_stiffness=K2)


def test_a_contact_layer_on_a_friction_only_model_points_to_with_friction():
    with pytest.raises(ValueError, match=r"no unilateral contact.*with_friction\(dof, mu, normal_load=N, "
                                         r"tangential_stiffness=k_t\)"):
        hand_built_jenkins(0.2).with_contact_layer(1e3)


def test_the_penalty_baseline_takes_the_physical_spring_by_default():
    model = hand_built_jenkins(0.2)
    with warnings.catch_warnings():
        warnings.simplefilter("error", mmshbm.ModelWarning)
        p = JenkinsForcedProblem(model, [F_, 0.0], 5)
    assert p.tangential_origin == "physical"
    assert p.tangential_stiffness.tolist() == [K2]
    q = JenkinsForcedProblem(model, [F_, 0.0], 5, tangential_stiffness="physical")
    u = q.start_point(0.2)
    # the same problem: the same residual at the same point (one computation, repeated)
    assert np.array_equal(p.residual(u), q.residual(u))


def test_the_penalty_baseline_says_what_it_adds_without_a_physical_spring():
    model = mmshbm.tip_damper_model(normal_load=1.0)
    says = r"adds a tangential penalty spring.*tangential_stiffness=k_t"
    with pytest.warns(mmshbm.ModelWarning, match=says):
        p = JenkinsForcedProblem(model, mmshbm.tip_damper_force(model), 3)
    assert p.tangential_origin == "default penalty"
    assert p.tangential_stiffness[0] == pytest.approx(DEFAULT_TANGENTIAL_FACTOR * p._rho[0], rel=1e-15)


def test_nlvib_friction_beam_with_a_jenkins_element_is_followed_to_its_end():
    """NLvib's example-08 beam (2 m, 0.1 × 0.3 m, 8 elements; 0.2 N at the tip, stiffness-
    proportional damping, 1 % at the stuck first mode) with Coulomb (μN = 1.5 N) at node 4
    behind k_t = 1e7 N/m, H = 13. Its scaled residual bottoms out near 1e-12 (a stiff
    model's round-off): a corrector that took that floor for a stalled corner refused every
    step and ran out of steps (3001 points, max_steps); one that searched along noise ran
    out of iterations. Measured: 171 points, 3.05 Newton iterations per point."""
    import scipy.linalg as la

    from mmshbm.fe.euler_bernoulli import cantilever

    M, K, dofs = cantilever(2.0, 0.3, 0.1, 185e9, 7830.0, 8)
    node4, tip = int(dofs[3, 0]), int(dofs[-1, 0])
    Md, Kd = M.toarray(), K.toarray()
    keep = [i for i in range(len(Md)) if i != node4]
    w_free = np.sqrt(la.eigh(Kd, Md, eigvals_only=True)[0])
    w_stuck = np.sqrt(la.eigh(Kd[np.ix_(keep, keep)], Md[np.ix_(keep, keep)], eigvals_only=True)[0])
    base = mmshbm.Model.from_matrices(M, K, [], [], [], damping=(2e-2 / w_stuck) * K, amplitude_dof=tip)
    model = base.with_friction(node4, 1.0, normal_load=1.5, tangential_stiffness=1e7)
    force = np.zeros(model.n_dof)
    force[tip] = 0.2
    band = (0.9 * w_free / (2 * np.pi), 1.5 * w_stuck / (2 * np.pi))
    r = mmshbm.frequency_response(model, force, band, harmonics=13)
    assert r.status == "bound:frequency"
    assert len(r) < 600
    assert r.newton_iterations.mean() <= 6
