"""The amplitude peak of a cosine series (mmshbm.core.measures._cosine_peak): its value
against a dense brute-force search, its maximiser's cosines against the envelope theorem's
gradient (finite differences), and the cases that trap a sampled search: two maxima of
nearly equal height and a constant series."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from mmshbm.core.measures import _cosine_peak, peak_grid
from tests.finite_differences import assert_derivative
from tests.roundoff import EPS, assert_roundoff_close

#: the dense grid of the brute-force search (2^16 samples)
DENSE = 1 << 16


def _series(row, tau):
    """q(τ) = Σ_k row_k cos kτ by direct evaluation (shape of ``tau``)."""
    k = np.arange(len(row))
    return np.cos(np.multiply.outer(np.atleast_1d(tau), k)) @ row


def _brute_force_peak(row, sign, every=False):
    """Largest sign·q (|q| for sign 0) on DENSE samples, each local maximum within the dense
    sampling error of the largest refined by a bounded Brent search to 1e-13 in τ (the 16
    largest of them, or with ``every`` all)."""
    tau = 2 * np.pi * np.arange(DENSE) / DENSE
    y = _series(row, tau)
    y = np.abs(y) if sign == 0 else sign * y
    h = 2 * np.pi / DENSE
    drop = h * h / 8 * np.sum(np.arange(len(row)) ** 2 * np.abs(row))
    local = (y >= np.roll(y, 1)) & (y >= np.roll(y, -1)) & (y >= y.max() - drop - 1e-14 * np.abs(row).sum())
    best = y.max()
    idx = np.flatnonzero(local)
    for i in (idx if every else idx[np.argsort(y[idx])[::-1][:16]]):
        def minus(t):
            q = _series(row, t)[0]
            return -(abs(q) if sign == 0 else sign * q)
        r = minimize_scalar(minus, bounds=(tau[i] - h, tau[i] + h), method="bounded",
                            options={"xatol": 1e-13})
        best = max(best, -r.fun)
    return best


def _tolerance_scale(row):
    """Σ_k |row_k| (1 + 2πk): the terms' size, with the rounding of the argument kτ (τ up
    to 2π) that moves cos kτ by up to ε·kτ."""
    k = np.arange(len(row))
    return float(np.sum(np.abs(row) * (1 + 2 * np.pi * k)))


def _peak(row, sign, n_fine=None):
    H = len(row) - 1
    cos_k = np.empty(H + 1)
    value, s = _cosine_peak(row, float(sign), cos_k, n_fine)
    return value, s, cos_k


@pytest.mark.parametrize("H", [1, 2, 3, 5, 8, 16, 31, 64, 128])
@pytest.mark.parametrize("sign", [0, 1, -1])
def test_the_peak_is_the_dense_search_maximum_to_round_off(H, sign):
    """Random series with coefficients decaying as 1/k (a contact orbit's content), H = 1…128:
    the peak equals the brute-force maximum within the round-off of H + 1 terms, and
    value = s·Σ row_k cos_k (the cosines of one τ*)."""
    rng = np.random.default_rng(1000 * H + sign + 1)
    row = rng.standard_normal(H + 1) / (1.0 + np.arange(H + 1))
    value, s, cos_k = _peak(row, sign)
    want = _brute_force_peak(row, sign)
    assert_roundoff_close(value, want, _tolerance_scale(row), terms=H + 3, err_msg=f"H={H} sign={sign}")
    assert s in (1.0, -1.0) and (sign == 0 or s == sign)
    chebyshev = np.polynomial.chebyshev.chebvander(cos_k[1], H)  # cos kτ = T_k(cos τ)
    k = np.arange(H + 1)
    assert np.all(np.abs(cos_k - chebyshev) <= 100 * (k**2 + 1) * EPS), (cos_k, chebyshev)  # |T_k'| <= k²
    assert_roundoff_close(value, s * row @ cos_k, np.abs(row).sum(), terms=H + 3)


@pytest.mark.parametrize("delta", [1e-7, 1e-10])
def test_the_higher_of_two_nearly_equal_maxima_wins(delta):
    """q = −cos 3τ + δ cos τ on 512 samples: maxima 1 − δ at τ = π (a sample, exactly) and
    ≈ 1 + δ/2 at τ ≈ π/3 (between samples, its nearest one 7e-5 lower): the peak is the
    higher, off-grid one (the brute-force maximum to round-off, above 1 + 0.4δ); the
    best sample alone would give 1 − δ."""
    row = np.array([0.0, delta, 0.0, -1.0])
    value, s, cos_k = _peak(row, 1, 512)
    assert value > 1 + 0.4 * delta
    assert_roundoff_close(value, _brute_force_peak(row, 1), _tolerance_scale(row), terms=6)
    assert abs(cos_k[1] - 0.5) < 1e-6  # τ* ≈ ±π/3


@pytest.mark.parametrize("constant", [2.5, -0.75, 0.0])
def test_a_constant_series_peaks_at_its_value(constant):
    """row = (c, 0, …, 0): every τ is a maximiser; the peak is |c| (sign 0), ±c (sign ±1)
    exactly, and cos_k is the cosines of one τ (cos 0 = 1 first)."""
    row = np.zeros(9)
    row[0] = constant
    for sign, want in ((0, abs(constant)), (1, constant), (-1, -constant)):
        value, s, cos_k = _peak(row, sign)
        assert value == want and cos_k[0] == 1.0
        assert np.all(np.abs(cos_k) <= 1.0)


@pytest.mark.parametrize("H", [3, 20, 64])
def test_the_cosines_at_the_maximiser_are_the_peak_gradient(H):
    """Envelope theorem: ∂(peak)/∂row = s·cos kτ*, checked by finite differences of the
    peak along a random direction of the coefficients."""
    rng = np.random.default_rng(H)
    row = rng.standard_normal(H + 1) / (1.0 + np.arange(H + 1))
    direction = rng.standard_normal(H + 1) / (1.0 + np.arange(H + 1))
    value, s, cos_k = _peak(row, 0)
    assert_derivative(lambda t: np.array([_peak(row + t * direction, 0)[0]]),
                      np.array([s * direction @ cos_k]), 1e-3, name=f"peak gradient H={H}")


def test_a_grid_too_coarse_for_the_series_is_refused():
    """n_fine < 2(H + 1) cannot sample the series; the error names n_fine."""
    with pytest.raises(ValueError, match="n_fine"):
        _cosine_peak(np.ones(9), 0.0, np.empty(9), 10)


def test_the_default_grid_has_16_samples_per_period_of_the_highest_harmonic():
    """peak_grid(H): a power of two, >= 16(H + 1) and >= 64, below twice either bound."""
    for H in (0, 1, 3, 4, 7, 31, 63, 64, 128):
        n = peak_grid(H)
        assert n & (n - 1) == 0 and n >= 16 * (H + 1) and n >= 64
        assert n < 2 * max(16 * (H + 1), 64)


def _refined_largest(row, sign, n, count):
    """Largest sign·q after a bounded Brent search from each of the ``count`` largest
    sampled local maxima on n samples (a capped candidate list)."""
    tau = 2 * np.pi * np.arange(n) / n
    y = sign * _series(row, tau)
    idx = np.flatnonzero((y >= np.roll(y, 1)) & (y >= np.roll(y, -1)))
    h = 2 * np.pi / n
    best = y.max()
    for i in idx[np.argsort(y[idx])[::-1][:count]]:
        r = minimize_scalar(lambda t: -sign * _series(row, t)[0], bounds=(tau[i] - h, tau[i] + h),
                            method="bounded", options={"xatol": 1e-13})
        best = max(best, -r.fun)
    return best


@pytest.mark.parametrize("delta", [1e-9, 1e-7])
@pytest.mark.parametrize(("H", "m"), [(31, 29), (64, 61), (64, 37)])
def test_a_dwell_with_many_near_equal_maxima_peaks_at_the_largest(H, m, delta):
    """A dwell-like row q = cos mτ − δ cos τ (m odd): m maxima of height 1 ± δ, the highest
    two beside τ = π and off the grid, the others' samples closer to their tops by up to
    the sampling error (h²m²/8 ≈ 1e-2 on the default grid, far above δ): the peak is the
    brute-force maximum on 2^16 samples, every local maximum refined, to round-off, while
    refining only the 8 largest sampled maxima misses it by 3–14 % of δ (far above round-off)."""
    row = np.zeros(H + 1)
    row[m], row[1] = 1.0, -delta
    want = _brute_force_peak(row, 1, every=True)
    assert want - _refined_largest(row, 1, peak_grid(H), 8) > 0.02 * delta  # a capped search misses
    for sign in (1, 0):
        value, s, cos_k = _peak(row, sign)
        assert_roundoff_close(value, want, _tolerance_scale(row), terms=H + 3, err_msg=f"H={H} sign={sign}")
        assert_roundoff_close(value, s * row @ cos_k, np.abs(row).sum(), terms=H + 3)
        assert abs(abs(cos_k[1]) - abs(np.cos(np.pi * (1 - 1 / m)))) < 1e-3  # next to τ = π


@pytest.mark.parametrize("H", [1, 8, 31, 64])
def test_the_monitor_series_peak_is_the_dense_search_maximum(H):
    """_series_peak (cosine and sine terms, on a table of 16H samples as the monitor's):
    the dense brute-force maximum of g = c_0 + Σ (c_k cos kτ + s_k sin kτ) to round-off,
    also for the dwell-like g = cos mτ − δ cos τ of the test above (m = H − 2, odd)."""
    from mmshbm.core.measures import _series_peak

    rng = np.random.default_rng(H)
    N = max(64, 16 * H)
    tau = 2 * np.pi * np.arange(N) / N
    k = np.arange(H + 1)
    cos_t, sin_t = np.cos(np.outer(k, tau)), np.sin(np.outer(k, tau))
    rows = [(rng.standard_normal(H + 1) / (1.0 + k), rng.standard_normal(H + 1) / (1.0 + k))]
    if H > 4:
        m = H - 2 if H % 2 else H - 3
        c = np.zeros(H + 1)
        c[m], c[1] = 1.0, -1e-8
        rows.append((c, np.zeros(H + 1)))
    dense = 2 * np.pi * np.arange(DENSE) / DENSE
    for c, s in rows:
        s = s.copy()
        s[0] = 0.0
        value = _series_peak(c, s, cos_t, sin_t, np.empty(N))
        def g(t, c=c, s=s):
            return (np.cos(np.multiply.outer(np.atleast_1d(t), k)) @ c
                    + np.sin(np.multiply.outer(np.atleast_1d(t), k)) @ s)

        y = g(dense)
        h = 2 * np.pi / DENSE
        best = y.max()
        for i in np.flatnonzero((y >= np.roll(y, 1)) & (y >= np.roll(y, -1)) & (y >= y.max() - 1e-6)):
            r = minimize_scalar(lambda t, g=g: -g(t)[0], bounds=(dense[i] - h, dense[i] + h),
                                method="bounded", options={"xatol": 1e-13})
            best = max(best, -r.fun)
        scale = _tolerance_scale(c) + _tolerance_scale(s)
        assert_roundoff_close(value, best, scale, terms=H + 3, err_msg=f"H={H}")
