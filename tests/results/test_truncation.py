"""Branch.truncation_error against the true error: the closed-form one-DOF oscillator and
exact single-contact orbits of small chains (mmshbm.exact); ratios estimate / true error
measured on these models are quoted per test, the tolerances leave a margin around them."""

import math
import warnings

import numpy as np
import pytest

import mmshbm
from mmshbm.results.truncation import _estimate
from validation import corpus_exact as ce


def _ratios(model, harmonics, gaps):
    out = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for H in harmonics:
            b = mmshbm.backbone(model, harmonics=H, max_amplitude=1.1 * max(gaps) * model.gap)
            for a in gaps:
                est = b.truncation_error(a, unit="gap")
                exact = mmshbm.exact.periodic_orbit(model, a * model.gap).frequency
                true = abs(est.frequency[0] / exact - 1)
                assert est.frequency[0] == pytest.approx(b.frequency_at(a, unit="gap"), rel=1e-12)
                out.append((H, a, est, est.error / true))
    return out


def test_extrapolation_recovers_an_algebraic_series():
    """f = f_∞ + C H^−p at H, 2H, 4H: rate and limit exact to round-off; an oscillating
    series is flagged and gets twice its spread."""
    for p in (1.0, 2.5, 4.0):
        f = tuple(3.0 + 0.2 * H ** -p for H in (10, 20, 40))
        est = _estimate(1.0, (10, 20, 40), f, 1.0, 2.0, "")
        assert est.asymptotic and est.rate == pytest.approx(p, rel=1e-9)
        assert est.limit == pytest.approx(3.0, rel=1e-12)
        assert est.error == pytest.approx(0.2 * 10 ** -p / 3.0, rel=1e-7)
    est = _estimate(1.0, (10, 20, 40), (3.0, 3.01, 3.005), 1.0, 2.0, "")
    assert not est.asymptotic and est.error == pytest.approx(2 * 0.01 / 3.0)


def test_tracks_the_stiff_oscillators_error():
    """Stiff stop (k2/k1 = 100): the series converges algebraically (p = 2.7–4.4) and the
    estimate is the true error to 0.99–1.01 at H = 10, 20, 31 and 1.3–3 gaps."""
    model = mmshbm.OneDofOscillator(2.5, 3, 300, 0.01).model()
    for H, a, est, ratio in _ratios(model, (10, 20, 31), (1.3, 2.0, 3.0)):
        assert est.asymptotic, (H, a, est)
        assert 0.8 <= ratio <= 1.25, (H, a, est, ratio)


def test_bounds_the_soft_oscillators_error():
    """Soft stop (k2/k1 = 4): the error is small and the steps in H change sign at several
    amplitudes (no algebraic regime); the estimate is 0.92–8.7 times the true error at
    H = 5, 10, 20, 31 and 1.3–3 gaps."""
    model = mmshbm.OneDofOscillator(1, 1, 4, 1).model()
    for H, a, est, ratio in _ratios(model, (5, 10, 20, 31), (1.3, 2.0, 3.0)):
        assert 0.8 <= ratio <= 10, (H, a, est, ratio)


@pytest.mark.parametrize("index", [4, 8, 22])
def test_tracks_the_error_on_chains(index):
    """Chains of seed 0 of corpus_exact, 1.3 gaps, whose error at H = 10 is 7e-4–3e-2:
    estimate / true error 0.96–1.06 at H = 10 and 31 (all asymptotic)."""
    model = ce.chains(index + 1, seed=0)[index].model()
    for H, a, est, ratio in _ratios(model, (10, 31), (1.3,)):
        assert est.asymptotic, (H, a, est)
        assert 0.8 <= ratio <= 1.25, (H, a, est, ratio)


def test_the_missing_chain_follows_a_stable_orbit_with_three_contacts():
    """Chain 38 of seed 0 at 1.3 gaps: the H = 31 branch is 2.8e-3 from the single-contact
    orbit and 5.0e-3 at H = 62, because it converges in H to another orbit. The
    single-contact orbit there is unstable (a Floquet multiplier −1.51, a period doubling
    near the 10:1 resonance with the second mode), the branch follows a stable orbit that
    closes the contact three times per period and whose largest excursion is not at its
    turning point (0.54 gaps there): the exact orbit through the H = 124 point is 8e-5
    from it. The branch says so itself: its estimate at H = 31 is 4.4e-3 (>= 1e-3; H = 62
    and 124 agree to 2.6e-5, the steps change sign) and its orbit closes three times."""
    model = ce.chains(39, seed=0)[38].model()
    g, A = model.gap, 1.3 * model.gap
    single = mmshbm.exact.periodic_orbit(model, A)
    assert single.converged and single.n_contacts == 1
    assert np.abs(single.multipliers).max() > 1.4
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        b = mmshbm.backbone(model, harmonics=31, max_amplitude=1.2 * A)
        est = b.truncation_error(A)
        assert est.error >= 1e-3 and not est.asymptotic
        assert ce.contact_closings(b, A) == 3
        b4 = mmshbm.backbone(model, harmonics=124, max_amplitude=1.35 * g)
        point = b4.solve_at([A])
    assert point.frequency[0] == pytest.approx(est.frequency[2], rel=1e-8)
    n = 4096
    _, q = point.time_signals(0, n_samples=n)
    turning = -model.stop_side * q[model.contact_dof, n // 2]
    assert 0.5 * g < turning < 0.6 * g
    other = mmshbm.exact.periodic_orbit(model, turning, guess=(q[model.l, n // 2], 0.5 / point.frequency[0]))
    assert other.converged and other.n_contacts == 3
    assert abs(other.max_excursion / A - 1) < 2e-3
    assert np.abs(other.multipliers).max() < 1 + 1e-6
    assert abs(point.frequency[0] / other.frequency - 1) < 3e-4
    assert abs(point.frequency[0] / single.frequency - 1) > 4e-3


def test_refuses_branches_without_harmonics():
    model = mmshbm.OneDofOscillator(1, 1, 4, 1).model()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        b = mmshbm.backbone(model, harmonics=5, max_amplitude=2.0)
    with pytest.raises(ValueError, match="no point"):
        b.truncation_error(5.0)
    with pytest.raises(ValueError, match="factors"):
        b.truncation_error(1.5, factors=(1,))
    assert math.isfinite(float(b.truncation_error(1.5)))


def test_a_miss_is_explained_by_the_estimate_beyond_the_tolerance():
    """corpus_exact's rule: a miss is explained when the branch's estimate at the amplitude
    is at least the comparison tolerance, or its orbit closes more than once, or it
    reports something there."""
    case = ce.chains(1, seed=0)[0]
    miss = ce.ExactComparison(case, True, 1.0, 1.002, "bound:amplitude", 1, 0.0, [])
    assert not miss.explained
    assert ce.ExactComparison(case, True, 1.0, 1.002, "", 1, 0.0, [], estimate=1.5e-3).explained
    assert not ce.ExactComparison(case, True, 1.0, 1.002, "", 1, 0.0, [], estimate=5e-4).explained
    assert ce.ExactComparison(case, True, 1.0, 1.002, "", 1, 0.0, [], estimate=5e-4).reasons(tol=4e-4)
    assert ce.ExactComparison(case, True, 1.0, 1.002, "", 1, 0.0, [], branch_contacts=3).explained
    assert ce.ExactComparison(case, True, 1.0, 1.002, "", 1, 0.0, [], reported="skipped").explained
