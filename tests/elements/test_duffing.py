"""The Duffing oscillator x'' + x + x³ = 0 (m = k = k₃ = 1) by MMS-HBM with a cubic spring
element, against its closed forms.

Single-harmonic balance: ω = √(1 + ¾A²). Exact: x(t) = A cn(ω t, m) with
ω = π√(1 + A²)/(2K(m)), m = A²/(2(1 + A²)), A = max|x| (here x(0): the cosine ansatz puts
the turning point at τ = 0).
"""

import numpy as np
import pytest
from scipy.special import ellipk

import mmshbm
from mmshbm.elements import CubicSpring


def duffing(k3=1.0):
    return mmshbm.Model.from_matrices([[1.0]], [[1.0]], [], [], []).with_element(
        CubicSpring(dof=0, stiffness=k3))


def exact_frequency(A):
    m = A**2 / (2 * (1 + A**2))
    return np.pi * np.sqrt(1 + A**2) / (2 * ellipk(m))


@pytest.fixture(scope="module")
def branches():
    return {H: mmshbm.backbone(duffing(), harmonics=H, max_amplitude=2.0) for H in (1, 15)}


def test_single_harmonic_backbone_is_the_closed_form(branches):
    """At H = 1 the balance is a_1 = A, Ω² = 1 + ¾A² exactly: the branch meets it to
    round-off of the Newton solution (tolerance 1e-9 of Ω, well above 1e-12 noise)."""
    b = branches[1]
    assert str(b.status).startswith("bound") and b.amplitude.max() >= 2.0 - 1e-9
    omega = 2 * np.pi * b.frequency
    np.testing.assert_allclose(omega, np.sqrt(1 + 0.75 * b.amplitude**2), rtol=1e-9, atol=0)


def test_fifteen_harmonics_meet_the_exact_backbone(branches):
    """At H = 15 the truncation error of the cn series (nome q <= 0.04 at A = 2: the
    omitted harmonics are below q^8 ~ 1e-11) is far below 1e-8 of Ω."""
    b = branches[15]
    assert b.amplitude.max() >= 2.0 - 1e-9 and b.amplitude.min() < 0.05
    omega = 2 * np.pi * b.frequency
    np.testing.assert_allclose(omega, exact_frequency(b.amplitude), rtol=1e-8, atol=0)


def test_amplitude_is_the_displacement_maximum_not_the_fundamental(branches):
    """The branch's amplitude is max|x(τ)| = x(0) = Σ_k a_k, which at A = 2 differs from the
    fundamental a_1 by the higher harmonics (a few per cent): the exact formula takes the
    former."""
    b = branches[15]
    problem = b.solver
    a, _ = problem.unpack(b.states[-1])
    assert b.amplitude[-1] == pytest.approx(a[:, 0].sum(), rel=1e-12)
    assert a[1, 0] < 0.99 * a[:, 0].sum()


def test_energy_is_the_duffing_energy(branches):
    """The energy record at the turning point: ½A² + ¼A⁴ (m = k = k₃ = 1)."""
    b = branches[15]
    A = b.amplitude
    np.testing.assert_allclose(b.energy, 0.5 * A**2 + 0.25 * A**4, rtol=1e-12)


def test_softening_spring_bends_the_backbone_down():
    """k₃ = −0.1: Ω = √(1 − 0.075 A²) at H = 1 (no turning point before A = 1.5)."""
    b = mmshbm.backbone(duffing(-0.1), harmonics=1, max_amplitude=1.5)
    omega = 2 * np.pi * b.frequency
    np.testing.assert_allclose(omega, np.sqrt(1 - 0.075 * b.amplitude**2), rtol=1e-9, atol=0)
    assert omega[-1] < omega[0]


# ---------------------------------------------------------------------- forced Duffing
#: x'' + 2ζ x' + x + x³ = F cos Ωt
ZETA, FORCE = 0.1, 0.2


def duffing_rhs(omega):
    def rhs(t, y):
        return [y[1], -2 * ZETA * y[1] - y[0] - y[0] ** 3 + FORCE * np.cos(omega * t)]
    return rhs


@pytest.fixture(scope="module")
def forced():
    model = duffing().with_damping(modal_ratio=ZETA)
    return mmshbm.frequency_response(model, [FORCE], (0.5 / (2 * np.pi), 2.0 / (2 * np.pi)), harmonics=9,
                                     n_samples=64)


def test_forced_duffing_bends_over_through_two_folds(forced):
    kinds = [p.kind for p in forced.special_points]
    assert kinds.count("fold") == 2 and str(forced.status).startswith("bound")
    between = slice(*[p.index for p in forced.special_points if p.kind == "fold"])
    assert not forced.stable[between].any() and forced.stable[:3].all() and forced.stable[-3:].all()


def test_forced_duffing_matches_a_fine_time_integration(forced):
    """At a point below the resonance, at the peak and past the jump down, the steady state
    of a tight DOP853 integration (started on the harmonic-balance orbit, 40 periods: the
    Floquet multipliers there are <= 0.67, so a start off the true orbit by the truncation
    error decays below 1e-7 of it) is the harmonic-balance orbit to within 1e-8 of its
    amplitude: the H = 9 truncation (the 11th harmonic of this orbit is ~1e-10 of it)."""
    from scipy.integrate import solve_ivp

    problem = forced.solver
    H = problem.H
    k = np.arange(1, H + 1)
    peak = int(np.argmax(forced.amplitude))
    for i in (3, peak, len(forced) - 3):
        assert forced.stable[i]
        omega = 2 * np.pi * forced.frequency[i]
        Q = problem.coefficients(forced.states[i])[0]
        start = [Q[0] + Q[1::2].sum(), omega * (k * Q[2::2]).sum()]
        period = 2 * np.pi / omega
        sol = solve_ivp(duffing_rhs(omega), (0, 40 * period), start, method="DOP853", rtol=1e-12, atol=1e-13,
                        dense_output=True)
        t = 39 * period + np.linspace(0, period, 401)
        x_ode = sol.sol(t)[0]
        x_hb = Q[0] + np.cos(np.outer(omega * t, k)) @ Q[1::2] + np.sin(np.outer(omega * t, k)) @ Q[2::2]
        assert np.abs(x_ode - x_hb).max() <= 1e-8 * np.abs(x_hb).max(), (i, omega)
        # the amplitude record is the series' peak: 10⁵ samples of it get within ~1e-8
        tau = np.linspace(0, 2 * np.pi, 100_001)
        fine = Q[0] + np.cos(np.outer(tau, k)) @ Q[1::2] + np.sin(np.outer(tau, k)) @ Q[2::2]
        assert forced.amplitude[i] == pytest.approx(np.abs(fine).max(), rel=1e-8)


def test_forced_duffing_floquet_multipliers_match_the_variational_equation(forced):
    """The monodromy (classical RK4 on 4N steps) against DOP853 on the variational equation
    y'' + 2ζ y' + (1 + 3x²) y = 0 along the orbit at the peak (tolerance: the RK4 error
    (2π/256)⁴ ~ 4e-7)."""
    from scipy.integrate import solve_ivp

    problem = forced.solver
    i = int(np.argmax(forced.amplitude))
    omega = 2 * np.pi * forced.frequency[i]
    Q = problem.coefficients(forced.states[i])[0]
    k = np.arange(1, problem.H + 1)

    def rhs(t, y):
        x = Q[0] + np.cos(k * omega * t) @ Q[1::2] + np.sin(k * omega * t) @ Q[2::2]
        Phi = y.reshape(2, 2)
        A = np.array([[0.0, 1.0], [-(1 + 3 * x * x), -2 * ZETA]])
        return (A @ Phi).ravel()

    sol = solve_ivp(rhs, (0, 2 * np.pi / omega), np.eye(2).ravel(), method="DOP853", rtol=1e-12, atol=1e-13)
    mu_ref = np.linalg.eigvals(sol.y[:, -1].reshape(2, 2))
    mu = forced.records["floquet"][i] if "floquet" in forced.records else problem.floquet_multipliers(
        forced.states[i])
    np.testing.assert_allclose(np.sort_complex(mu), np.sort_complex(mu_ref), rtol=0, atol=1e-6)
    # Liouville: the product of the multipliers is exp(−2ζ T)
    assert np.prod(mu).real == pytest.approx(np.exp(-2 * ZETA * 2 * np.pi / omega), rel=1e-6)


# ---------------------------------------------------------------------- beside a stop
#: x'' + x + x³ + k_c (x − g)₊ = 0: the Duffing mass joined by a spring k_c to a massless
#: node that meets a rigid stop at g (the node follows the mass while it is open)
K_C, GAP = 1.0, 0.5


def stop_potential(x):
    return 0.5 * x * x + 0.25 * x**4 + 0.5 * K_C * max(x - GAP, 0.0) ** 2


def exact_frequency_with_stop(A):
    """Ω of the orbit of x'' + x + x³ + k_c (x − g)₊ = 0 whose excursion away from the stop
    is A (= max|x|): T = 2∫ dx/√(2(E − V)) between the turning points, by quadrature in
    x = c − r cos θ (smooth integrand; the kink at g a break point), relative error ~1e-13."""
    from scipy.integrate import quad
    from scipy.optimize import brentq

    energy = stop_potential(-A)
    top = brentq(lambda x: stop_potential(x) - energy, 0.0, A, xtol=1e-15, rtol=1e-15)
    c, r = 0.5 * (top - A), 0.5 * (top + A)

    def integrand(theta):
        x = c - r * np.cos(theta)
        return r * np.sin(theta) / np.sqrt(max(2 * (energy - stop_potential(x)), 1e-300))

    breaks = [np.arccos((c - GAP) / r)] if top > GAP else None
    period = 2 * quad(integrand, 0, np.pi, points=breaks, epsabs=0, epsrel=1e-13, limit=400)[0]
    return 2 * np.pi / period


def duffing_beside_a_stop():
    M = np.diag([1.0, 0.0])
    K = np.array([[1.0 + K_C, -K_C], [-K_C, K_C]])
    return (mmshbm.Model.from_matrices(M, K, 1, GAP, 1).with_element(CubicSpring(dof=0, stiffness=1.0))
            .with_amplitude_dof(0))


def test_cubic_spring_beside_a_rigid_stop_converges_to_the_exact_backbone():
    """A cubic spring on the DOF with mass beside a rigid stop on the massless node, in one
    model: the stop's rows are MMS-HBM's proximal law, the spring's the AFT force. The kink
    of the contact makes the truncation error fall algebraically in H (measured ~H^-3:
    1.1e-4 at H = 5, 2.3e-5 at 10, 2.9e-7 at 40); the test asserts that order (the error
    at H = 40 below 1/16 of that at H = 10, i.e. at least second order) and the size at
    H = 40 (<= 1e-6)."""
    errors = {}
    for H in (10, 40):
        b = mmshbm.backbone(duffing_beside_a_stop(), harmonics=H, max_amplitude=2.0)
        assert str(b.status).startswith("bound") and b.contact_force_max[-1] > 0.5
        ref = np.array([exact_frequency_with_stop(A) for A in b.amplitude])
        errors[H] = np.abs(2 * np.pi * b.frequency / ref - 1).max()
    assert errors[40] <= errors[10] / 16 and errors[40] <= 1e-6, errors


def test_rigid_stop_on_a_massless_node_equals_a_compliant_stop():
    """The same system written with a CompliantStop(k_c, g) element on the mass (no massless
    node, AFT alone) meets the same exact backbone (1e-6 at H = 40: its sampled kink
    converges as the rigid stop's projection does)."""
    model = duffing().with_element(mmshbm.elements.CompliantStop(dof=0, gap=GAP, stiffness=K_C))
    b = mmshbm.backbone(model, harmonics=40, max_amplitude=2.0)
    ref = np.array([exact_frequency_with_stop(A) for A in b.amplitude])
    assert np.abs(2 * np.pi * b.frequency / ref - 1).max() <= 1e-6


def test_shooting_baseline_converges_to_the_exact_backbone():
    """Shooting (trapezoidal rule, half period) on the Duffing oscillator: the frequency
    error is the rule's (Ωh)²/12 at small amplitude (−5.02e-5 at N = 256), it falls as N⁻²,
    and the Richardson extrapolation of N = 256, 512 at A = 2 meets the exact backbone to
    1e-8 (measured 1.4e-9: the N⁻⁴ remainder)."""
    model = duffing()
    omega = {}
    for N in (256, 512):
        b = mmshbm.backbone(model, method="shooting", max_amplitude=2.0, steps_per_period=N)
        assert b.method == "shooting" and b.amplitude[-1] == pytest.approx(2.0, rel=1e-10)
        omega[N] = 2 * np.pi * b.frequency[-1]
        first = 2 * np.pi * b.frequency[0] / exact_frequency(b.amplitude[0]) - 1
        assert first == pytest.approx(-(2 * np.pi / N) ** 2 / 12, rel=1e-3)
    exact = exact_frequency(2.0)
    assert (omega[256] / exact - 1) / (omega[512] / exact - 1) == pytest.approx(4.0, rel=0.02)
    assert (4 * omega[512] - omega[256]) / 3 == pytest.approx(exact, rel=1e-8)


def test_damped_nonlinear_mode_of_the_duffing_oscillator():
    """EPMC (mmshbm.backbone on the damped model dispatches to it): with mass-proportional
    damping C = αM the term −ξM q' cancels it exactly, so ξ = α along the whole mode (to
    round-off) and Ω is the conservative backbone: the closed form at H = 1 (1e-9) and the
    exact elliptic one at H = 15 (1e-8); the damping ratio is α/(2Ω)."""
    model = duffing().with_damping(rayleigh=(0.05, 0.0))
    for H, reference in ((1, lambda A: np.sqrt(1 + 0.75 * A**2)), (15, exact_frequency)):
        b = mmshbm.backbone(model, harmonics=H, max_amplitude=2.0)
        assert b.method == "epmc" and b.metadata["requested_method"] == "mmshbm"
        assert b.amplitude[-1] == pytest.approx(2.0, rel=1e-9)
        np.testing.assert_allclose(b.records["xi"], 0.05, rtol=1e-12, atol=0)
        tolerance = 1e-8 if H > 1 else 1e-9
        np.testing.assert_allclose(2 * np.pi * b.frequency, reference(b.amplitude), rtol=tolerance)
        np.testing.assert_allclose(b.damping_ratio, 0.05 / (4 * np.pi * b.frequency), rtol=1e-12)
