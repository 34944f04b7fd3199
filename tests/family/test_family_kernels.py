"""The compiled family records against their NumPy expressions: the energies to the
round-off of their sums (tests/roundoff.py), the records derived from them within what that
round-off can move them."""

from __future__ import annotations

import numpy as np
from roundoff import EPS, assert_roundoff_close, roundoff_tolerance

from mmshbm.methods.mms._family_kernels import family_records, harmonic_energies


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


def _energy_scale(a, dD, eta, pole_k, omega):
    """Σ|terms| of each harmonic's energy (Ω/8)(Σ_ij a_ki ∂D_kij a_kj − 2k²Ω Σ η_p²), and the
    number of roundings in its longest chain (terms summed plus those of each product)."""
    scale = np.einsum("ki,kij,kj->k", np.abs(a), np.abs(dD), np.abs(a))
    for p, k in enumerate(pole_k):
        scale[k] += 2.0 * k * k * omega * eta[p] ** 2
    return omega / 8.0 * scale, a.shape[1] ** 2 + len(pole_k) + 4


def _assert_records_close(got, want, ref, tol):
    """The records of the compiled kernel against NumPy's, given the NumPy energies ``ref``
    and the round-off ``tol`` (entry by entry) they may differ by."""
    assert list(got) == list(want)
    total = ref[1:].sum()
    if total > 0:  # e₁/Σe: the round-off of both (and of Σ's H − 1 additions)
        dtotal = tol[1:].sum() + len(ref) * EPS * total
        share_tol = (tol[1] + want["fundamental_share"] * dtotal) / total + 2 * EPS
        assert abs(got["fundamental_share"] - want["fundamental_share"]) <= share_tol
    else:
        assert got["fundamental_share"] == want["fundamental_share"] == 1.0
    top = np.sort(ref[2:])[::-1]
    if len(top) > 1 and top[0] - top[1] <= 2 * tol[2:].max():
        return  # the strongest higher harmonic is a tie within round-off: either is right
    for key in ("resonance_harmonic", "resonance_mode"):  # integers
        assert got[key] == want[key], key
    assert_roundoff_close(got["resonance_detuning"], want["resonance_detuning"],
                          abs(want["resonance_detuning"]) + 1.0, terms=4)


def test_records_are_the_numpy_expressions_to_their_roundoff():
    rng = np.random.default_rng(11)
    for trial in range(3000):
        n_c, n_p = rng.integers(1, 6), rng.integers(0, 4)
        H1 = rng.integers(2, 30) if trial % 100 else rng.integers(120, 140)  # and a few long ones
        a = rng.standard_normal((H1, n_c)) * 1e-3
        dD = rng.standard_normal((H1, n_c, n_c)) * 1e-2
        dD -= 2e-2 * np.eye(n_c)  # mostly positive energies, some clipped at 0
        eta = rng.standard_normal(n_p) * 1e-3
        pole_k = rng.integers(1, H1, size=n_p).astype(np.int64)
        omega = 300.0 * rng.random()
        freqs = np.sort(rng.random(rng.integers(1, 8)) * 500.0)
        ref = _energies_numpy(a, dD, eta, pole_k, omega)
        scale, terms = _energy_scale(a, dD, eta, pole_k, omega)
        got = harmonic_energies(a, dD, eta, pole_k, omega)
        assert_roundoff_close(got, ref, scale, terms, err_msg=f"trial {trial}")
        _assert_records_close(family_records(a, dD, eta, pole_k, omega, freqs),
                              _records_numpy(a, dD, eta, pole_k, omega, freqs), ref,
                              roundoff_tolerance(scale, terms))


def test_the_tolerance_sees_a_missing_term():
    """A pole term left out, or a sign flipped, moves an energy by many times the round-off."""
    rng = np.random.default_rng(2)
    a, dD = rng.standard_normal((6, 3)) * 1e-3, rng.standard_normal((6, 3, 3)) * 1e-2 - 2e-2 * np.eye(3)
    eta, pole_k, omega = np.array([1e-3]), np.array([2], dtype=np.int64), 250.0
    scale, terms = _energy_scale(a, dD, eta, pole_k, omega)
    tol = roundoff_tolerance(scale, terms)
    got = harmonic_energies(a, dD, eta, pole_k, omega)
    without_pole = _energies_numpy(a, dD, eta[:0], pole_k[:0], omega)
    assert abs(got[2] - without_pole[2]) > 1e6 * tol[2]
    flipped = _energies_numpy(a, -dD, eta, pole_k, omega)
    assert np.max(np.abs(got - flipped)[1:]) > 1e6 * tol[1:].max()


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
