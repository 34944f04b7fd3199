"""The element protocol (mmshbm.elements): laws, JSON, validation, the model hook, the
registry's refusals, the AFT force and the analytic Jacobian of the element problems."""

import json

import numpy as np
import pytest
from finite_differences import assert_derivative, assert_jacobian
from roundoff import assert_roundoff_close, product_scale

import mmshbm
from mmshbm.elements import ELEMENTS, CompliantStop, CubicSpring, PolynomialSpring, from_json
from mmshbm.methods.mms.element_aft import ElementForces
from mmshbm.methods.mms.smooth import ElementBackboneProblem

ELEMENT_CASES = [CubicSpring(dof=0, stiffness=2.5), CubicSpring(dofs=(1, 0), stiffness=-0.7),
                 PolynomialSpring(dof=1, coefficients={2: 0.3, 3: 1.1, 5: -0.2}),
                 CompliantStop(dof=0, gap=0.2, stiffness=40.0, side=-1),
                 CompliantStop(dofs=(0, 1), gap=0.0, stiffness=3.0)]


def duffing(k3=1.0):
    return mmshbm.Model.from_matrices([[1.0]], [[1.0]], [], [], []).with_element(
        CubicSpring(dof=0, stiffness=k3))


@pytest.mark.parametrize("element", ELEMENT_CASES, ids=repr)
def test_law_derivative_and_potential(element):
    """φ' is the derivative of φ and φ the derivative of V (finite differences with their own
    error bound), at points away from a compliant stop's kink."""
    for delta in (-0.9, -0.35, 0.13, 0.6):
        phi, dphi = element.law(np.array([delta]))
        assert_derivative(lambda s, d=delta: element.law(np.array([d + s]))[0], dphi, 1e-3, name="phi'")
        assert_derivative(lambda s, d=delta: element.potential(np.array([d + s])), phi, 1e-3, name="V'")
    assert element.potential(np.zeros(1))[0] == 0.0


@pytest.mark.parametrize("element", ELEMENT_CASES, ids=repr)
def test_json_round_trip_and_registration(element):
    record = json.loads(json.dumps(element.to_json()))
    assert from_json(record) == element
    assert ELEMENTS[record["kind"]] is type(element)
    assert hash(from_json(record)) == hash(element)


def test_two_dof_element_acts_on_the_relative_displacement():
    """Between DOFs (i, j) the force is +φ(q_i − q_j) on i and −φ on j, its Jacobian w wᵀ φ'."""
    spring = CubicSpring(dofs=(2, 5), stiffness=3.0)
    q = np.array([[0.4, -0.1], [0.1, 0.3]])  # rows: DOF 2, DOF 5; two instants
    f, df = spring.sampled(q)
    delta = q[0] - q[1]
    np.testing.assert_allclose(f, [3.0 * delta**3, -3.0 * delta**3], rtol=4e-16, atol=0)
    np.testing.assert_allclose(df, [[9.0 * delta**2, -9.0 * delta**2], [-9.0 * delta**2, 9.0 * delta**2]],
                               rtol=4e-16, atol=0)


def test_compliant_stop_engages_behind_its_gap():
    stop = CompliantStop(dof=0, gap=0.5, stiffness=10.0, side=-1)
    phi, dphi = stop.law(np.array([-0.75, -0.5, 0.0, 0.75]))
    np.testing.assert_array_equal(phi, [-2.5, 0.0, 0.0, 0.0])  # pushes back toward +
    np.testing.assert_array_equal(dphi, [10.0, 0.0, 0.0, 0.0])


@pytest.mark.parametrize("make, message", [
    (lambda: CubicSpring(dof=0, stiffness=0.0), "nonzero"),
    (lambda: CubicSpring(stiffness=1.0), "exactly one of dof"),
    (lambda: CubicSpring(dof=0, stiffness=1.0, dofs=(0, 1)), "exactly one of dof"),
    (lambda: CubicSpring(dofs=(3, 3), stiffness=1.0), "two different DOFs"),
    (lambda: CubicSpring(dofs=(0, 1, 2), stiffness=1.0), "one DOF or a pair"),
    (lambda: PolynomialSpring(dof=0, coefficients={1: 2.0}), "integers >= 2"),
    (lambda: PolynomialSpring(dof=0, coefficients={3: 0.0}), "every coefficient"),
    (lambda: CompliantStop(dof=0, gap=-1.0, stiffness=1.0), "gap must be >= 0"),
    (lambda: CompliantStop(dof=0, gap=0.1, stiffness=0.0), "stiffness must be positive"),
    (lambda: CompliantStop(dof=0, gap=0.1, stiffness=1.0, side=2), "side must be"),
    (lambda: from_json({"kind": "no_such_element"}), "unknown element kind"),
])
def test_bad_elements_are_refused_by_name(make, message):
    with pytest.raises((ValueError, TypeError), match=message):
        make()


def test_elements_are_immutable():
    with pytest.raises(AttributeError, match="immutable"):
        CubicSpring(dof=0, stiffness=1.0).stiffness = 2.0


def test_with_element_hooks_into_the_model():
    base = mmshbm.Model.from_matrices(np.eye(2), [[2.0, -1.0], [-1.0, 2.0]], [], [], [])
    spring = CubicSpring(dofs=(0, 1), stiffness=1.0)
    model = base.with_element(spring)
    assert model.elements == (spring,) and base.elements == ()
    assert model.amplitude_dof == 0  # no contacts: the first element's DOF
    assert model.fingerprint() != base.fingerprint() and not model.same_as(base)
    recorded = model.description["transforms"][-1]
    assert recorded == {"name": "with_element", "args": {"element": spring.to_json()}}
    assert model.with_element(spring.to_json()).elements == (spring, spring)
    assert "cubic_spring on [0, 1]" in repr(model)
    with pytest.raises(ValueError, match="outside the model's DOFs 0..1"):
        base.with_element(CubicSpring(dof=2, stiffness=1.0))
    with pytest.raises(TypeError, match="must be an mmshbm.elements.Element"):
        base.with_element("cubic")


@pytest.mark.parametrize("method", ["penalty-reduced"])
def test_methods_without_elements_refuse_them_by_name(method):
    with pytest.raises(NotImplementedError, match=f"method '{method}' .*cubic_spring: use method .*'mmshbm'"):
        mmshbm.backbone(duffing(), harmonics=3, method=method, max_amplitude=1.0)


def test_phase_resonance_refuses_elements_by_name():
    model = duffing().with_damping(modal_ratio=0.01)
    with pytest.raises(NotImplementedError, match="'phase_resonance' .*cubic_spring"):
        mmshbm.backbone(model, harmonics=3, max_amplitude=1.0, method="phase_resonance")


def test_element_on_a_contact_dof_is_refused():
    model = mmshbm.default_beam().model(4)
    with pytest.raises(ValueError, match="contact DOF"):
        ElementBackboneProblem(model.with_element(CubicSpring(dof=model.contact_dof, stiffness=1.0)), 3)


def test_aft_of_a_cubic_is_exact():
    """cos³τ = (3 cos τ + cos 3τ)/4: the AFT force of a·cos τ on N = 4H+1 samples."""
    H, a = 3, 0.7
    forces = ElementForces([CubicSpring(dof=0, stiffness=2.0)], np.array([0]), H, 4 * H + 1, cosine_only=True)
    X = np.zeros((H + 1, 1))
    X[1, 0] = a
    F, _ = forces.evaluate(X, jacobian=False)
    np.testing.assert_allclose(F[:, 0], [0.0, 2.0 * 0.75 * a**3, 0.0, 2.0 * 0.25 * a**3], rtol=0, atol=1e-15)


def test_backbone_jacobian_matches_finite_differences():
    """The analytic Jacobian of the element backbone problem (condensation + AFT) on a
    cantilever with a cubic spring between a DOF with mass and the massless tip, and a
    compliant stop on another DOF with mass (away from its kink)."""
    base = mmshbm.default_beam().model(4)
    model = (mmshbm.Model.from_matrices(base.M, base.K, [], [], [])
             .with_element(CubicSpring(dofs=(4, base.contact_dof), stiffness=3e9))
             .with_element(CompliantStop(dof=2, gap=1e-4, stiffness=1e6)))
    problem = ElementBackboneProblem(model, harmonics=3)
    a = np.zeros((4, problem.n_s))
    a[1] = 1.5e-3 * problem.mode_shape_s
    a[3] = 2e-5 * problem.mode_shape_s
    u = problem.pack(a, 1.1 * problem.omega_ref)
    R, J = problem.residual_and_jacobian(u)
    np.testing.assert_array_equal(R, problem.residual(u))
    assert_jacobian(problem.residual, u, J, 1e-6 * np.abs(u).max())


def test_registry_states_the_elements_of_every_method():
    from mmshbm.methods.frequency_response import FORCED_METHODS
    from mmshbm.methods.registry import FORCED_METHOD_ELEMENTS, METHOD_ELEMENTS, METHODS

    assert set(METHOD_ELEMENTS) == set(METHODS) and set(FORCED_METHOD_ELEMENTS) == set(FORCED_METHODS)
    assert set(METHOD_ELEMENTS["mmshbm"]) == set(ELEMENTS)


@pytest.mark.parametrize("method", ["penalty", "shooting"])
def test_forced_methods_without_elements_refuse_them_by_name(method):
    model = duffing().with_damping(modal_ratio=0.05)
    refusal = f"method '{method}' \\(frequency response\\).*cubic_spring"
    with pytest.raises(NotImplementedError, match=refusal):
        mmshbm.frequency_response(model, [0.1], (0.1, 0.3), harmonics=3, method=method)


def test_forced_elements_beside_stops_are_refused():
    from mmshbm.methods.frequency_response import make_forced_problem

    beam = mmshbm.default_beam().model(4).with_damping(modal_ratio=0.01)
    model = beam.with_element(CubicSpring(dof=2, stiffness=1e9))
    force = np.zeros(model.n_dof)
    force[2] = 1.0
    with pytest.raises(NotImplementedError, match="no stops"):
        make_forced_problem(model, force)


def test_pole_signs_are_the_sign_of_det_S_oo_dense_and_sparse():
    """sgn det S_oo,k of the condensation onto the beam's tip deflection, below and above
    the first eigenfrequency of the beam with its tip held (where D_1 has a pole), from the
    dense LU and from the sparse one, against numpy's slogdet."""
    from mmshbm.methods.mms import set_condense

    base = mmshbm.default_beam().model(8)
    model = mmshbm.Model.from_matrices(base.M, base.K, [], [], [])
    held = set_condense.SetCondensation(model, [base.contact_dof])
    K, M = model.K.toarray()[np.ix_(held.o, held.o)], model.M.toarray()[np.ix_(held.o, held.o)]
    pole = np.sqrt(np.linalg.eigvals(np.linalg.solve(M[:14, :14], K[:14, :14] - K[:14, 14:] @ np.linalg.solve(
        K[14:, 14:], K[14:, :14]))).real.min())
    for dense in (True, False):
        cond = set_condense.SetCondensation(model, [base.contact_dof])
        cond.dense = dense
        if not dense:
            cond._blocks = {name: (ss, so, set_condense.sp.csc_matrix(oo)) for name, (ss, so, oo) in
                            cond._blocks.items()}
        for omega in (0.97 * pole, 1.03 * pole):
            cond.dynamic_stiffness(omega, 1, derivative=False)
            expected = np.linalg.slogdet(K - omega**2 * M)[0]
            assert cond.pole_signs[1] == expected and cond.pole_signs[0] == 1.0, (dense, omega)


def test_cubic_spring_at_the_beam_tip_matches_a_fine_time_integration():
    """The default beam (8 elements) with a cubic spring at its massless tip (k₃ = k_tip/L²,
    L = 1 mm: the frequency rises by 60 % at 1.5 mm), H = 15, against DOP853 on the full
    linear model plus the cubic force: the DOFs with mass integrated, the massless tip
    solved at each instant (its rotation linearly, its deflection from the monotone cubic
    k₃ x³ + k x + b = 0 in closed form), started on the harmonic-balance orbit's turning
    point and followed over one period. Measured: 1.3e-11 of the amplitude at 0.58 mm,
    2.6e-9 at 1.5 mm (the H = 15 truncation; the integration's own error at rtol = 1e-9 is
    below it); asserted <= 1e-7."""
    from scipy.integrate import solve_ivp

    from mmshbm.methods.mms.set_condense import SetCondensation

    beam = mmshbm.default_beam().model(8)
    base = mmshbm.Model.from_matrices(beam.M, beam.K, [], [], [])
    tip, L = beam.contact_dof, 1e-3
    k_tip = SetCondensation(base, [tip]).dynamic_stiffness(0.0, 0, derivative=False)[0][0, 0, 0]
    k3 = k_tip / L**2
    model = base.with_element(CubicSpring(dof=tip, stiffness=k3))
    H = 15
    branch = mmshbm.backbone(model, harmonics=H, max_amplitude=1.5 * L)
    assert str(branch.status).startswith("bound") and branch.frequency[-1] > 1.5 * branch.frequency[0]

    l, c = model.l, model.c
    K, M = model.K.toarray(), model.M.toarray()
    K_ll, K_lc, K_cc = K[np.ix_(l, l)], K[np.ix_(l, c)], K[np.ix_(c, c)]
    M_inv = np.linalg.inv(M[np.ix_(l, l)])
    i, j = list(c).index(tip), [n for n in range(len(c)) if c[n] != tip]
    K_jj = K_cc[np.ix_(j, j)]
    k_eff = K_cc[i, i] - K_cc[i, j] @ np.linalg.solve(K_jj, K_cc[j, i])
    B = K_lc.T[i] - K_cc[i, j] @ np.linalg.solve(K_jj, K_lc.T[j])

    def massless(q_l):
        p, q = k_eff / k3, (B @ q_l) / k3  # x³ + p x + q = 0, p > 0: its one real root
        x = -2 * np.sqrt(p / 3) * np.sinh(np.arcsinh(1.5 * q / p * np.sqrt(3 / p)) / 3)
        q_c = np.empty(len(c))
        q_c[i] = x
        q_c[j] = -np.linalg.solve(K_jj, K_lc.T[j] @ q_l + K_cc[j, i] * x)
        return q_c

    n_l = len(l)

    def rhs(t, y):
        q_l = y[:n_l]
        return np.concatenate([y[n_l:], M_inv @ (-K_ll @ q_l - K_lc @ massless(q_l))])

    problem = branch.solver
    k = np.arange(1, H + 1)
    for point in (len(branch) // 2, len(branch) - 1):
        Q = problem.coefficients(branch.states[point])
        omega = 2 * np.pi * branch.frequency[point]
        period = 2 * np.pi / omega
        start = np.concatenate([Q[l, 0] + Q[l][:, 1::2].sum(axis=1), np.zeros(n_l)])
        sol = solve_ivp(rhs, (0, period), start, method="DOP853", rtol=1e-9, atol=1e-12, dense_output=True)
        t = np.linspace(0, period, 201)
        q_hb = Q[l, 0][:, None] + Q[l][:, 1::2] @ np.cos(np.outer(k, omega * t))
        assert np.abs(sol.sol(t)[:n_l] - q_hb).max() <= 1e-7 * np.abs(q_hb).max(), point
        # the massless tip of the harmonic-balance orbit is the instant's static solution
        x_tip = Q[tip, 0] + Q[tip, 1::2] @ np.cos(np.outer(k, omega * t))
        x_static = np.array([massless(q)[i] for q in q_hb.T])
        assert np.abs(x_tip - x_static).max() <= 1e-7 * np.abs(x_tip).max(), point


def cubic_beam(n_elements=8, L=1e-3):
    """The default beam with a cubic spring k_tip/L² at its massless tip, no stop."""
    from mmshbm.methods.mms.set_condense import SetCondensation

    beam = mmshbm.default_beam().model(n_elements)
    base = mmshbm.Model.from_matrices(beam.M, beam.K, [], [], [])
    k_tip = SetCondensation(base, [beam.contact_dof]).dynamic_stiffness(0.0, 0, derivative=False)[0][0, 0, 0]
    return base.with_element(CubicSpring(dof=beam.contact_dof, stiffness=k_tip / L**2))


def test_full_dof_harmonic_balance_baseline_agrees_with_the_condensed_one():
    """method="penalty" on a model with elements is classical HBM on all 16 DOFs, nothing
    condensed: the MMS-HBM element branch's points, recovered on every DOF, satisfy its
    equations to round-off (scaled residual <= 1e-10; measured <= 3e-13), and both branches
    end at the amplitude bound on the same frequency (1e-9; measured 4e-11)."""
    model = cubic_beam()
    condensed = mmshbm.backbone(model, harmonics=9, max_amplitude=1.5e-3)
    full = mmshbm.backbone(model, harmonics=9, max_amplitude=1.5e-3, method="penalty")
    assert full.method == "penalty" and full.solver.n_unknowns == 10 * model.n_dof + 1
    problem = full.solver
    for i, u in enumerate(condensed.states):
        Q = condensed.solver.coefficients(u)
        cosine = Q[:, [0, *range(1, Q.shape[1], 2)]].T
        R = problem.residual(problem.pack(cosine, 2 * np.pi * condensed.frequency[i]))
        assert np.abs(R).max() <= 1e-10, i
    assert full.amplitude[-1] == pytest.approx(condensed.amplitude[-1], rel=1e-9)
    assert full.frequency[-1] == pytest.approx(condensed.frequency[-1], rel=1e-9)


def test_full_dof_baseline_jacobian_matches_finite_differences():
    from mmshbm.methods.penalty.elements import ElementHBMProblem

    model = cubic_beam(4).with_element(CompliantStop(dof=2, gap=1e-4, stiffness=1e6))
    problem = ElementHBMProblem(model, harmonics=3)
    Q = np.zeros((4, model.n_dof))
    Q[1] = 1.5e-3 * problem.mode_shape
    Q[3] = 2e-5 * problem.mode_shape
    u = problem.pack(Q, 1.1 * problem.omega_ref)
    R, J = problem.residual_and_jacobian(u)
    assert_jacobian(problem.residual, u, J.toarray(), 1e-5 * np.abs(u).max())
    with pytest.raises(NotImplementedError, match="without stops"):
        ElementHBMProblem(mmshbm.default_beam().model(4).with_element(CubicSpring(dof=2, stiffness=1.0)))


def test_shooting_baseline_meets_the_cubic_beam_backbone():
    """Shooting on a cubic beam (4 elements, spring at the massless tip): at the amplitude
    bound its frequency converges as N⁻² (1.06e-5 below MMS-HBM's at N = 512, 4.0 times less
    than at 256), and the Richardson extrapolation meets MMS-HBM at H = 15 to 1e-7
    (measured 1.8e-8: the N⁻⁴ remainder; from N = 1024, 2048 it is 8e-11)."""
    model = cubic_beam(4)
    reference = mmshbm.backbone(model, harmonics=15, max_amplitude=1.5e-3).frequency[-1]
    f = {N: mmshbm.backbone(model, method="shooting", max_amplitude=1.5e-3, steps_per_period=N).frequency[-1]
         for N in (256, 512)}
    assert (f[256] / reference - 1) / (f[512] / reference - 1) == pytest.approx(4.0, rel=0.02)
    assert (4 * f[512] - f[256]) / 3 == pytest.approx(reference, rel=1e-7)


def test_shooting_baseline_jacobian_matches_finite_differences():
    from mmshbm.methods.shooting.elements import ElementShootingProblem

    problem = ElementShootingProblem(cubic_beam(4), steps_per_period=64)
    u = problem.linear_mode_point(1e-3)
    u[-1] *= 1.2
    R, J = problem.residual_and_jacobian(u)
    assert_jacobian(problem.residual, u, J, 1e-5 * np.abs(u).max())
    with pytest.raises(ValueError, match="must be even"):
        ElementShootingProblem(cubic_beam(4), steps_per_period=65)


def test_damped_nonlinear_mode_of_the_cubic_beam():
    """EPMC on the cubic beam with 1 % modal damping of every mode: the damping ratio of the
    nonlinear mode starts at the linear mode's 0.01 (at 1 % of the bound the cubic force is
    1e-4 of the linear one: rel 1e-3) and the frequency rises as the conservative backbone's
    (within 1e-3 at the bound: light damping shifts a mode by O(ζ²)); the Jacobian is the
    finite differences' ."""
    from mmshbm.methods.mms.smooth_epmc import ElementEPMCProblem

    model = cubic_beam(4).with_damping(modal_ratio=0.01)
    b = mmshbm.backbone(model, harmonics=7, max_amplitude=1.5e-3)
    conservative = mmshbm.backbone(cubic_beam(4), harmonics=7, max_amplitude=1.5e-3)
    assert b.method == "epmc" and str(b.status).startswith("bound")
    assert b.damping_ratio[0] == pytest.approx(0.01, rel=1e-3)
    assert b.frequency[-1] == pytest.approx(conservative.frequency[-1], rel=1e-3)
    problem = b.solver
    assert isinstance(problem, ElementEPMCProblem)
    u = b.states[len(b) // 2]
    R, J = problem.residual_and_jacobian(u)
    assert_jacobian(problem.residual, u, J, 1e-5 * np.abs(u).max())


def test_element_problems_satisfy_the_continuation_protocol():
    """Every element problem (the backbones of mmshbm, penalty, shooting and EPMC, the
    forced response of mmshbm) is a ContinuationProblemBase with every capability declared,
    its start of the right shape, and R of residual() that of residual_and_jacobian()."""
    from mmshbm.core import problem as protocol
    from mmshbm.methods.frequency_response import make_forced_problem
    from mmshbm.methods.registry import make_problem

    capabilities = (protocol.StepControl, protocol.PinnedSolves, protocol.FamilyEvents,
                    protocol.BranchRecords)
    beam = cubic_beam(4)
    damped = beam.with_damping(modal_ratio=0.01)
    force = np.zeros(beam.n_dof)
    force[beam.l[-2]] = 1.0
    problems = [("backbone", make_problem(beam, m, harmonics=3)) for m in ("mmshbm", "penalty")]
    problems += [("backbone", make_problem(beam, "shooting", steps_per_period=32)),
                 ("backbone", make_problem(damped, "epmc", harmonics=3)),
                 ("forced", make_forced_problem(damped, force, "mmshbm", 3))]
    for kind, p in problems:
        start = protocol.AmplitudeStart if kind == "backbone" else protocol.FrequencyStart
        for proto in (protocol.ContinuationProblem, *capabilities, start):
            assert isinstance(p, proto), (type(p).__name__, proto.__name__)
        u = p.linear_mode_point(1e-4) if kind == "backbone" else p.linear_response_point(40.0)
        R, J = p.residual_and_jacobian(u)
        assert u.shape == (p.n_unknowns,) and np.shape(J) == (p.n_unknowns - 1, p.n_unknowns)
        J = J.toarray() if hasattr(J, "toarray") else np.asarray(J)
        terms = product_scale(J, u) + np.abs(R)  # residual() and the Jacobian's pass: two paths
        assert_roundoff_close(p.residual(u), R, terms + terms.max(), terms=p.n_unknowns, err_msg=kind)
    assert len({type(p).__name__ for _, p in problems}) == 5


def test_elements_survive_the_model_transforms_and_files(tmp_path):
    """A model's elements carry over through with_gap, with_damping, with_contact_layer
    (which keeps the DOF numbers) and a save_npz / from_npz round trip (the file keeps the
    recorded transforms)."""
    spring = CubicSpring(dof=2, stiffness=1e9)
    beam = mmshbm.default_beam().model(4)
    model = mmshbm.Model.from_matrices(beam.M, beam.K, 4, 1e-3).with_element(spring)  # the stop has mass
    assert model.with_gap(2e-3).elements == (spring,)
    assert model.with_damping(modal_ratio=0.01).elements == (spring,)
    layered = model.with_contact_layer()
    assert layered.elements == (spring,) and layered.n_dof == model.n_dof + 1
    path = tmp_path / "model.npz"
    model.save_npz(path)
    loaded = mmshbm.Model.from_npz(path)
    assert loaded.elements == (spring,) and loaded.fingerprint() == model.fingerprint()


def test_a_saved_branch_of_an_element_model_rebuilds_its_solver(tmp_path):
    """A branch whose file keeps the model's matrices (a user model) gets its elements back
    on load, so that its solver rebuilds: a point solved again on the loaded branch is the
    stored one to the Newton tolerance."""
    model = duffing()
    branch = mmshbm.backbone(model, harmonics=3, max_amplitude=1.0)
    path = branch.save(tmp_path / "duffing.npz")
    loaded = mmshbm.Branch.load(path)
    assert loaded.model.elements == model.elements
    amplitude = float(branch.amplitude[len(branch) // 2])
    np.testing.assert_allclose(loaded.frequency_at(amplitude), branch.frequency_at(amplitude), rtol=1e-9)
