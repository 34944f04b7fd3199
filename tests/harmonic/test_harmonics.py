"""Harmonic transforms against plain DFT-matrix references (tests/naive.py)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from naive import projection, synthesis_matrix

from mmshbm.harmonic.harmonics import HarmonicTransform, check_harmonics, default_n_samples, transform

shapes = st.tuples(st.integers(1, 12), st.integers(0, 40), st.integers(1, 3)).map(
    lambda t: (t[0], 2 * t[0] + 1 + t[1], t[2]))


@settings(max_examples=40, deadline=None)
@given(shapes, st.integers(0, 2**31 - 1), st.booleans())
def test_synthesis_and_projection_match_dft_matrices(shape, seed, use_fftw):
    H, N, n = shape
    coeffs = np.random.default_rng(seed).normal(size=(n, 2 * H + 1))
    tr = HarmonicTransform(H, N, n, use_fftw=use_fftw)
    x = tr.to_time(coeffs)
    E = synthesis_matrix(H, N)
    np.testing.assert_allclose(x, coeffs @ E.T, atol=1e-12 * (1 + np.abs(coeffs).sum()))
    # round trip: projecting a band-limited signal recovers its coefficients
    np.testing.assert_allclose(tr.to_harmonics(x), coeffs, atol=1e-12 * (1 + np.abs(coeffs).sum()))
    # projection of arbitrary samples equals the DFT-matrix projection
    y = np.random.default_rng(seed + 1).normal(size=(n, N))
    ref = np.array([projection(row, H) for row in y])
    np.testing.assert_allclose(tr.to_harmonics(y), ref, atol=1e-12 * N)


@settings(max_examples=40, deadline=None)
@given(shapes, st.integers(0, 2**31 - 1))
def test_cosine_transforms_are_the_cosine_part(shape, seed):
    H, N, n = shape
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n, H + 1))
    full = np.zeros((n, 2 * H + 1))
    full[:, 0] = a[:, 0]
    full[:, 1::2] = a[:, 1:]
    tr = HarmonicTransform(H, N, n)
    x = tr.cos_to_time(a)
    np.testing.assert_allclose(x, full @ synthesis_matrix(H, N).T, atol=1e-12 * (1 + np.abs(a).sum()))
    np.testing.assert_allclose(tr.time_to_cos(x), a, atol=1e-12 * (1 + np.abs(a).sum()))


@settings(max_examples=30, deadline=None)
@given(st.integers(1, 10), st.integers(0, 30), st.integers(0, 2**31 - 1))
def test_cosine_spectrum_gives_products_of_cosines(H, extra, seed):
    N = 2 * H + 1 + extra
    s = np.random.default_rng(seed).random(N)
    tau = 2 * np.pi * np.arange(N) / N
    S = HarmonicTransform(H, N, 1).cosine_spectrum(s[None])[0]
    for m in range(H + 1):
        for k in range(H + 1):
            direct = np.mean(s * np.cos(m * tau) * np.cos(k * tau))
            assert abs(0.5 * (S[abs(m - k) % N] + S[(m + k) % N]) - direct) < 1e-13


def test_numpy_fallback_equals_fftw():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(2, 6))
    x1 = HarmonicTransform(5, 64, 2, use_fftw=True).cos_to_time(a)
    x2 = HarmonicTransform(5, 64, 2, use_fftw=False).cos_to_time(a)
    np.testing.assert_allclose(x1, x2, atol=1e-13)


def test_transform_cache_returns_same_plan():
    assert transform(5, 64, 2) is transform(5, 64, 2)


@pytest.mark.parametrize("H, N, match", [
    (0, None, "harmonics"),
    (3, 6, r"n_samples must be >= 2\*harmonics\+1 = 7, got 6"),
    (2.5, None, "integer"),
    (True, None, "integer"),
])
def test_bad_harmonics(H, N, match):
    with pytest.raises((ValueError, TypeError), match=match):
        check_harmonics(H, N)


def test_default_samples_oversample():
    for H in (1, 5, 20, 100):
        N = default_n_samples(H)
        assert N >= 16 * H and N >= 64 and N & (N - 1) == 0
