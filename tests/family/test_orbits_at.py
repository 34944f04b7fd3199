"""Branch.orbits_at: every orbit of the starting mode's family at one amplitude, the
backbone's first (mmshbm.results.orbits)."""

import dataclasses
import math
import warnings

import numpy as np
import pytest

import mmshbm
from mmshbm.core.pinned import solve_at_amplitude
from mmshbm.results.orbits import FAMILY_SHARE, Deflated, Orbit, OrbitsAt
from mmshbm.results.truncation import state_truncation_error
from tests.finite_differences import assert_derivative
from validation import corpus_exact as ce


def _backbone(model, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return mmshbm.backbone(model, **kw)


@pytest.fixture(scope="module")
def two_orbit_chain():
    """Random chain #130 of the exact comparison (seed 23; two masses, gap 1 cm, H = 31):
    at 1.3 gaps the default branch's orbit (fundamental share 0.69) lies 2.5 % below the
    exact single-contact orbit (share 0.96), which the branch never visits."""
    model = ce.chains(131, seed=23)[130].model()
    A = 1.3 * model.gap
    branch = _backbone(model, harmonics=31, max_amplitude=1.2 * A)
    return model, A, branch, mmshbm.exact.periodic_orbit(model, A)


def _matches(branch, orbit, f_exact: float) -> bool:
    """``orbit`` is the H = 31 orbit of the exact one of frequency ``f_exact`` (Hz): its
    frequency within its own truncation estimate (re-solved at 2H and 4H) of the exact
    one; where the series contracts algebraically, the extrapolated limit within the last
    step |f(4H) − f(2H)|."""
    est = state_truncation_error(branch, orbit.amplitude, orbit.frequency, orbit.state)
    if est.asymptotic:
        return abs(est.limit - f_exact) <= abs(est.frequency[2] - est.frequency[1])
    return abs(orbit.frequency / f_exact - 1) <= est.error


def test_the_exact_orbit_the_branch_never_visits_is_listed(two_orbit_chain):
    """The backbone's orbit first (the one frequency_at returns); the search lists the
    exact single-contact orbit's H = 31 counterpart, an orbit of the family (its share
    above one half), which the branch's own points do not reach."""
    model, A, b, exact = two_orbit_chain
    assert exact.converged and exact.n_contacts == 1 and exact.fundamental_share() > 0.9
    plain = b.orbits_at(A)
    found = b.orbits_at(A, search=True)
    for r in (plain, found):
        assert r[0].source == "backbone"
        assert r[0].frequency == pytest.approx(b.frequency_at(A), rel=1e-12)
    assert not any(_matches(b, o, exact.frequency) for o in plain)
    listed = [o for o in found if _matches(b, o, exact.frequency)]
    assert len(listed) == 1 and listed[0].source == "search"
    assert listed[0].fundamental_share >= FAMILY_SHARE
    # the backbone is another orbit of the family, 2.5 % lower: the exact orbit found by
    # shooting from the branch's own point (validation.corpus_exact.branch_orbit)
    f_branch_exact, share = ce.branch_orbit(model, b, A)
    assert share >= FAMILY_SHARE
    assert _matches(b, found[0], f_branch_exact)
    assert found[0].frequency / exact.frequency - 1 < -0.02


def test_an_orbit_of_the_path_beside_the_backbone_is_listed():
    """Random chain #168 of the exact comparison with contact springs of 10..1e5 N/m
    (seed 32): the backbone at 1.3 gaps holds 0.35 of its energy in the fundamental, 3.1 %
    below the exact single-contact orbit (share 0.89); a loop of the path crosses 1.3 gaps
    on the exact orbit's H = 31 counterpart, 0.56 % below it by truncation (the 2H and 4H
    re-solves extrapolate to the exact frequency)."""
    model = ce.chains(169, seed=32, contact_decades=(1, 5))[168].model()
    A = 1.3 * model.gap
    b = _backbone(model, harmonics=31, max_amplitude=1.2 * A)
    exact = mmshbm.exact.periodic_orbit(model, A)
    assert exact.converged and exact.n_contacts == 1
    r = b.orbits_at(A)
    assert r[0].source == "backbone" and r[0].frequency / exact.frequency - 1 < -0.02
    listed = [o for o in r if _matches(b, o, exact.frequency)]
    assert len(listed) == 1 and listed[0].source == "branch"
    assert listed[0].fundamental_share >= FAMILY_SHARE


def test_orbits_are_frozen_records_in_their_order_and_units(two_orbit_chain):
    """An Orbit cannot be changed (nor its state); the list is the backbone's, then the
    branch's, then the search's, each in increasing frequency; the amplitude in gaps is
    the amplitude in m times the gap (the same solves)."""
    model, A, b, _ = two_orbit_chain
    r = b.orbits_at(1.3, unit="gap", search=True)
    assert isinstance(r, OrbitsAt) and r.amplitude == 1.3 * model.gap and r.reason == ""
    o = r[0]
    assert isinstance(o, Orbit) and o.amplitude == r.amplitude
    with pytest.raises(dataclasses.FrozenInstanceError):
        o.frequency = 1.0
    with pytest.raises(ValueError):
        o.state[0] = 0.0
    sources = [x.source for x in r]
    assert sources == sorted(sources, key=["backbone", "branch", "search"].index)
    for s in ("branch", "search"):
        f = [x.frequency for x in r if x.source == s]
        assert f == sorted(f)
    same = b.orbits_at(1.3 * model.gap, search=True)
    assert [x.frequency for x in same] == [x.frequency for x in r]
    np.testing.assert_array_equal(r.frequencies, [x.frequency for x in r])
    # every listed orbit solves the equations at the amplitude
    for x in r:
        assert np.abs(b.solver.residual(x.state)).max() < 1e-8
        assert b.solver.monitor(x.state)["amplitude"] == pytest.approx(A, rel=1e-9)


def test_a_known_orbit_is_never_listed_twice(two_orbit_chain):
    """No two listed or rejected orbits are the same; the deflated Newton started on the
    backbone's own orbit does not return it."""
    model, A, b, _ = two_orbit_chain
    r = b.orbits_at(A, search=True)
    everything = [o.frequency for o in r] + list(r.rejected)
    for i, f in enumerate(everything):
        for g in everything[i + 1:]:
            assert abs(f / g - 1) > 1e-7
    backbone = r[0]
    try:
        u = solve_at_amplitude(Deflated(b.solver, [backbone.state]), backbone.state, A, max_iter=30)[0]
    except ArithmeticError:
        return
    assert abs(b.solver.monitor(u)["frequency"] / backbone.frequency - 1) > 1e-7


class _TwoRoots:
    """R(u) = u₀² − 1 in two unknowns, amplitude u₁: at a pinned amplitude the roots are
    u₀ = ±1."""

    n_unknowns = 2

    def residual(self, u):
        return np.array([u[0] ** 2 - 1.0])

    def residual_and_jacobian(self, u):
        return self.residual(u), np.array([[2 * u[0], 0.0]])

    def monitor(self, u):
        return {"amplitude": float(u[1]), "frequency": 1.0}


def test_deflation_sends_newton_to_the_other_root():
    """From next to the root u₀ = 1, Newton returns it; deflated at it, the other root
    u₀ = −1. The deflated Jacobian is the derivative of the deflated residual."""
    problem = _TwoRoots()
    start = np.array([0.8, 0.5])
    plain = solve_at_amplitude(problem, start, 0.5, max_iter=40)[0]
    assert plain[0] == pytest.approx(1.0, abs=1e-9)
    deflated = Deflated(problem, [np.array([1.0, 0.5])])
    other = solve_at_amplitude(deflated, start, 0.5, max_iter=40)[0]
    assert other[0] == pytest.approx(-1.0, abs=1e-9) and other[1] == pytest.approx(0.5, abs=1e-9)
    u, d = np.array([0.3, 0.7]), np.array([0.6, -0.8])
    _, J = deflated.residual_and_jacobian(u)
    assert_derivative(lambda s: deflated.residual(u + s * d), J @ d, 1e-3, name="deflated Jacobian")


def test_bad_amplitudes_are_refused_or_answered_with_a_reason():
    """A non-positive or non-finite amplitude, or an unknown unit, is a ValueError naming
    it; an amplitude beyond the branch gets no orbit, a reason and a BranchWarning; a
    search on a solver that records no fundamental share (shooting, penalty-HBM) is
    refused, its backbone's orbit listed without it."""
    model = mmshbm.OneDofOscillator(1, 1, 4, 1).model()
    b = _backbone(model, harmonics=5, max_amplitude=3.0)
    for bad in (0.0, -1.0, math.nan):
        with pytest.raises(ValueError, match="amplitude"):
            b.orbits_at(bad)
    with pytest.raises(ValueError, match="unit"):
        b.orbits_at(1.0, unit="mm")
    with pytest.warns(mmshbm.BranchWarning, match="outside"):
        r = b.orbits_at(30.0)
    assert len(r) == 0 and "outside" in r.reason
    r = b.orbits_at(2.0, search=True)
    assert len(r) >= 1 and r[0].source == "backbone" and r[0].frequency == pytest.approx(b.frequency_at(2.0))
    for method in ("shooting", "penalty"):  # no fundamental share to search by: refused
        other = _backbone(model, method=method, harmonics=5, max_amplitude=3.0)
        with pytest.raises(ValueError, match="search"):
            other.orbits_at(2.0, search=True)
        plain = other.orbits_at(2.0)
        assert len(plain) == 1 and plain[0].source == "backbone"
        assert plain[0].frequency == pytest.approx(other.frequency_at(2.0), rel=1e-12)


def test_the_exact_comparison_explains_a_miss_by_three_computed_facts():
    """A miss (error > 1e-3) is explained by the exact orbit listed, its share below one
    half, or a truncation estimate of at least a third of the difference; nothing else,
    and a case within 1e-3 needs no explanation."""
    case = ce.chains(1, seed=0)[0]

    def comparison(**kw):
        return ce.ExactComparison(case, True, 1.0, 0.97, "bound:amplitude", 1, 0.0, [], **kw)

    assert ce.ExactComparison(case, True, 1.0, 1.0005, "", 1, 0.0, []).explanations() == []
    assert comparison(exact_share=0.9, estimate=1e-3).explanations() == []
    assert comparison(exact_share=0.9, estimate=1e-3, reported="coexisting").explanations() == []
    assert comparison(exact_share=0.9, estimate=0.0101).explanations()[0].startswith("truncation")
    assert comparison(exact_share=0.4).explanations()[0].startswith("exact orbit's fundamental share")
    listed = comparison(exact_share=0.9, exact_listed="within 0.001")
    assert listed.explanations()[0].startswith("exact orbit listed")
