"""MMS-HBM forced responses with Coulomb friction against ground truth: the linear closed
forms in the stuck and free-slip limits, the exact periodic orbit (event-driven,
mmshbm.methods.exact.friction, itself checked against solve_ivp), the energy balance
per period, and central differences of the Jacobian."""

import numpy as np
import pytest

import mmshbm
from mmshbm.methods.exact.friction import friction_orbit
from mmshbm.methods.mms.friction_forced import FrictionForcedProblem

M_, K1, K2, C_, F_ = 1.0, 1.0, 2.0, 0.05, 0.1
EPS = np.finfo(float).eps


def jenkins(normal_load, mu=0.5, c=C_):
    """Mass m on spring k1 to ground and spring k2 to a massless node with Coulomb friction."""
    M = np.diag([M_, 0.0])
    K = np.array([[K1 + K2, -K2], [-K2, K2]])
    damping = np.diag([c, 0.0]) if c else None
    base = mmshbm.Model.from_matrices(M, K, [], [], [], damping=damping, amplitude_dof=0)
    return base.with_friction(1, mu, normal_load=normal_load)


def solve(model, f, H, law="play"):
    p = FrictionForcedProblem(model, [F_, 0.0], H, law=law)
    u, ok = p.solve_at(f, p.start_point(f))
    assert ok
    return p, u


@pytest.mark.parametrize("law", ["play", "velocity"])
@pytest.mark.parametrize("f", [0.1, 0.2757, 0.35])
def test_stuck_and_free_slip_limits_equal_the_linear_closed_forms(law, f):
    omega = 2 * np.pi * f
    for N, k in ((1e3, K1 + K2), (0.0, K1)):
        p, u = solve(jenkins(N), f, 5, law)
        X = F_ / (k - M_ * omega**2 + 1j * C_ * omega)
        x = p.coefficients(u)[0]
        expect = np.zeros(11)
        expect[1], expect[2] = X.real, -X.imag
        np.testing.assert_allclose(x, expect, rtol=0, atol=1e-10 * abs(X))
        assert np.hypot(x[1], x[2]) == pytest.approx(abs(X), rel=1e-10)  # max |x| of a harmonic
    # the stuck orbit sits in the symmetric position: node at rest at 0, mean force zero
    p, u = solve(jenkins(1e3), f, 5, law)
    assert np.abs(p.coefficients(u)[1]).max() <= 1e-12 * abs(X)
    assert p.monitor(u)["slip_fraction"] == 0.0


def _energy(p, u):
    """(input, viscous, friction) work per period (J) of an HBM point, by Parseval."""
    x = p.coefficients(u)[0]
    _, omega = p.unpack(u)
    H = p.H
    k = np.arange(1, H + 1)
    a, b = x[1::2], x[2::2]
    inp = np.pi * F_ * b[0]  # ∫ F cos τ · x′ dτ
    visc = C_ * omega * np.pi * np.sum(k**2 * (a**2 + b**2))
    return inp, visc, p.monitor(u)["friction_dissipation"]


@pytest.mark.parametrize("law", ["play", "velocity"])
def test_energy_balance_at_every_converged_point(law):
    model = jenkins(0.2)
    fr = mmshbm.frequency_response(model, [F_, 0.0], (0.12, 0.32), harmonics=9, law=law)
    assert fr.status.startswith("bound")
    slipping = 0
    for u in fr.states:
        inp, visc, fric = _energy(fr.solver, u)
        assert abs(inp - visc - fric) <= 1e-10 * inp
        slipping += fric > 1e-6 * inp
    assert slipping > 5


def test_friction_alone_damps_the_response():
    """No viscous damping: the resonance is bounded by friction, input = friction work."""
    model = jenkins(0.2, c=0.0)
    fr = mmshbm.frequency_response(model, [F_, 0.0], (0.12, 0.32), harmonics=9)
    assert fr.status.startswith("bound") and np.all(np.isfinite(fr.amplitude))
    for u in fr.states[::5]:
        fric = fr.solver.monitor(u)["friction_dissipation"]
        x = fr.solver.coefficients(u)[0]
        assert abs(np.pi * F_ * x[2] - fric) <= 1e-10 * max(abs(fric), 1e-30)


@pytest.mark.parametrize("f", [0.2, 0.25])
def test_mmshbm_converges_to_the_exact_periodic_orbit(f):
    """Largest |x| against the exact orbit: the play form converges ~H⁻³ (measured 7e-5,
    7e-6, 5e-7 at H = 7, 15, 31 at 0.2 Hz); the velocity form slowly (~1e-2 at H = 31)."""
    model = jenkins(0.2)
    orbit = friction_orbit(model, [F_, 0.0], f)
    assert orbit.converged and 0.3 < orbit.slip_fraction < 0.9
    A = orbit.amplitude(0)
    W = orbit.energy_balance()["friction"]
    err = {}
    for H in (7, 15, 31):
        p, u = solve(model, f, H)
        rec = p.monitor(u)
        err[H] = abs(rec["amplitude"] / A - 1)
        if H == 31:
            assert abs(rec["friction_dissipation"] / W - 1) < 1e-4
    assert err[31] < err[15] < err[7]
    assert err[15] < 1e-4 and err[31] < 1e-5, err
    # the velocity form: 1.3e-2 and 2.9e-3 at H = 31
    p, u = solve(model, f, 31, law="velocity")
    assert abs(p.monitor(u)["amplitude"] / A - 1) < 0.05


@pytest.mark.parametrize("law", ["play", "velocity"])
def test_jacobian_against_central_differences(law):
    """The scaled Jacobian (n_x, n_x + 1) at a slipping point; tolerance: Richardson estimate
    of the truncation error plus 64 ε max|R| / h."""
    p, u0 = solve(jenkins(0.2), 0.21, 4, law)
    u0 = u0 * (1 + 1e-3 * np.sin(np.arange(len(u0))))  # off the solution: R ≠ 0
    R0, J = p.evaluate(u0)
    n = len(u0)

    def central(h):
        D = np.empty((len(R0), n))
        for j in range(n):
            e = np.zeros(n)
            e[j] = h
            D[:, j] = (p.evaluate(u0 + e, jacobian=False) - p.evaluate(u0 - e, jacobian=False)) / (2 * h)
        return D

    h = 1e-6
    D1, D2 = central(h), central(2 * h)
    trunc = np.abs(D2 - D1).max() / 3
    roundoff = 64 * EPS * (np.abs(R0).max() + np.abs(J).max() * np.abs(u0).max()) / h
    err = np.abs(D1 - J).max()
    assert err <= 2 * (trunc + roundoff), (err, trunc, roundoff)


def test_what_is_not_yet_done_says_so():
    M = np.diag([1.0, 0.0, 0.0])
    K = np.array([[3.0, -1, -1], [-1, 2, 0], [-1, 0, 2]])
    coupled = mmshbm.Model.from_matrices(M, K, 1, 1e-3, amplitude_dof=0).with_friction(
        2, 0.2, normal_contact=0)
    with pytest.raises(NotImplementedError, match="not yet solved by the Jenkins"):
        mmshbm.frequency_response(coupled, [1.0, 0, 0], (0.1, 0.2), method="penalty")
    with pytest.raises(ValueError, match="preload > 0"):  # the EPMC's stuck start needs μ·preload > 0
        mmshbm.backbone(coupled, max_amplitude=1e-3)
    with pytest.raises(NotImplementedError, match="one friction contact and no unilateral"):
        mmshbm.frequency_response(coupled, [1.0, 0, 0], (0.1, 0.2), method="shooting")
    with pytest.raises(NotImplementedError, match="play"):
        FrictionForcedProblem(jenkins(0.2), [F_, 0.0], 3, stability=True, law="velocity")
    with pytest.raises(ValueError, match="law must be"):
        FrictionForcedProblem(jenkins(0.2), [F_, 0.0], 3, law="penalty")


def test_a_response_with_friction_is_saved_and_loaded(tmp_path):
    model = jenkins(0.2)
    fr = mmshbm.frequency_response(model, [F_, 0.0], (0.15, 0.25), harmonics=5)
    path = fr.save(tmp_path / "jenkins.npz")
    back = mmshbm.FrequencyResponse.load(path)
    assert back.get_model().same_as(model) and back.get_model().friction == model.friction
    back.attach_solver()
    assert isinstance(back.solver, FrictionForcedProblem)
    np.testing.assert_allclose(back.solver.monitor(back.states[3])["amplitude"], fr.amplitude[3], rtol=1e-12)


def test_several_dofs_with_mass_converge_to_the_exact_orbit():
    """Two masses in a chain, the node on the second, friction alone (no viscous damping)."""
    M = np.diag([1.0, 0.5, 0.0])
    K = np.array([[3.0, -1.0, 0.0], [-1.0, 3.0, -2.0], [0.0, -2.0, 2.0]])
    model = mmshbm.Model.from_matrices(M, K, [], [], [], amplitude_dof=0)
    model = model.with_friction(2, 0.5, normal_load=0.1)
    force, f = [0.1, 0.0, 0.0], 0.19
    orbit = friction_orbit(model, force, f)
    assert orbit.converged and 0 < orbit.slip_fraction < 1
    A = orbit.amplitude(0)
    err = {}
    for H in (7, 31):
        p = FrictionForcedProblem(model, force, H)
        u, ok = p.solve_at(f, p.start_point(f))
        assert ok
        err[H] = abs(p.monitor(u)["amplitude"] / A - 1)
    assert err[31] < err[7] and err[31] < 1e-4, err


def test_the_continuation_follows_a_stuck_resonance():
    """Stuck, the node's coefficients (the condensed unknowns) vanish; harmonic 1 of the
    amplitude DOF is carried as unknowns so the arclength sees the peak. Largest sampled
    amplitude against the closed-form peak F/(k 2ζ√(1−ζ²)), k = k1 + k2: measured 2e-7."""
    fr = mmshbm.frequency_response(jenkins(1e3), [F_, 0.0], (0.1, 0.4), harmonics=5)
    k = K1 + K2
    zeta = C_ / (2 * np.sqrt(k * M_))
    peak = F_ / k / (2 * zeta * np.sqrt(1 - zeta**2))
    assert fr.amplitude.max() == pytest.approx(peak, rel=1e-4)
    assert np.all(fr.records["slip_fraction"] == 0.0)


@pytest.mark.slow  # ~10 s
def test_a_stiff_friction_node_on_the_beam_tip():
    """A damper on the default beam's massless tip (node stiffness with the masses held
    2.4e9 N/m, so s/ρ = 2e-10 m: the node sticks only at reversals): the globalised
    corrector follows the whole response (plain Newton cycled near 31 Hz), and the
    resonance amplitude drops below the free beam's."""
    beam = mmshbm.default_beam().model(21)
    tip = beam.contact_dof
    base = mmshbm.Model.from_matrices(beam.M, beam.K, [], [], [], amplitude_dof=tip - 2)
    base = base.with_damping(modal_ratio=0.01)
    force = np.zeros(beam.n_dof)
    force[tip - 2] = 1.0
    free = mmshbm.frequency_response(base.with_friction(tip, 0.5, normal_load=0.0), force, (30, 60),
                                     harmonics=7)
    damped = mmshbm.frequency_response(base.with_friction(tip, 0.5, normal_load=1.0), force, (30, 60),
                                       harmonics=7)
    assert free.status.startswith("bound") and damped.status.startswith("bound")
    assert damped.amplitude.max() < 0.5 * free.amplitude.max()
    assert np.all(damped.records["slip_fraction"] > 0.9)


@pytest.mark.slow  # ~10 s
def test_the_stiff_tip_damper_is_followed_past_the_bend_at_33_hz():
    """μN = 0.5 N, H = 15: ripples of the truncated free-node signal add and remove short
    stick arcs near 31-33.3 Hz, where the friction rows are weak (condition ~1e7). A point
    accepted on its residual alone (1e-10) lay 2.5e-5 (scaled) off the branch and every later
    corrector left the predictor cone: the response stopped at 33.3 Hz. The corrector now
    also asks for a small Newton step; the whole range is followed."""
    model = mmshbm.tip_damper_model(normal_load=1.0)
    r = mmshbm.frequency_response(model, mmshbm.tip_damper_force(model), (20, 60), harmonics=15)
    assert r.status.startswith("bound"), r.status
    assert 45 < r.frequency[np.argmax(r.amplitude)] < 47
