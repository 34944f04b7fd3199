"""Shooting with the friction node's exact prox per step against the exact event-driven
orbit (Δt → 0, and along a frequency response) and the linear stuck limit."""

import numpy as np
import pytest

import mmshbm
from mmshbm.methods.exact.friction import friction_orbit
from mmshbm.methods.shooting.friction import friction_shooting_orbit

M_, K1, K2, C_, F_ = 1.0, 1.0, 2.0, 0.05, 0.1


def jenkins(normal_load, mu=0.5):
    M = np.diag([M_, 0.0])
    K = np.array([[K1 + K2, -K2], [-K2, K2]])
    base = mmshbm.Model.from_matrices(M, K, [], [], [], damping=np.diag([C_, 0.0]), amplitude_dof=0)
    return base.with_friction(1, mu, normal_load=normal_load)


@pytest.mark.parametrize("f", [0.2, 0.25])
def test_shooting_converges_to_the_exact_orbit(f):
    """Measured: 4.4e-4, 1.7e-5, 2.0e-6 (0.2 Hz) and 4.0e-4, 3.1e-5, 1.7e-6 (0.25 Hz) at 128,
    512, 2048 steps: the trapezoidal rule's O(Δt²), a switch located within a step."""
    model = jenkins(0.2)
    exact = friction_orbit(model, [F_, 0.0], f)
    err = {}
    for n in (128, 512, 2048):
        orbit = friction_shooting_orbit(model, [F_, 0.0], f, n)
        assert orbit.converged
        err[n] = abs(orbit.amplitude(0) / exact.amplitude(0) - 1)
    assert err[2048] < err[512] < err[128]
    assert err[2048] < 5e-6, err
    assert abs(orbit.slip_fraction - exact.slip_fraction) < 2.0 / 2048 + 1e-12


def test_stuck_limit_is_the_linear_response_up_to_the_trapezoidal_phase_error():
    """N = 1000 N: the node never slips, the orbit is the linear stuck response; the
    trapezoidal rule's relative amplitude error near resonance is O((ωΔt)²/ζ), asserted at
    (2π/n)²/ζ."""
    f, n = 0.25, 1024
    w = 2 * np.pi * f
    X = F_ / (K1 + K2 - M_ * w**2 + 1j * C_ * w)
    orbit = friction_shooting_orbit(jenkins(1000.0), [F_, 0.0], f, n)
    assert orbit.converged and orbit.slip_fraction == 0.0
    zeta = C_ / (2 * np.sqrt((K1 + K2) * M_))
    assert abs(orbit.amplitude(0) / abs(X) - 1) < (2 * np.pi / n) ** 2 / zeta


def test_shooting_frequency_response_follows_the_exact_orbits():
    """Points of the continued response equal the fixed-frequency orbits and lie within
    2e-5 of the exact orbits at 1024 steps (measured <= 1.0e-5; MMS-HBM H = 15: 1.2e-5)."""
    model = jenkins(0.2)
    r = mmshbm.frequency_response(model, [F_, 0.0], (0.19, 0.21), method="shooting", steps_per_period=1024)
    assert r.status.startswith("bound") and len(r.frequency) >= 3
    for f, a in zip(r.frequency[::3], r.amplitude[::3], strict=True):
        orbit = friction_shooting_orbit(model, [F_, 0.0], f, 1024)
        assert a == pytest.approx(orbit.amplitude(0), rel=1e-8)
        assert a == pytest.approx(friction_orbit(model, [F_, 0.0], f).amplitude(0), rel=2e-5)
    assert np.all(r.records["friction_dissipation"] > 0)
