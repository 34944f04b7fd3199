"""Kinetic-energy shares per mode and harmonic (mmshbm.harmonic.modal_energy)."""

import numpy as np

import mmshbm
from mmshbm.harmonic.modal_energy import kinetic_energy_shares


def test_shares_of_a_two_mode_motion_are_exact():
    """q = φ1 a cos τ + φ2 b cos 3τ: shares ω-weighted as ¼(kΩ)²η², summing to 1."""
    model = mmshbm.default_beam().model(8)
    _, phi = model.linear_modes(len(model.l))
    M = model.M
    a, b, omega = 2e-3, 1e-4, 300.0
    Q = np.zeros((model.n_dof, 7))
    Q[:, 1] = a * phi[:, 0]
    Q[:, 5] = b * phi[:, 1]
    shares, total = kinetic_energy_shares(phi, None, Q, omega, M)
    T1, T2 = 0.25 * omega**2 * a**2, 0.25 * (3 * omega) ** 2 * b**2
    assert total == np.float64(total) and abs(total - (T1 + T2)) < 1e-12 * (T1 + T2)
    assert abs(shares[0, 1] - T1 / (T1 + T2)) < 1e-10 and abs(shares[1, 3] - T2 / (T1 + T2)) < 1e-10
    assert abs(shares.sum() - 1.0) < 1e-10 and shares[:, 0].sum() == 0.0
