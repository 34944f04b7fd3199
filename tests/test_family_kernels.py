"""The compiled family records reproduce their NumPy expressions to the last bit (the
branch's records and the family guard's decisions must not change with them)."""

from __future__ import annotations

import numpy as np

from mmshbm.methods.mms._family_kernels import _block_sum, family_records, harmonic_energies


def _energies_numpy(a, dD, eta, pole_k, omega):
    quad = np.einsum("ki,kij,kj->k", a, dD, a)
    for p, k in enumerate(pole_k):
        quad[k] -= 2.0 * k * k * omega * eta[p] ** 2
    energies = -omega / 8.0 * quad
    energies[0] = 0.0
    return np.maximum(energies, 0.0)


def _records_numpy(a, dD, eta, pole_k, omega, freqs):
    energies = _energies_numpy(a, dD, eta, pole_k, omega)
    total = float(energies[1:].sum())
    out = {"fundamental_share": float(energies[1] / total) if total > 0 else 1.0,
           "resonance_harmonic": 0.0, "resonance_mode": 0.0, "resonance_detuning": float("nan")}
    H = len(energies) - 1
    if H >= 2 and total > 0:
        k = int(np.argmax(energies[2:])) + 2
        f = k * omega / (2 * np.pi)
        j = int(np.argmin(np.abs(freqs - f)))
        out.update(resonance_harmonic=float(k), resonance_mode=float(j + 1),
                   resonance_detuning=float(f / freqs[j] - 1.0))
    return out


def test_block_sum_is_numpys():
    rng = np.random.default_rng(5)
    for n in range(1, 129):
        x = np.abs(rng.standard_normal(n + 3)) * 10.0 ** rng.integers(-8, 3, size=n + 3)
        assert _block_sum(x, 2, n) == float(x[2:2 + n].sum())


def test_records_are_the_numpy_expressions_bit_for_bit():
    rng = np.random.default_rng(11)
    for trial in range(3000):
        n_c, n_p = rng.integers(1, 6), rng.integers(0, 4)
        H1 = rng.integers(2, 30) if trial % 100 else rng.integers(120, 140)  # either side of H = 128
        a = rng.standard_normal((H1, n_c)) * 1e-3
        dD = rng.standard_normal((H1, n_c, n_c)) * 1e-2
        dD -= 2e-2 * np.eye(n_c)  # mostly positive energies, some clipped at 0
        eta = rng.standard_normal(n_p) * 1e-3
        pole_k = rng.integers(1, H1, size=n_p).astype(np.int64)
        omega = 300.0 * rng.random()
        freqs = np.sort(rng.random(rng.integers(1, 8)) * 500.0)
        ref = _energies_numpy(a, dD, eta, pole_k, omega)
        assert np.array_equal(harmonic_energies(a, dD, eta, pole_k, omega), ref)
        got = family_records(a, dD, eta, pole_k, omega, freqs)
        want = _records_numpy(a, dD, eta, pole_k, omega, freqs)
        assert list(got) == list(want)
        for key in want:
            assert got[key] == want[key] or (np.isnan(got[key]) and np.isnan(want[key])), key


def test_no_motion_and_one_harmonic():
    a = np.zeros((4, 2))
    dD = -np.ones((4, 2, 2))
    none = np.zeros(0, dtype=np.int64)
    rec = family_records(a, dD, np.zeros(0), none, 100.0, np.array([10.0, 50.0]))
    assert rec["fundamental_share"] == 1.0 and rec["resonance_harmonic"] == 0.0
    assert np.isnan(rec["resonance_detuning"])
    a1 = np.array([[0.0], [1e-3]])
    rec1 = family_records(a1, -np.ones((2, 1, 1)), np.zeros(0), none, 100.0, np.array([10.0]))
    assert rec1["fundamental_share"] == 1.0 and rec1["resonance_mode"] == 0.0
