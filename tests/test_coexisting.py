"""Orbits that coexist with the backbone at the same amplitude are reported
(mmshbm.results.coexisting, the "coexisting_orbits" finding)."""

import warnings

import numpy as np

import mmshbm
from mmshbm.results.coexisting import coexisting_intervals
from validation import corpus


def _run(model, **kw):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        b = mmshbm.backbone(model, **kw)
    return b, [str(w.message) for w in caught if issubclass(w.category, mmshbm.BranchWarning)]


def test_a_tongue_beside_the_backbone_is_reported_with_its_amplitudes():
    """A chain whose 3:1 tongue (3Ω = f2) leaves the backbone at 1.2 gaps, folds at
    1.68 gaps and comes back down to 1.03 gaps before the branch jumps: between 1.03 and
    1.68 gaps the tongue's orbits and the backbone's coexist. The finding names that
    interval; inside it both orbits solve the equations at the same amplitude, at
    frequencies that differ by more than the Newton tolerance could explain."""
    case = corpus.generate(138, seed=0)[137]
    model = case.model()
    b, messages = _run(model, harmonics=case.harmonics, max_amplitude=10 * model.gap)
    assert b.completed
    found = [f for f in b.findings if f.kind == "coexisting_orbits"]
    assert len(found) == 1
    intervals = coexisting_intervals(b)
    gap = model.gap
    lo, hi = intervals[0].lo / gap, intervals[-1].hi / gap
    assert 1.0 < lo < 1.1 and 1.6 < hi < 1.7, (lo, hi)
    assert f"{intervals[0].lo / gap:.4g}-{intervals[0].hi / gap:.4g} gaps" in found[0].message
    # the warning says it (within the family's warning: one warning, as before)
    assert sum("coexist" in m for m in messages) == 1
    # an off-front point inside the interval and the backbone at its amplitude: two
    # orbits, both solutions, different frequencies
    front = set(b.family_front().tolist())
    i = next(i for i in intervals[-1].points if i not in front and 1.3 * gap < b.amplitude[i] < 1.6 * gap)
    f_backbone, u = mmshbm.results.family_points.family_point(b, float(b.amplitude[i]))
    assert np.abs(b.solver.evaluate(u, jacobian=False)).max() < 1e-8
    assert np.abs(b.solver.evaluate(b.states[i], jacobian=False)).max() < 1e-8
    assert abs(f_backbone / b.frequency[i] - 1) > 1e-3


def test_no_coexistence_where_the_branch_never_leaves_its_family():
    """A one-DOF oscillator (no other mode, no tongue) and plain path following: nothing
    is reported."""
    model = mmshbm.OneDofOscillator(1, 1, 4, 1).model()
    b, _ = _run(model, harmonics=5, max_amplitude=10.0)
    assert b.completed and coexisting_intervals(b) == []
    assert not [f for f in b.findings if f.kind == "coexisting_orbits"]
    case = corpus.generate(138, seed=0)[137]
    p, _ = _run(case.model(), harmonics=case.harmonics, max_amplitude=10 * case.model().gap, follow="path")
    assert coexisting_intervals(p) == []


def test_the_segment_from_the_front_into_a_tongue_holds_coexisting_orbits():
    """A chain whose branch leaves its family front at 1.265 gaps (the fundamental loses
    the kinetic energy's majority), rises on the tongue side to a fold at 1.54 gaps, and
    jumps from 1.265 gaps onto an orbit 9 % higher in frequency. Its first point off the
    front is at 1.301 gaps, so at 1.3 gaps only the path's segment from the front point
    holds the tongue side's orbit. The exact single-contact orbit at 1.3 gaps
    (mmshbm.exact) is that orbit: the branch must say that another orbit coexists there
    with its backbone, at the exact orbit's frequency."""
    from validation import corpus_exact as ce

    model = ce.chains(288, seed=23)[287].model()
    A = 1.3 * model.gap
    orbit = mmshbm.exact.periodic_orbit(model, A)
    assert orbit.converged and orbit.n_contacts == 1
    b, _ = _run(model, harmonics=31, max_amplitude=1.56 * model.gap)
    assert abs(b.frequency_at(A) / orbit.frequency - 1) > 0.05  # the backbone is the other orbit
    holding = [c for c in coexisting_intervals(b) if c.lo <= A <= c.hi]
    assert len(holding) == 1
    f_lo, f_hi = holding[0].frequency_other
    # the tongue side's orbits between the front point and the first point off it: the
    # exact orbit's frequency lies between theirs
    assert f_lo * (1 - 1e-3) <= orbit.frequency <= f_hi * (1 + 1e-3)
