"""The fundamental share of exact orbits, and which orbit is the mode's where the
single-contact orbit is an internal resonance's.

``PeriodicOrbit.fundamental_share`` measures the exact motion as the harmonic-balance
branches measure theirs (kinetic energy in harmonic 1 over all harmonics): checked on
the linear motion (exactly one), against MMS-HBM converging in H on a one-mass chain,
and on a corpus chain whose single-contact orbit at 1.3 gaps sits on a 2:1 resonance
with its second mode while the default branch follows the exact orbit with the
fundamental's majority (validation.corpus_exact).
"""

import warnings

import numpy as np
import pytest
from test_classical_hbm import chain

import mmshbm
from mmshbm import exact
from validation import corpus_exact


def test_a_motion_without_contact_is_all_fundamental():
    model = chain((1.0, 0.2), (100.0, 2000.0), 4.0e4)
    orbit = exact.periodic_orbit(model, 0.9 * model.gap)
    assert orbit.n_contacts == 0
    # the first linear mode: harmonics 2.. hold round-off only
    assert orbit.fundamental_share() == pytest.approx(1.0, abs=1e-12)


def test_harmonic_balance_converges_to_the_exact_share():
    """One mass, contact spring ~900 times the structure's, 1.3 gaps: the share of the
    exact motion (0.911) is what MMS-HBM's record converges to as H grows (its
    truncation: 1.0e-3 at H = 31, 1.9e-5 at 62, 7e-7 at 124); sampling the exact motion
    with 2048 or 8192 points changes it by 2e-8."""
    model = chain((2.0027,), (38.071,), 33749.83)
    A = 1.3 * model.gap
    orbit = exact.periodic_orbit(model, A)
    share = orbit.fundamental_share()
    assert share == pytest.approx(orbit.fundamental_share(8192), abs=1e-7)
    errors = []
    for H in (31, 124):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            branch = mmshbm.backbone(model, harmonics=H, max_amplitude=1.05 * A, r="residual")
        errors.append(abs(branch.solve_at([A]).records["fundamental_share"][0] - share))
    assert errors[1] < 1e-5
    assert errors[1] < errors[0] / 100


def test_the_branch_is_the_modes_orbit_where_the_single_contact_orbit_resonates():
    """Seed 31's chain #163 (four masses, contact spring drawn over the structure's
    decades): the single-contact orbit found from the linear mode at 1.3 gaps holds 18 %
    of its kinetic energy in the fundamental (its frequency 0.78615 Hz is half the second
    linear mode's, 1.5748 Hz: a 2:1 resonance, which the exact backbone from grazing
    climbs). The default branch jumps that tongue and reaches 1.3 gaps at 0.88460 Hz,
    on an exact orbit with 93 % in the fundamental, found by shooting from the branch's
    own point, 5e-5 from it (the truncation at H = 31)."""
    case = corpus_exact.chains(164, seed=31, contact_decades=(1, 5))[163]
    result = corpus_exact.compare(case, options={"r": "residual"})
    assert result.clean
    assert result.error > 0.1  # not the single-contact orbit from the linear mode
    assert result.exact_share < 0.25
    f2 = case.model().linear_frequencies(2)[1]
    assert 2 * result.exact == pytest.approx(f2, rel=0.01)
    assert result.family_share > 0.9
    assert abs(result.branch / result.family_exact - 1) < 2e-4
    assert result.resonant and result.first_mode
    assert np.isfinite(result.continued)


def test_the_branch_is_the_modes_orbit_past_the_tongue_the_continuation_climbs():
    """Seed 31's chain #16 (four masses): the single-contact orbit found
    from the linear mode's shape at 1.3 gaps is the third mode's (1.93159 Hz, the linear
    f₃ = 1.93155 Hz, all in its fundamental); the exact orbit continued from the first
    linear mode through grazing climbs a 4:1 tongue of that mode (0.48284 Hz = f₃/4, 1.2 %
    in the fundamental). The default branch jumps the tongue: at 1.3 gaps it is 6e-4 from
    the exact orbit found from its own point (0.56076 Hz, 90 % in the fundamental) with
    r = "residual"; with the static r 9.4e-3, which its truncation estimate (9.6e-3) says."""
    case = corpus_exact.chains(17, seed=31, contact_decades=(1, 5))[16]
    f = case.model().linear_frequencies(3)
    residual = corpus_exact.compare(case, options={"r": "residual"})
    assert residual.exact == pytest.approx(f[2], rel=1e-3) and residual.exact_share > 0.99
    assert 4 * residual.continued == pytest.approx(f[2], rel=1e-3) and residual.continued_share < 0.05
    assert residual.family_share > 0.85
    assert residual.resonant and residual.first_mode
    static = corpus_exact.compare(case)
    assert static.family_exact == pytest.approx(residual.family_exact, rel=1e-9)  # one exact orbit
    assert not static.first_mode
    assert static.estimate >= abs(static.branch / static.family_exact - 1) > 1e-3


def test_newton_does_not_report_the_vanishing_half_period_as_an_orbit():
    """v(0) = 0 = v(T/2) holds trivially as T/2 → 0. Started from the second open mode's
    shape at 4.9 Hz on a corpus chain (seed 55 #180), Newton slid to T/2 ~ 5e-26 s and
    reported a converged orbit of 9.7e24 Hz with no contact; no orbit turns back sooner
    than half a period of its fastest phase."""
    from mmshbm.methods.exact.system import PiecewiseLinearSystem
    from validation.corpus import generate

    model = generate(181, 55)[180].model()
    system = PiecewiseLinearSystem.of(model)
    x = system.open.modes[:, 1]
    x = x if system.amplitude_row @ x > 0 else -x
    orbit = exact.periodic_orbit(model, 2.2 * model.gap, guess=(x, 0.5 / 4.875), max_iter=40)
    fastest = max(float(ph.omega.max()) for ph in system._phases.values()) / (2 * np.pi)
    assert orbit.frequency > 1e20 * fastest  # the spurious root, reached
    assert not orbit.converged
