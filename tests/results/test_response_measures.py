"""The per-DOF measures of a forced response (rms, peak amplitude, phase, frequency in rad/s)
against the closed form of the linear response: friction with zero normal load is the
linear system, Q̂_1 = F̂/(K − Ω²M + iΩC) per DOF (2-DOF Jenkins oscillator, the slider
following the mass)."""

import numpy as np
import pytest

import mmshbm

M_, K1, K2, C_, F_ = 1.0, 1.0, 2.0, 0.05, 0.1


@pytest.fixture(scope="module")
def linear_response():
    M = np.diag([M_, 0.0])
    K = np.array([[K1 + K2, -K2], [-K2, K2]])
    base = mmshbm.Model.from_matrices(M, K, [], [], [], damping=np.diag([C_, 0.0]), amplitude_dof=0)
    model = base.with_friction(1, 0.5, normal_load=0.0)
    return mmshbm.frequency_response(model, [F_, 0.0], (0.1, 0.25), harmonics=5)


def _closed_form(omega):
    """Harmonic 1 of DOFs 0 and 1, shape (n_points, 2), complex: the slider is free, so it
    moves with the mass."""
    X = F_ / (K1 - M_ * omega**2 + 1j * C_ * omega)
    return np.column_stack([X, X])


def test_frequency_in_rad_per_second(linear_response):
    r = linear_response
    np.testing.assert_allclose(r.angular_frequency, 2 * np.pi * r.frequency, rtol=1e-15)


@pytest.mark.parametrize("dof", [0, 1])
def test_rms_peak_and_phase_equal_the_closed_form(linear_response, dof):
    r = linear_response
    X = _closed_form(r.angular_frequency)[:, dof]
    # rms of a harmonic: |X|/√2 (the sample mean of q² is exact: round-off only)
    np.testing.assert_allclose(r.rms(dof), np.abs(X) / np.sqrt(2), rtol=1e-10)
    # peak: the parabola through the sampled maximum of a sinusoid on 256 samples is off by
    # at most (Δτ)⁴/... ~ 1e-8 relative (Δτ = 2π/256)
    np.testing.assert_allclose(r.peak_amplitude(dof), np.abs(X), rtol=1e-7)
    # phase: the lag of q behind the force F cos Ωt is −arg X, in [0, π) for damping > 0
    np.testing.assert_allclose(r.phase_of(dof), -np.angle(X), rtol=0, atol=1e-10)


def test_the_default_dof_is_the_amplitude_dof(linear_response):
    r = linear_response
    np.testing.assert_array_equal(r.rms(), r.rms(0))
    np.testing.assert_allclose(r.peak_amplitude(), r.amplitude, rtol=1e-7)
    np.testing.assert_allclose(r.phase_of(), r.phase, rtol=0, atol=1e-10)


def test_a_bad_dof_is_named(linear_response):
    with pytest.raises(ValueError, match=r"dof must be in \[0, 1\], got 7"):
        linear_response.rms(7)
    with pytest.raises(TypeError, match="dof"):
        linear_response.peak_amplitude(0.5)
