"""Orbits that coexist with the backbone at the same amplitude are reported
(mmshbm.results.coexisting, the "coexisting_orbits" finding)."""

import warnings

import numpy as np
import pytest

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


def test_the_coexisting_points_are_solved_orbits_at_their_amplitude():
    """Each point of the coexisting interval off the family front is an orbit that
    ``orbits_at`` finds at that amplitude: listed when its fundamental holds at least half
    the kinetic energy, among the rejected frequencies otherwise (a tongue's)."""
    case = corpus.generate(138, seed=0)[137]
    model = case.model()
    b, _ = _run(model, harmonics=case.harmonics, max_amplitude=10 * model.gap)
    front = set(b.family_front().tolist())
    off = [i for c in coexisting_intervals(b) for i in c.points if i not in front]
    for i in off[:: max(1, len(off) // 3)][:3]:
        r = b.orbits_at(float(b.amplitude[i]))
        known = list(r.frequencies) + list(r.rejected)
        f_backbone = b.frequency_at(float(b.amplitude[i]))
        if np.isfinite(f_backbone):  # the backbone's orbit first
            assert r[0].source == "backbone" and r[0].frequency == pytest.approx(f_backbone, rel=1e-12)
        else:  # inside an interval the front skipped: no backbone orbit, and the reason says it
            assert all(o.source != "backbone" for o in r)
            assert not len(r) or not r.reason
        assert any(abs(f / b.frequency[i] - 1) <= 1e-7 for f in known), (b.frequency[i], known)


def test_the_backbone_plot_marks_the_coexisting_orbits():
    """plot_backbone draws the coexisting points off the family front as their own
    markers with one legend entry (at their frequencies and amplitudes), and not with
    ``coexisting=False``."""
    from mmshbm import plotting

    case = corpus.generate(138, seed=0)[137]
    model = case.model()
    b, _ = _run(model, harmonics=case.harmonics, max_amplitude=10 * model.gap)
    front = set(b.family_front().tolist())
    points = sorted({i for c in coexisting_intervals(b) for i in c.points if i not in front})
    assert points
    ax = plotting.plot_backbone(b).axes[0]
    marked = [line for line in ax.get_lines() if line.get_label() == "coexisting orbit (same amplitude)"]
    assert len(marked) == 1
    np.testing.assert_array_equal(marked[0].get_xdata(), b.frequency[points])
    np.testing.assert_array_equal(marked[0].get_ydata(), b.amplitude[points] / model.gap)
    assert "coexisting orbit (same amplitude)" in [t.get_text() for t in ax.get_legend().get_texts()]
    ax = plotting.plot_backbone(b, coexisting=False).axes[0]
    assert not [line for line in ax.get_lines() if line.get_label().startswith("coexisting")]
