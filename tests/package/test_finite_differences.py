"""The finite-difference check used by the Jacobian tests: it passes a right derivative
whatever the evaluation noise, fails a wrong one, and refuses a kink inside its step."""

from __future__ import annotations

import numpy as np
import pytest
from finite_differences import assert_derivative, noise_level

_RNG = np.random.default_rng(0)


def _cancelling(s, noise=0.0):
    """f(s) = (big + sin(1 + s)) − big: a derivative of size 1 under round-off of ε·big."""
    big = 1e9
    return np.array([(big + np.sin(1 + s)) - big, np.exp(s)]) + noise * _RNG.standard_normal(2)


def test_noise_level_measures_added_noise():
    table = np.stack([_cancelling(i * 1e-8, noise=1e-6) for i in range(33)])
    sigma = noise_level(table)
    assert 0.5e-6 < sigma.min() and sigma.max() < 2e-6


def test_right_derivative_passes_under_cancellation():
    # ε·big/h ≈ 1e-3 for h = 1e-4: a fixed 1e-6 tolerance would fail a right derivative here
    assert_derivative(_cancelling, np.array([np.cos(1.0), 1.0]), 1e-2, rtol_cap=1e-4)


def test_wrong_derivative_fails():
    # 1e-7 relative: ten times below the fixed tolerance these checks had before
    with pytest.raises(AssertionError, match="entry"):
        assert_derivative(_cancelling, np.array([np.cos(1.0), 1.0 + 1e-7]), 1e-2, rtol_cap=1e-4)


def test_kink_inside_the_step_is_refused():
    with pytest.raises(AssertionError, match="cannot check"):
        assert_derivative(lambda s: np.array([abs(s + 1e-12) * 1e6]), np.array([1e6]), 1e-3)
