"""Numba kernels against plain-NumPy references."""

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from naive import proximal_contact_loop

from mmshbm.contact.projection import cosine_product_matrix
from mmshbm.contact.unilateral import proximal_contact
from mmshbm.harmonic.kernels import _band_quadratic_form, _band_solve


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(-1e3, 1e3), st.floats(-1e-2, 1e-2)), min_size=1, max_size=50),
       st.floats(1e-3, 1e6))
def test_proximal_contact_equals_loop(pairs, r):
    lam, g = (np.array(v) for v in zip(*pairs, strict=True))
    R, active = proximal_contact(lam, g, r)
    R_ref, active_ref = proximal_contact_loop(lam, g, r)
    np.testing.assert_allclose(R, R_ref, rtol=1e-12, atol=1e-12 * (1 + r))
    np.testing.assert_array_equal(active, active_ref)


@settings(max_examples=60, deadline=None)
@given(st.floats(-1e3, 1e3, allow_subnormal=False), st.floats(-1e-2, 1e-2, allow_subnormal=False),
       st.floats(1e-3, 1e6))
def test_proximal_zeros_are_complementary(lam, g, r):
    """R = 0 exactly when 0 <= g ⊥ λ >= 0 (for any r > 0; a subnormal g makes r·g underflow
    to 0, which no floating-point residual can tell from an exact zero)."""
    R, _ = proximal_contact(np.array([lam]), np.array([g]), r)
    complementary = g >= 0 and lam >= 0 and (g == 0 or lam == 0)
    assert (R[0] == 0) == complementary


def test_proximal_fixed_point_projection():
    """At a zero of R, λ = max(0, λ − r g) holds: λ is the prox of λ − r g onto R+."""
    lam = np.array([0.0, 5.0, 0.0])
    g = np.array([1e-3, 0.0, 0.0])
    for r in (1.0, 1e4):
        R, _ = proximal_contact(lam, g, r)
        np.testing.assert_array_equal(R, 0.0)
        np.testing.assert_array_equal(lam, np.maximum(0.0, lam - r * g))


def test_proximal_contact_validates():
    with pytest.raises(ValueError, match="equal length"):
        proximal_contact(np.zeros(3), np.zeros(4), 1.0)
    with pytest.raises(ValueError, match="r must be positive"):
        proximal_contact(np.zeros(3), np.zeros(3), 0.0)


def test_cosine_product_matrix_equals_direct_sums():
    H, N = 4, 32
    tau = 2 * np.pi * np.arange(N) / N
    s = (np.cos(tau) > 0.3).astype(float)
    S = np.array([np.mean(s * np.cos(p * tau)) for p in range(N)])
    P = cosine_product_matrix(S, H)
    for m in range(H + 1):
        for k in range(H + 1):
            c = 1.0 if m == 0 else 2.0
            assert abs(P[m, k] - c * np.mean(s * np.cos(m * tau) * np.cos(k * tau))) < 1e-14


def _random_band(n, kl, rng, shift=0.0):
    A = sp.random(n, n, density=1.0, random_state=rng).toarray()
    A = np.triu(np.tril(A, kl), -kl)
    return A + A.T + shift * np.eye(n)


def _row_band(A, kl):
    n = A.shape[0]
    B = np.zeros((n, 3 * kl + 1))
    for i in range(n):
        for j in range(max(0, i - kl), min(n, i + kl + 1)):
            B[i, j - i + kl] = A[i, j]
    return B


@pytest.mark.parametrize("n, kl", [(1, 1), (5, 1), (40, 3), (60, 5)])
def test_band_solve_equals_dense_solve_including_pivoting(n, kl):
    rng = np.random.default_rng(n + kl)
    K = _random_band(n, kl, rng, shift=0.1)   # indefinite mixtures need pivoting
    M = _random_band(n, kl, rng, shift=n)
    B = rng.normal(size=(n, 3))
    for w2 in (0.0, 0.7, 3.0):
        X = np.empty_like(B)
        info = _band_solve(_row_band(K, kl), _row_band(M, kl), kl, w2, B, np.empty((n, 3 * kl + 1)), X)
        assert info == 0
        np.testing.assert_allclose(X, np.linalg.solve(K - w2 * M, B), rtol=1e-9, atol=1e-10)


def test_band_solve_reports_exact_singularity():
    K = np.diag([1.0, 0.0, 2.0])
    info = _band_solve(_row_band(K, 1), np.zeros((3, 4)), 1, 0.0, np.ones((3, 1)), np.empty((3, 4)),
                       np.empty((3, 1)))
    assert info == 2


def test_band_quadratic_form():
    rng = np.random.default_rng(0)
    M = _random_band(30, 3, rng, shift=30)
    Z = rng.normal(size=(30, 2))
    out = np.empty((2, 2))
    _band_quadratic_form(_row_band(M, 3), 3, Z, out)
    np.testing.assert_allclose(out, Z.T @ M @ Z, rtol=1e-12)
