"""The exact comparison (validation/corpus_exact.py): the definition's frequency band
decides whether an exact orbit is the first mode's, and ``accuracy`` compares a tolerance
backbone, explained by its own estimate."""

import math
import warnings

import numpy as np

from mmshbm import exact
from mmshbm.methods.backbone import backbone
from validation import corpus_exact as ce


def test_an_exact_orbit_above_the_held_contact_mode_is_not_the_first_modes():
    """Chain 88 of seed 23: the single-contact exact orbit found from the linear mode's
    shape at 1.3 gaps holds the fundamental's majority (share ~1) but rings at 1.837 Hz,
    above the first mode with the contact held (1.834 Hz, the band's top); the branch is
    the first mode's (0.77 Hz). The band excludes the exact orbit: the miss is explained."""
    case = ce.chains(89, seed=23)[88]
    model = case.model()
    A = 1.3 * model.gap
    orbit = exact.periodic_orbit(model, A)
    assert orbit.converged and orbit.n_contacts == 1 and orbit.fundamental_share() >= 0.5
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        b = backbone(model, harmonics=8, max_amplitude=0.5 * model.gap)  # below grazing: the linear mode
    lo, hi = ce._band(b)
    assert lo == b.frequency[0] and hi < orbit.frequency < 1.01 * hi  # outside only without the slack
    r = ce.ExactComparison(case, True, float(orbit.frequency), 0.767, "", 1, 0.0, [], band=(lo, hi),
                           exact_share=orbit.fundamental_share())
    assert not r.in_band
    assert any("outside the first mode's band" in e for e in r.explanations())
    inside = ce.ExactComparison(case, True, 0.5 * (lo + hi), 0.767, "", 1, 0.0, [], band=(lo, hi),
                                exact_share=1.0)
    assert inside.in_band and not inside.explanations()


def test_the_comparison_runs_a_tolerance_backbone_with_its_own_estimate():
    """Chain 8 of seed 0 (error 3e-2 at H = 10 at 1.3 gaps): with ``accuracy = 1e-4`` the
    comparison runs ``backbone(tol=1e-4)``; its own estimate at the amplitude meets the
    tolerance, no tolerance_not_met, and the frequency is within 3 × tol of the exact."""
    case = ce.chains(9, seed=0)[8]
    r = ce.compare(case, accuracy=1e-4)
    assert r.clean and r.tolerance == 1e-4 and not r.tolerance_not_met
    assert math.isfinite(r.estimate) and r.estimate <= 1e-4
    assert r.error <= 3e-4
    assert np.isnan(r.branch_2h)  # no fixed-H run at 2H
