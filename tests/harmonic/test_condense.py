"""Condensation of the linear subsystem against dense references and closed forms."""

import numpy as np
import pytest
from finite_differences import assert_derivative
from naive import condensed_stiffness_dense

import mmshbm
from mmshbm.harmonic.condense import Condensation, SingularDynamicStiffness


def test_one_dof_closed_form():
    """D_k = k2 − k2²/(k1 + k2 − (kΩ)² m) for the massless-node oscillator."""
    m, k1, k2 = 2.0, 3.0, 5.0
    model = mmshbm.OneDofOscillator(m, k1, k2, 0.1).model()
    omega = 0.9
    D, dD = Condensation(model).dynamic_stiffness(omega, 4)
    for k in range(5):
        s = k1 + k2 - (k * omega) ** 2 * m
        assert D[k, 0, 0] == pytest.approx(k2 - k2**2 / s, rel=1e-13)
        assert dD[k, 0, 0] == pytest.approx(-(k2**2) * 2 * k**2 * omega * m / s**2, rel=1e-12, abs=1e-14)


@pytest.mark.parametrize("backend", ["banded", "splu"])
@pytest.mark.parametrize("omega", [0.0, 2 * np.pi * 45.0, 2 * np.pi * 120.0])
def test_beam_matches_dense(beam21, backend, omega):
    D, dD = Condensation(beam21, backend).dynamic_stiffness(omega, 5)
    D_ref, dD_ref = condensed_stiffness_dense(beam21, omega, 5)
    for k in range(6):
        np.testing.assert_allclose(D[k], D_ref[k], rtol=1e-8, atol=1e-9 * np.abs(D_ref[k]).max())
        np.testing.assert_allclose(dD[k], dD_ref[k], rtol=1e-7, atol=1e-8 * max(np.abs(dD_ref[k]).max(), 1))
        np.testing.assert_allclose(D[k], D[k].T, rtol=1e-9, atol=1e-9 * np.abs(D[k]).max())


def test_derivative_matches_finite_difference(beam21):
    cond = Condensation(beam21)
    omega = 2 * np.pi * 50.0
    _, dD = cond.dynamic_stiffness(omega, 5)
    assert_derivative(lambda s: cond.dynamic_stiffness(omega + s, 5, derivative=False), dD, 1e-2)


def test_recover_satisfies_linear_equations(beam21):
    """S_k Q_l,k + K_lc Q_c,k = 0 for every harmonic and both cos/sin parts."""
    cond = Condensation(beam21)
    omega, H = 2 * np.pi * 50.0, 3
    rng = np.random.default_rng(1)
    Qc = rng.normal(size=(len(beam21.c), 2 * H + 1))
    Ql = cond.recover(omega, Qc)
    b = beam21.blocks
    for col in range(2 * H + 1):
        k = (col + 1) // 2
        S = b["K_ll"] - (k * omega) ** 2 * b["M_ll"]
        res = S @ Ql[:, col] + b["K_lc"] @ Qc[:, col]
        assert np.abs(res).max() < 1e-9 * np.abs(b["K_lc"] @ Qc[:, col]).max()


def test_condensed_static_stiffness_is_the_static_solution(beam21):
    """D_0 = the static stiffness at the tip: w_tip under a unit tip force from D_0⁻¹."""
    D0 = Condensation(beam21).D0
    tip_compliance = np.linalg.solve(D0, [1.0, 0.0])[0]
    beam = mmshbm.default_beam()
    # Timoshenko cantilever under a tip load: L³/(3EI) + L/(κGA)
    G = beam.E / (2 * (1 + beam.nu))
    A, I = beam.width * beam.height, beam.width * beam.height**3 / 12
    exact = beam.length**3 / (3 * beam.E * I) + beam.length / (beam.shear_factor * G * A)
    assert tip_compliance == pytest.approx(exact, rel=1e-10)


def test_singular_harmonic_is_reported():
    """kΩ exactly on an eigenfrequency of the clamped-contact structure."""
    model = mmshbm.OneDofOscillator(1.0, 1.0, 3.0, 0.1).model()
    omega_pole = np.sqrt(4.0)  # (k1 + k2)/m
    cond = Condensation(model)
    with pytest.raises(SingularDynamicStiffness, match="singular"):
        cond.dynamic_stiffness(omega_pole / 2, 2)


def test_backend_validation(beam21):
    with pytest.raises(ValueError, match="backend"):
        Condensation(beam21, "dense")
