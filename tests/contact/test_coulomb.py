"""The Coulomb law at a massless DOF: pointwise kernels and the exact harmonic projection
against plain-NumPy references (tests/naive_friction.py) and finite differences."""

import numpy as np
import pytest
from naive_friction import clip_loop, play_force_sampled, project_clip, synth

from mmshbm.contact import coulomb_derivative, coulomb_residual, derivative_matrix, project_coulomb
from mmshbm.contact.coulomb import project_coulomb_play

EPS = np.finfo(float).eps


def test_the_three_cases_of_coulomb_solve_the_proximal_equation():
    s, r = 2.0, 7.0
    # stick: v = 0, |f| <= s; slip +: f = s, v > 0; slip −: f = −s, v < 0
    f = np.array([0.3, -2.0, 2.0, 2.0, -2.0])
    v = np.array([0.0, 0.0, 0.0, 1.5, -0.2])
    assert np.all(coulomb_residual(f, v, s, r) == 0.0)
    # violations: slip against the force, |f| > s, slip below s
    f_bad = np.array([2.0, 2.5, 1.0, -1.0])
    v_bad = np.array([-1.0, 0.0, 0.5, -0.5])
    assert np.all(coulomb_residual(f_bad, v_bad, s, r) != 0.0)


def test_pointwise_kernels_against_branches():
    rng = np.random.default_rng(1)
    f, v = 3 * rng.normal(size=500), rng.normal(size=500)
    s = np.abs(rng.normal(size=500))
    r = 2.5
    ref = f - np.array([clip_loop([f[j] + r * v[j]], s[j])[0] for j in range(500)])
    np.testing.assert_allclose(coulomb_residual(f, v, s, r), ref, rtol=0, atol=1e-14)
    a, b = coulomb_derivative(f, v, s, r)
    stick = np.abs(f + r * v) < s
    np.testing.assert_array_equal(a, np.where(stick, 0.0, 1.0))
    np.testing.assert_array_equal(b, np.where(stick, -r, 0.0))


def test_bad_input_is_named():
    with pytest.raises(ValueError, match="slip force"):
        coulomb_residual([1.0], [1.0], -1.0, 1.0)
    with pytest.raises(ValueError, match="r must be"):
        project_coulomb(np.zeros(3), np.zeros(3), 1.0, 0.0)


def _random_case(H, seed):
    rng = np.random.default_rng(seed)
    decay = np.repeat(1.0 / np.arange(1, H + 1) ** 1.5, 2)
    f = np.concatenate([[0.2], rng.normal(size=2 * H) * decay])
    v = np.concatenate([[0.0], rng.normal(size=2 * H) * decay])
    return f, v


@pytest.mark.parametrize("H,seed,s", [(1, 0, 0.4), (3, 1, 0.5), (7, 2, 0.3), (7, 3, 0.0), (12, 4, 0.8)])
def test_exact_projection_against_quadrature(H, seed, s):
    f, v = _random_case(H, seed)
    r = 1.3
    R, dR_df, dR_dv, slip = project_coulomb(f, v, s, r)
    proj, J_stick = project_clip(f + r * v, s)
    # both are exact up to round-off of O(|p|) sums over 2H+1 terms and the roots' round-off
    scale = np.abs(f).sum() + r * np.abs(v).sum() + s
    np.testing.assert_allclose(R, f - proj, rtol=0, atol=200 * EPS * scale)
    np.testing.assert_allclose(dR_df, np.eye(2 * H + 1) - J_stick, rtol=0, atol=1e-12)
    np.testing.assert_allclose(dR_dv, -r * J_stick, rtol=0, atol=1e-12 * r)
    assert slip == pytest.approx(1.0 - J_stick[0, 0], abs=1e-12)


@pytest.mark.parametrize("H,seed", [(2, 5), (5, 6), (9, 7)])
def test_jacobian_against_central_differences(H, seed):
    """Central differences D(h) = J + c h² + O(ε|R|/h): the truncation part is estimated by
    Richardson, (D(2h) − D(h))/3, the round-off part by 64 ε max|R| / h; the exact Jacobian
    must agree within the sum (doubled)."""
    f, v = _random_case(H, seed)
    s, r = 0.5, 0.9
    _, A, B, _ = project_coulomb(f, v, s, r)
    J = np.hstack([A, B])
    x0 = np.concatenate([f, v])
    n = len(f)

    def R(x):
        return project_coulomb(x[:n], x[n:], s, r)[0]

    def central(h):
        D = np.empty((n, 2 * n))
        for j in range(2 * n):
            e = np.zeros(2 * n)
            e[j] = h
            D[:, j] = (R(x0 + e) - R(x0 - e)) / (2 * h)
        return D

    h = 1e-5
    D1, D2 = central(h), central(2 * h)
    trunc = np.abs(D2 - D1).max() / 3
    roundoff = 64 * EPS * (np.abs(R(x0)).max() + np.abs(x0).max()) / h
    err = np.abs(D1 - J).max()
    assert err <= 2 * (trunc + roundoff), (err, trunc, roundoff)
    assert err < 1e-6


def test_sampled_projection_approaches_the_exact_one():
    f, v = _random_case(4, 8)
    s, r = 0.4, 1.0
    exact = project_coulomb(f, v, s, r)[0]
    errs = [np.abs(project_coulomb(f, v, s, r, exact=False, n_samples=n)[0] - exact).max()
            for n in (64, 1024, 16384)]
    assert errs[2] < errs[0] and errs[2] < 1e-5


def test_full_stick_and_free_slip_limits():
    H = 3
    f, v = _random_case(H, 9)
    r = 1.0
    p = f + r * v
    big = 10 * (np.abs(p).sum())
    R, A, B, slip = project_coulomb(f, v, big, r)
    np.testing.assert_allclose(R, -r * v, atol=1e-14)  # clip(p) = p
    assert slip == 0.0 and np.all(A == 0.0)
    R0, A0, _, slip0 = project_coulomb(f, v, 0.0, r)  # s = 0: clip = 0, R = f
    np.testing.assert_allclose(R0, f, atol=1e-14)
    assert slip0 == pytest.approx(1.0)


def test_derivative_matrix_differentiates_a_series():
    H = 4
    c = np.random.default_rng(2).normal(size=2 * H + 1)
    tau = np.linspace(0, 2 * np.pi, 7)
    h = 1e-6
    fd = (synth(c, tau + h) - synth(c, tau - h)) / (2 * h)
    np.testing.assert_allclose(synth(derivative_matrix(H) @ c, tau), fd, atol=1e-8)


# ---------------------------------------------------------------------- displacement level
def _smooth_case(H, seed, mean=0.1):
    rng = np.random.default_rng(seed)
    return np.concatenate([[mean], rng.normal(size=2 * H) / np.repeat(np.arange(1, H + 1) ** 2, 2)])


@pytest.mark.parametrize("H,seed,s", [(1, 0, 0.3), (5, 1, 0.3), (5, 2, 0.05), (9, 3, 0.02), (4, 4, 5.0),
                                      (3, 5, 0.0)])
def test_play_projection_against_the_sampled_play_operator(H, seed, s):
    """The clamp recursion on 2^17 samples per period is exact on the sampled polyline: its
    error is O(h² max|y″|) at each of the few switches, h = 2π/2^17 (~2e-9 relative)."""
    y = _smooth_case(H, seed)
    r = 1.7
    g, _, slip = project_coulomb_play(y, s, r)
    ref = play_force_sampled(y, s, r)
    scale = r * np.abs(y).sum() + s
    np.testing.assert_allclose(g, ref, rtol=0, atol=1e-7 * scale)
    if s == 5.0:
        assert slip == 0.0  # sticks throughout, in the symmetric position: mean force zero
        assert g[0] == pytest.approx(0.0, abs=1e-15)


@pytest.mark.parametrize("H,seed,s", [(3, 6, 0.2), (6, 7, 0.05), (10, 8, 0.1), (4, 9, 3.0)])
def test_play_jacobian_against_central_differences(H, seed, s):
    """As for the velocity form: Richardson estimate of the truncation error plus the
    round-off bound 64 ε max|g| / h."""
    y = _smooth_case(H, seed)
    r = 0.8
    g0, J, _ = project_coulomb_play(y, s, r)
    n = len(y)

    def central(h):
        D = np.empty((n, n))
        for j in range(n):
            e = np.zeros(n)
            e[j] = h
            D[:, j] = (project_coulomb_play(y + e, s, r)[0] - project_coulomb_play(y - e, s, r)[0]) / (2 * h)
        return D

    h = 1e-5
    D1, D2 = central(h), central(2 * h)
    trunc = np.abs(D2 - D1).max() / 3
    roundoff = 64 * EPS * (np.abs(g0).max() + r * np.abs(y).max()) / h
    err = np.abs(D1 - J).max()
    assert err <= 2 * (trunc + roundoff), (err, trunc, roundoff)
    assert err < 1e-6
