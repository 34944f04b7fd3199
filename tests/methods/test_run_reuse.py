"""The shortcuts of a run's checks and options give what the plain computation gives: the
kept sample grid and default thresholds, the contact check's depth and pull from the
extreme samples (against every sample of every point), the coexistence scan that stops
where nothing is off the family front, and the continuation options validated before."""

import warnings

import numpy as np
import pytest

import mmshbm
from mmshbm.results import coexisting, contact_checks, diagnostics
from mmshbm.results.family_points import family_front
from mmshbm.results.findings import CheckThresholds


def _branch(model, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return mmshbm.backbone(model, **kwargs)


def _clearance():
    return mmshbm.Model.from_matrices(np.diag([1.0, 0.0]), np.array([[2.0, -1.0], [-1.0, 1.0]]),
                                      contact_dof=[1, 1], gap=[0.5, 0.5], stop_side=[1, -1], amplitude_dof=0)


def test_kept_grid_is_the_computed_one():
    for n in (8, 256, 1000):
        tau = contact_checks._grid(n)
        np.testing.assert_array_equal(tau, 2 * np.pi * np.arange(n) / n)
        assert not tau.flags.writeable and contact_checks._grid(n) is tau


def test_default_thresholds_record_is_the_thresholds_and_each_branch_its_own():
    model = mmshbm.OneDofOscillator(1.0, 1.0, 4.0, 1.0).model()
    b = _branch(model, harmonics=3, max_amplitude=2 * model.gap)
    first = b.metadata["check_thresholds"]
    assert first == {name: getattr(CheckThresholds(), name) for name in first}
    explicit = b.check(CheckThresholds(), warn=False)
    assert b.metadata["check_thresholds"] == first and b.metadata["check_thresholds"] is not first
    assert [f.to_dict() for f in explicit] == b.metadata["checks"]
    b.check(warn=False)
    assert b.metadata["check_thresholds"] is not diagnostics._DEFAULT_RECORD


def _plain_contact(branch, th):
    """(depth past the stops (n_pts,) in gaps, pull (n_pts,)) one sample at a time from the
    signals the check takes (every point's at once with one stop, else each point's), with
    the force scale as np.nanmax gives it."""
    solver, model = branch.solver, branch.get_model()
    n = th.n_samples
    tau = 2 * np.pi * np.arange(n) / n
    f_all = np.asarray(branch.contact_force_max, dtype=float)
    f_scale = float(np.nanmax(np.abs(f_all))) if np.any(np.isfinite(f_all)) else 0.0
    k_c = float(np.max(np.atleast_1d(np.asarray(solver.contact_stiffness, dtype=float))))
    f_scale = max(f_scale, k_c * max(c.gap for c in model.contacts))
    floor = th.force_floor * f_scale
    dofs = [c.dof for c in model.contacts]
    if model.n_contacts == 1:
        Q, L = solver.contact_signals_many(np.asarray(branch.states), tau)
    pen, neg = np.empty(len(branch)), np.empty(len(branch))
    for i, u in enumerate(branch.states):
        if model.n_contacts == 1:
            q, lam = Q[i], L[i]
        else:
            q = solver.time_signals(u, dofs, n)[1]
            lam = contact_checks._stop_forces(model, q, np.atleast_2d(solver.contact_force(u, n)[1]))
        depth = [max((ct.side * q[k, j] - ct.gap) / ct.gap for j in range(n))
                 for k, ct in enumerate(model.contacts)]
        pull = []
        for k in range(len(model.contacts)):
            peak, lo = max(max(lam[k]), floor), min(lam[k])
            pull.append(-lo / peak if depth[k] >= -th.penetration and peak > 0 and lo < -floor else 0.0)
        pen[i] = max(depth)
        neg[i] = max(pull) * (pen[i] >= -th.penetration)
    return pen, neg


@pytest.mark.parametrize("case", ["oscillator", "clearance"])
def test_contact_check_is_the_per_sample_computation(case):
    """The contact check's findings (worst depth, worst pull, first and last points) are
    those of every sample of every point (one stop, and a clearance's two stops: the lower
    stop's depth from the smallest sample)."""
    if case == "oscillator":
        model = mmshbm.OneDofOscillator(1.0, 1.0, 4.0, 1.0).model()
        b = _branch(model, harmonics=3, max_amplitude=3 * model.gap)
    else:
        model = _clearance()
        b = _branch(model, harmonics=3, max_amplitude=3 * model.gap)
    th = CheckThresholds(penetration=0.01, negative_force=0.01)
    found = {f.kind: f for f in contact_checks.contact_findings(b, b.solver, th)}
    pen, neg = _plain_contact(b, th)
    assert "penetration" in found  # H = 3 passes the stop: the comparison has numbers to compare
    bad = np.flatnonzero(pen > th.penetration)
    f = found["penetration"]
    assert (f.first, f.last, f.value) == (int(bad[0]), int(bad[-1]), float(pen[bad].max()))
    bad = np.flatnonzero(neg > th.negative_force)
    if len(bad):
        f = found["negative_force"]
        assert (f.first, f.last, f.value) == (int(bad[0]), int(bad[-1]), float(-neg[bad].max()))
    else:
        assert "negative_force" not in found


def test_coexistence_scan_stops_only_where_nothing_is_off_the_front():
    """A branch all on its front without jumps has no coexisting orbits (the full scan
    agrees); one point taken off the front runs the scan, which finds it."""
    model = mmshbm.OneDofOscillator(1.0, 1.0, 4.0, 1.0).model()
    b = _branch(model, harmonics=5, max_amplitude=3 * model.gap)
    assert coexisting.coexisting_intervals(b) == []
    assert len(family_front(b)) == len(b)
    b.records["on_family"] = b.records["on_family"].copy()
    b.records["on_family"][len(b) // 2] = 0.0  # an excursion in the middle: the front covers it
    found = coexisting.coexisting_intervals(b)
    assert len(found) == 1 and found[0].points == (len(b) // 2,)


def _fields(opts):
    import dataclasses

    values = [(f.name, getattr(opts, f.name)) for f in dataclasses.fields(opts)]
    return [(name, type(v), repr(v)) for name, v in values]


@pytest.mark.parametrize("given", [{}, {"ds": 0.05, "max_steps": 7, "follow": "path"},
                                   {"bounds": {"frequency": (0.0, 80.0)}, "newton_tol": 1e-9},
                                   {"bounds": {"amplitude": (-0.0, 1.0)}}, {"ds_max": 1}])
def test_validated_continuation_options_are_the_validated_ones(given):
    """The continuation options of a run whose values were validated before are, field for
    field (types, reprs, the bounds' order), those validated afresh, each run its own object
    and bounds dict; values of other types (a list) are validated every time."""
    from mmshbm.core.options import ContinuationOptions
    from mmshbm.methods import runner

    runner._VALIDATED.clear()
    bounds = {"amplitude": (0.0, 2.0)}
    first = runner.continuation_options({"harmonics": 5, **dict(given)}, bounds)
    options = {"harmonics": 5, **dict(given)}
    again = runner.continuation_options(options, bounds)
    assert options == {"harmonics": 5}  # the continuation fields taken out, the method's left
    fresh = ContinuationOptions(**{k: v for k, v in given.items() if k != "bounds"},
                                bounds={**bounds, **dict(given.get("bounds", {}))})
    assert _fields(again) == _fields(fresh) == _fields(first) and again == fresh
    assert list(again.bounds) == list(fresh.bounds)
    assert again is not first and again.bounds is not first.bounds
    again.bounds["energy"] = (0.0, 1.0)  # a run's own dict: the next run's options do not see it
    assert "energy" not in runner.continuation_options({**given}, bounds).bounds
    assert runner._options_key({"bounds": {"amplitude": [0.0, 1.0]}}) is None
    assert runner._options_key({"ds": np.float64(0.1)}) is None
    with pytest.raises(ValueError, match="ds_min <= ds"):
        runner.continuation_options({"ds": 5.0}, bounds)
    with pytest.raises(ValueError, match="ds_min <= ds"):  # not kept: raises again
        runner.continuation_options({"ds": 5.0}, bounds)


def test_no_resonance_scan_where_the_starting_mode_is_the_only_one_tracked():
    """With the first mode the only one tracked (the one-DOF oscillator) the scan can name
    nothing: the special points are those the full scan gives (sorted the same way); a
    second tracked mode (the beam) is scanned."""
    from unittest import mock

    from mmshbm.core.resonances import internal_resonances
    from mmshbm.core.special_points import SpecialPoint
    from mmshbm.methods import runner

    model = mmshbm.OneDofOscillator(1.0, 1.0, 4.0, 1.0).model()
    b = _branch(model, harmonics=13, max_amplitude=2 * model.gap)
    p = b.solver
    rec = {"frequency": b.frequency, **b.records}
    assert rec["modal_shares"].shape[1] == 1 and p.mode == 1
    special = [SpecialPoint("start", 0), SpecialPoint("grazing", 9), SpecialPoint("fold", 3),
               SpecialPoint("endpoint", len(b) - 1), SpecialPoint("bound:amplitude", len(b) - 1)]
    full = sorted(special + internal_resonances(rec["frequency"], rec["modal_shares"], p.tracked_frequencies,
                                                p.mode), key=lambda s: (s[1], s[0] == "endpoint"))
    with mock.patch("mmshbm.core.resonances.internal_resonances", side_effect=AssertionError):
        assert runner.name_internal_resonances(p, rec, list(special)) == full
    beam = mmshbm.default_beam().model(21)
    bb = _branch(beam, harmonics=5, max_amplitude=3 * beam.gap)
    assert bb.records["modal_shares"].shape[1] > 1
    assert any(s.kind == "internal_resonance" for s in bb.special_points)


def test_family_options_of_a_run_are_those_of_its_fields():
    """The family following's options of a run's continuation options are those built afresh
    from the same fields (one object per set of values), for a replaced object too; none for
    plain path following."""
    import dataclasses

    from mmshbm.core.options import ContinuationOptions
    from mmshbm.family.options import FamilyOptions

    opts = ContinuationOptions(family_share=0.4, max_excursion=7, jump_step=0.05, max_jumps=3)
    fresh = FamilyOptions(family_share=0.4, max_excursion=7, jump_step=0.05, max_jumps=3)
    assert FamilyOptions.of(opts) == fresh and FamilyOptions.of(opts) is FamilyOptions.of(opts)
    other = dataclasses.replace(opts, max_jumps=9)
    assert FamilyOptions.of(other) == FamilyOptions(family_share=0.4, max_excursion=7, jump_step=0.05,
                                                    max_jumps=9)
    assert FamilyOptions.of(dataclasses.replace(opts, follow="path")) is None
    assert FamilyOptions.of(ContinuationOptions(follow="path")) is None


def test_range_check_skipped_only_where_every_mode_is_kept():
    """The monitor skips the modal truncation's range check where the condensation keeps
    every mode: there the check passes at any frequency."""
    model = mmshbm.OneDofOscillator(1.0, 1.0, 4.0, 1.0).model()
    b = _branch(model, harmonics=13, max_amplitude=2 * model.gap)
    cond = b.solver.cond
    assert cond.backend == "modal" and cond.complete
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert all(cond.check_range(w, 40) for w in (1.0, 1e3, 1e9, 1e300))
    beam = mmshbm.default_beam().model(21)
    bb = _branch(beam, harmonics=5, max_amplitude=3 * beam.gap)
    assert not bb.solver.cond.complete  # a truncated reduction: checked at every point


def test_the_truncation_findings_count_the_tolerance_on_the_family_front():
    """The penetration and pull findings of a tolerance run say at how many of their points
    the estimate meets tol on the family front only (as tolerance_not_met does): a point off
    the front with a NaN estimate (``error_not_estimated``) or a large one is left out of
    the count and of the largest estimate, and said to be left out."""
    class Stub:  # what the check reads of a branch: 5 points, the front the first 3
        metadata = {"tolerance": {"tol": 1e-3}}
        records = {"frequency_error": np.array([1e-4, 2e-4, 5e-3, np.nan, 2e-1]),
                   "error_not_estimated": np.array([0, 0, 0, 1, 0])}

        def __len__(self):
            return 5

        def family_front(self):
            return np.array([0, 1, 2])

    stub = Stub()
    text = contact_checks._against_tolerance(stub, np.array([1, 2, 3, 4]))
    assert text == ("; against the tolerance 0.001: the frequency's estimated error at these points is up to "
                    "0.005 on the family front, within the tolerance at 1 of the 2 there (2 off the family "
                    "front not counted)")
    assert "at 2 of the 2 there" in contact_checks._against_tolerance(stub, np.array([0, 1]))
    assert "not counted" not in contact_checks._against_tolerance(stub, np.array([0, 1]))
    assert "none of these points is on the family front (1 off" in \
        contact_checks._against_tolerance(stub, np.array([3]))
