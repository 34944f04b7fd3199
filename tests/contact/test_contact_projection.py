"""The exact (C¹) harmonic projection of the contact law (mmshbm.methods.mms.contact_kernels)
against adaptive quadrature between independently located zeros, and its Jacobian
against finite differences."""

import numpy as np
import pytest
from finite_differences import assert_jacobian
from scipy.integrate import quad
from scipy.optimize import brentq

from mmshbm.contact.projection import contact_spectrum
from mmshbm.contact.unilateral import project_contact


def _p(coefs, tau):
    H = (len(coefs) - 1) // 2
    k = np.arange(1, H + 1)
    return coefs[0] + coefs[1::2] @ np.cos(np.outer(k, tau)) + coefs[2::2] @ np.sin(np.outer(k, tau))


def _reference(coefs, lo, hi):
    """proj of (p − hi)₊ − (lo − p)₊ by scipy.quad on the arcs between zeros found by
    brentq on a 20 000-point grid (no code shared with the kernels)."""
    H = (len(coefs) - 1) // 2
    grid = np.linspace(0.0, 2 * np.pi, 20001)

    def f(t):
        v = _p(coefs, np.atleast_1d(t))[0]
        return max(0.0, v - hi) - max(0.0, lo - v)

    breaks = [0.0]
    for theta in (hi, lo):
        if np.isinf(theta):
            continue
        v = _p(coefs, grid) - theta
        for j in np.flatnonzero(v[:-1] * v[1:] < 0):
            def g(t, th=theta):
                return _p(coefs, np.atleast_1d(t))[0] - th

            breaks.append(brentq(g, grid[j], grid[j + 1], xtol=1e-15))
    breaks = sorted(breaks) + [2 * np.pi]
    r = np.zeros(2 * H + 1)
    tol = {"epsabs": 1e-14, "epsrel": 1e-12}
    for a, b in zip(breaks[:-1], breaks[1:], strict=True):
        r[0] += quad(f, a, b, **tol)[0] / (2 * np.pi)
        for k in range(1, H + 1):
            r[2 * k - 1] += quad(lambda t, k=k: f(t) * np.cos(k * t), a, b, **tol)[0] / np.pi
            r[2 * k] += quad(lambda t, k=k: f(t) * np.sin(k * t), a, b, **tol)[0] / np.pi
    return r


@pytest.mark.filterwarnings("ignore::scipy.integrate.IntegrationWarning")
@pytest.mark.parametrize("H, seed, lo, hi", [(1, 0, -np.inf, 0.3), (3, 1, -0.5, 0.2), (5, 2, -0.2, np.inf),
                                             (8, 3, -0.4, 0.4)])
def test_exact_projection_equals_quadrature(H, seed, lo, hi):
    p = np.random.default_rng(seed).normal(size=2 * H + 1) / np.sqrt(np.arange(1, 2 * H + 2))
    r, _ = project_contact(p, lo, hi)
    np.testing.assert_allclose(r, _reference(p, lo, hi), rtol=0, atol=1e-11)


@pytest.mark.parametrize("exact", [True, False])
def test_jacobian_matches_finite_differences(exact):
    H = 6
    p = np.random.default_rng(5).normal(size=2 * H + 1) / np.arange(1, 2 * H + 2)
    r, G = project_contact(p, -0.3, 0.25, exact=exact)
    assert_jacobian(lambda q: project_contact(q, -0.3, 0.25, exact=exact)[0], p, G, 1e-5)


def test_a_narrow_contact_between_samples_is_found():
    """p = cos τ − 0.9999: the set {p > 0} is an arc of width 2·arccos(0.9999) ≈ 0.028,
    less than one sample spacing of 8 samples; its spectrum is still exact."""
    width = 2 * np.arccos(0.9999)
    C, S = contact_spectrum(np.array([-0.9999, 1.0]), None, exact=True, n_samples=8)
    assert C[0] == pytest.approx(width / (2 * np.pi), rel=1e-12)
    assert np.abs(S).max() < 1e-15
    # and a pair hidden between samples (no sample above zero): shifted off the grid
    c = np.array([-0.9999, np.cos(0.3), np.sin(0.3)])  # cos(τ − 0.3) − 0.9999
    C2, _ = contact_spectrum(c[:2], np.array([0.0, c[2]]), exact=True, n_samples=8)
    assert C2[0] == pytest.approx(width / (2 * np.pi), rel=1e-10)


@pytest.mark.parametrize("n_samples", [8, 64, 128])
def test_zeros_and_extrema_on_samples(n_samples):
    """p = cos τ: its zeros π/2, 3π/2 and extrema 0, π lie on the samples, where the
    sampled values are round-off (±6e-17) rather than zero; the arc (−π/2, π/2) is found
    exactly: C_0 = 1/2, C_1 = 1/π, C_2 = 0, C_3 = −1/(3π)."""
    C, S = contact_spectrum(np.array([0.0, 1.0, 0.0, 0.0]), None, exact=True, n_samples=n_samples)
    np.testing.assert_allclose(C[:4], [0.5, 1 / np.pi, 0.0, -1 / (3 * np.pi)], rtol=0, atol=1e-15)
    assert np.abs(S).max() < 1e-15
    # scaled to metres (a gap of 1 mm): the round-off stop must scale with the function
    C_mm, _ = contact_spectrum(np.array([0.0, 1e-3, 0.0, 0.0]), None, exact=True, n_samples=n_samples)
    np.testing.assert_allclose(C_mm, C, rtol=0, atol=1e-15)


def test_the_projection_is_continuous_through_grazing():
    """As a contact window opens (p's maximum crosses hi), the projection and its Jacobian
    change continuously: no jump from one side of grazing to the other."""
    base = np.array([0.0, 1.0, 0.0, 0.2, 0.0])
    values = []
    for hi in np.linspace(1.2 - 1e-6, 1.2 + 1e-6, 41):
        r, G = project_contact(base, -np.inf, hi)
        values.append((r, G))
    dr = max(np.abs(a[0] - b[0]).max() for a, b in zip(values, values[1:], strict=False))
    dG = max(np.abs(a[1] - b[1]).max() for a, b in zip(values, values[1:], strict=False))
    assert dr < 1e-9 and dG < 1e-3


def test_bad_input():
    with pytest.raises(ValueError, match="need lo <= hi"):
        project_contact(np.zeros(3), 1.0, 0.0)
    with pytest.raises(ValueError, match="2H\\+1 entries"):
        project_contact(np.zeros(4), -1.0, 1.0)
