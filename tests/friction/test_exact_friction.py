"""The exact friction reference (mmshbm.methods.exact.friction) against closed forms, an
independent time integration (scipy solve_ivp with events) and the energy balance."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mmshbm
from mmshbm.methods.exact.friction import friction_orbit

M_, K1, K2, C_, F_ = 1.0, 1.0, 2.0, 0.05, 0.1


def jenkins(normal_load, mu=0.5, c=C_):
    M = np.diag([M_, 0.0])
    K = np.array([[K1 + K2, -K2], [-K2, K2]])
    base = mmshbm.Model.from_matrices(M, K, [], [], [], damping=np.diag([c, 0.0]), amplitude_dof=0)
    return base.with_friction(1, mu, normal_load=normal_load)


def linear_amplitude(k, omega, c=C_):
    return abs(F_ / (k - M_ * omega**2 + 1j * c * omega))


@pytest.mark.parametrize("f", [0.1, 0.2757, 0.35])
def test_stuck_and_free_slip_limits_equal_the_linear_closed_forms(f):
    omega = 2 * np.pi * f
    stuck = friction_orbit(jenkins(1e3), [F_, 0.0], f)
    assert stuck.converged and stuck.slip_fraction == 0.0
    assert stuck.amplitude(0) == pytest.approx(linear_amplitude(K1 + K2, omega), rel=1e-10)
    free = friction_orbit(jenkins(0.0), [F_, 0.0], f)
    assert free.converged
    assert free.amplitude(0) == pytest.approx(linear_amplitude(K1, omega), rel=1e-10)


def ivp_jenkins(x0, v0, u0, t_end, s, omega, c=C_):
    """Independent event-driven integration of the Jenkins oscillator (DOP853, tight
    tolerances): stick (u fixed, |k2 (u − x)| < s) and slip σ (force −σ s on the mass,
    u = x − σ s/k2) with the switches located by solve_ivp's event finder."""
    t, y = 0.0, np.array([x0, v0])
    g = K2 * (u0 - x0)
    mode = 0 if abs(g) < s else (-1 if g > 0 else 1)
    u = u0 if mode == 0 else x0 - mode * s / K2
    switches = []
    while t < t_end:
        if mode == 0:
            def rhs(t, y, u=u):
                return [y[1], (F_ * np.cos(omega * t) - c * y[1] - K1 * y[0] + K2 * (u - y[0])) / M_]
            events = [lambda t, y, u=u: s - K2 * (u - y[0]), lambda t, y, u=u: s + K2 * (u - y[0])]
        else:
            def rhs(t, y, sg=mode):
                return [y[1], (F_ * np.cos(omega * t) - c * y[1] - K1 * y[0] - sg * s) / M_]
            events = [lambda t, y, sg=mode: sg * y[1]]
        for e in events:
            e.terminal, e.direction = True, -1
        sol = solve_ivp(rhs, (t, t_end), y, method="DOP853", rtol=1e-13, atol=1e-16, events=events)
        y = sol.y[:, -1]
        if sol.status != 1:
            break
        t = sol.t[-1]
        switches.append(t)
        if mode == 0:
            mode = -1 if len(sol.t_events[0]) else 1
        else:
            u, mode = y[0] - mode * s / K2, 0
    if mode != 0:
        u = y[0] - mode * s / K2
    return y, u, np.array(switches)


@pytest.mark.parametrize("f", [0.2, 0.25])
def test_exact_orbit_against_an_independent_time_integration(f):
    omega = 2 * np.pi * f
    model = jenkins(0.2)
    orbit = friction_orbit(model, [F_, 0.0], f)
    assert orbit.converged and 0 < orbit.slip_fraction < 1
    x0, v0, u0 = orbit.y0
    y, u, switches = ivp_jenkins(x0, v0, u0, 1 / f, 0.1, omega)
    # DOP853 at rtol 1e-13 over one period: a few 1e-12 of the state's scale
    scale = np.abs(orbit.y0).max()
    np.testing.assert_allclose([y[0], y[1], u], orbit.y0, rtol=0, atol=1e-10 * scale)
    np.testing.assert_allclose(switches, orbit.switch_times, rtol=0, atol=1e-9 / f)


def test_exact_transient_against_an_independent_time_integration():
    """From a state far off the orbit (stick at an offset), two periods with many switches."""
    f = 0.22
    model = jenkins(0.2)
    orbit = friction_orbit(model, [F_, 0.0], f, settle_periods=0, max_iter=0)
    sysm = orbit.system
    start = np.array([0.3, -0.1, 0.25])
    segs, z, u = sysm.integrate(start[:2], start[2], 0.0, 2 / f)
    y, u_ivp, switches = ivp_jenkins(*start, 2 / f, 0.1, 2 * np.pi * f)
    np.testing.assert_allclose([y[0], y[1], u_ivp], [z[0], z[1], u], rtol=0, atol=1e-10)
    np.testing.assert_allclose(switches, [sg[2] for sg in segs[1:]], rtol=0, atol=1e-8)


@pytest.mark.parametrize("f,N", [(0.18, 0.2), (0.2, 0.2), (0.25, 0.1), (0.16, 0.02)])
def test_energy_balance_of_the_exact_orbit(f, N):
    """Input work = viscous + friction dissipation (s × slip distance) per period: each by
    quadrature exact to round-off, so they agree to ~1e-14 relative."""
    orbit = friction_orbit(jenkins(N), [F_, 0.0], f)
    assert orbit.converged
    e = orbit.energy_balance()
    assert e["friction"] > 0
    assert abs(e["input"] - e["viscous"] - e["friction"]) <= 1e-10 * e["input"]


def test_several_dofs_with_mass_and_friction_alone():
    """Two masses in a chain, the second joined to the massless node, no viscous damping:
    the orbit is periodic and its input work equals the friction dissipation."""
    M = np.diag([1.0, 0.5, 0.0])
    K = np.array([[3.0, -1.0, 0.0], [-1.0, 3.0, -2.0], [0.0, -2.0, 2.0]])
    model = mmshbm.Model.from_matrices(M, K, [], [], [], amplitude_dof=0)
    model = model.with_friction(2, 0.5, normal_load=0.1)
    orbit = friction_orbit(model, [0.1, 0.0, 0.0], 0.19)
    assert orbit.converged and 0 < orbit.slip_fraction < 1
    e = orbit.energy_balance()
    assert e["viscous"] == 0.0
    assert abs(e["input"] - e["friction"]) <= 1e-10 * e["input"]


def test_what_the_reference_does_not_handle_is_refused():
    M = np.diag([1.0, 0.0, 0.0])
    K = np.array([[3.0, -1, -1], [-1, 2, 0], [-1, 0, 2]])
    model = mmshbm.Model.from_matrices(M, K, 1, 1e-3, amplitude_dof=0).with_friction(2, 0.2, normal_load=1.0)
    with pytest.raises(NotImplementedError, match="no unilateral contact"):
        friction_orbit(model, [1.0, 0, 0], 0.2)
