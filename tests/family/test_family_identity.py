"""What "the same nonlinear mode" means: the family measure is the fundamental harmonic's
share of the kinetic energy, and a stretch where a higher harmonic holds most of it is a
tongue only when the backbone folds or locks its frequency there (docs/resonances.md)."""

import numpy as np
import pytest

import mmshbm
from mmshbm.cli import main
from mmshbm.family.guard import FamilyGuard


def _chain(springs, masses, gap=0.01, side=1):
    """ground - m1 - ... - mn - massless contact node, springs in series."""
    n = len(springs)
    K = np.zeros((n, n))
    for i, k in enumerate(springs):
        K[i, i] += k
        if i:
            K[i - 1, i - 1] += k
            K[i - 1, i] -= k
            K[i, i - 1] -= k
    M = np.diag(list(masses) + [0.0])
    return mmshbm.Model.from_matrices(M, K, n - 1, gap, side)


@pytest.fixture(scope="module")
def stiff_chain():
    return _chain((1000.0, 1000.0, 5000.0), (1.0, 1.0))


def test_a_mode_that_changes_shape_reaches_its_bound_on_its_family(stiff_chain):
    """The chain's nonlinear mode moves energy into harmonic 2 of mode 2 (2Ω approaches
    f2 = 8.14 Hz from below without reaching it: 3.96 Hz at 10 gaps) and the fundamental's
    share of the kinetic energy falls to 0.46, but the backbone rises without a fold: the
    default branch is the plainly followed one, point for point, and complete."""
    fam = mmshbm.backbone(stiff_chain, harmonics=7)
    path = mmshbm.backbone(stiff_chain, harmonics=7, follow="path")
    assert fam.status == "bound:amplitude" and fam.completed
    assert not [s for s in fam.special_points if s.kind == "jump"]
    assert np.all(fam.records["on_family"] == 1.0)
    assert min(fam.records["fundamental_share"]) < 0.5  # the stretch that is not a tongue
    assert len(fam) == len(path)
    np.testing.assert_array_equal(fam.frequency, path.frequency)  # no jump taken: the same steps
    assert not [f for f in fam.metadata["checks"] if f["kind"] == "left_family"]
    assert not [f for f in path.metadata["checks"] if f["kind"] == "left_family"]


def test_the_chain_completes_on_the_command_line(stiff_chain, tmp_path):
    path = tmp_path / "chain.npz"
    stiff_chain.save_npz(path)
    assert main(["backbone", "--model-file", str(path), "-H", "7", "--out", str(tmp_path)]) == 0


def test_fundamental_share_is_the_kinetic_energy_of_harmonic_1(stiff_chain):
    """From the condensed stiffness (−(Ω/8) a_kᵀ ∂D_k/∂Ω a_k per harmonic) it equals the sum
    over the tracked modes of the modal kinetic energy shares at k = 1 (all modes of the
    chain are tracked): two computations of one quantity, to round-off."""
    b = mmshbm.backbone(stiff_chain, harmonics=7, follow="path", max_amplitude=0.06)
    for u, share in zip(b.states[::5], b.records["fundamental_share"][::5], strict=True):
        assert share == pytest.approx(b.solver.modal_shares(u).sum(axis=0)[1], abs=1e-10)


def _records(amplitudes, frequencies, shares):
    return [{"amplitude": a, "frequency": f, "fundamental_share": s}
            for a, f, s in zip(amplitudes, frequencies, shares, strict=True)]


def test_a_climb_that_folds_back_is_a_tongue():
    """Above the frontier the fundamental loses the majority while the branch rises; when
    it folds back the climb is marked off the family after the fact and the frontier is
    the last point before it."""
    recs = _records([1, 2, 3, 4, 3.5, 3.0], [10, 11, 12, 12.1, 12.05, 12.0], [1, 0.9, 0.4, 0.2, 0.1, 0.05])
    guard = FamilyGuard(0.5, 60)
    for i, r in enumerate(recs):
        guard.observe(i, r)
    assert [r["on_family"] for r in recs] == [1, 1, 0, 0, 0, 0]
    assert guard.frontier_index == 1 and guard.left


def test_a_climb_that_locks_its_frequency_is_a_tongue():
    """The amplitude grows by half while the frequency stays within 0.5 %: locked onto
    ω_j/k, a tongue even without a fold."""
    recs = _records([1, 2, 2.5, 3.2, 3.9], [10, 11, 11.01, 11.02, 11.03], [1, 0.9, 0.3, 0.2, 0.1])
    guard = FamilyGuard(0.5, 60)
    for i, r in enumerate(recs):
        guard.observe(i, r)
    assert [r["on_family"] for r in recs] == [1, 1, 0, 0, 0]


def test_a_locked_climb_cut_short_by_the_bound_is_a_tongue():
    """A pending climb that reaches the amplitude bound after growing by 30 % (less than
    the lock's 1.5×) with the frequency flat is judged at the bound by the lock's slope
    (0.5 % of frequency per 50 % of amplitude): a tongue, its points off the family and
    the frontier back where it began. One whose frequency keeps rising at the family's
    pace stays pending (it is not decided there), and so does one that grew by less than
    10 %, or by more than the lock test's 1.5× (which judged it on the way)."""
    def judged(amplitudes, frequencies, shares):
        recs = _records(amplitudes, frequencies, shares)
        guard = FamilyGuard(0.5, 60)
        for i, r in enumerate(recs):
            guard.observe(i, r)
        return guard.locked_at_bound(), [r["on_family"] for r in recs], guard.frontier_index

    flat = [10, 11, 11.001, 11.002, 11.003]
    locked, on, frontier = judged([1, 2, 2.2, 2.4, 2.6], flat, [1, 0.9, 0.3, 0.1, 0.01])
    assert locked and on == [1, 1, 0, 0, 0] and frontier == 1
    rising = judged([1, 2, 2.2, 2.4, 2.6], [10, 11, 11.2, 11.4, 11.6], [1, 0.9, 0.3, 0.1, 0.01])
    assert not rising[0] and rising[1] == [1] * 5
    short = judged([1, 2, 2.05, 2.1, 2.15], [10, 11, 11.0, 11.0, 11.0], [1, 0.9, 0.3, 0.1, 0.01])
    assert not short[0]
    # past 1.5x the lock test itself has judged the stretch (0.64 % > 0.5 %: not locked)
    grown = judged([1, 2, 2.2, 3.4, 3.6], [10, 11, 11.0, 11.07, 11.075], [1, 0.9, 0.3, 0.1, 0.01])
    assert not grown[0] and grown[1] == [1] * 5


def test_a_climb_that_keeps_rising_is_the_family():
    recs = _records([1, 2, 3, 4, 5], [10, 11, 11.5, 11.8, 12.0], [1, 0.9, 0.45, 0.42, 0.6])
    guard = FamilyGuard(0.5, 60)
    for i, r in enumerate(recs):
        guard.observe(i, r)
    assert [r["on_family"] for r in recs] == [1] * 5 and guard.frontier_index == 4


def test_a_branch_round_a_closed_loop_asks_for_a_jump():
    """Off the family, the branch comes back onto it just above the frontier (a point the
    loop passes with a fundamental majority), goes round and comes back there again: the
    second return asks for a jump instead of moving the frontier by round-off each round
    (the branch would go round until its step budget). A passage that comes back
    somewhere new moves the frontier."""
    family = ([1.0, 1.05], [0.30, 0.36], [1.0, 0.9])
    loop = ([1.04, 0.9, 0.75, 0.9, 1.05, 1.0912], [0.3635, 0.3639, 0.3639, 0.3639, 0.3639, 0.36514],
            [0.4, 0.0, 0.0, 0.0, 0.0, 0.53])
    again = ([1.054, 0.9, 0.75, 0.9, 1.05, 1.0914], [0.36353, 0.3639, 0.3639, 0.3639, 0.3639, 0.365126],
             [0.4, 0.0, 0.0, 0.0, 0.0, 0.53])
    recs = _records(*(a + b + c for a, b, c in zip(family, loop, again, strict=True)))
    guard = FamilyGuard(0.5, 60)
    asked = [guard.observe(i, r) for i, r in enumerate(recs)]
    assert asked[:-1] == [None] * (len(recs) - 1) and asked[-1] == "jump"
    assert guard.frontier_index == 7 and recs[-1]["on_family"] == 0.0
    elsewhere = _records(*(a + b + c for a, b, c in zip(family, loop, (
        [1.054, 0.9, 1.2], [0.36353, 0.3639, 0.38], [0.4, 0.0, 0.7]), strict=True)))
    guard = FamilyGuard(0.5, 60)
    assert [guard.observe(i, r) for i, r in enumerate(elsewhere)] == [None] * len(elsewhere)
    assert guard.frontier_index == len(elsewhere) - 1


# ----------------------------------------------------------------- clearances
@pytest.fixture(scope="module")
def clearance(stiff_chain):
    return mmshbm.Model.from_matrices(stiff_chain.M, stiff_chain.K, [2, 2], [0.01, 0.01], [1, -1])


def test_a_clearance_measures_its_amplitude_at_a_dof_with_mass(clearance):
    """The massless node between the stops never passes them: by default the amplitude is
    that of the mass next to it (the DOF with mass that moves most with the node), and
    the branch reaches 10 gaps."""
    assert clearance.amplitude_dof == 1
    b = mmshbm.backbone(clearance, harmonics=7)
    assert b.status == "bound:amplitude" and b.amplitude[-1] == pytest.approx(0.1, rel=1e-9)


def test_an_amplitude_dof_that_cannot_pass_the_clearance_is_refused(clearance):
    with pytest.raises(ValueError, match="massless and held between two stops.*DOF 1"):
        mmshbm.backbone(clearance.with_amplitude_dof(2), harmonics=7)
    # within the clearance it is a valid choice
    b = mmshbm.backbone(clearance.with_amplitude_dof(2), harmonics=7, max_amplitude=0.009)
    assert b.status == "bound:amplitude"


def test_the_force_check_reads_each_stop_on_its_own():
    """Two stops push in opposite directions: the net force on the node is ±(peak) over a
    period, which read as one stop's force would be a pull of 1 of the peak. Per stop, the
    pull left is the Fourier series' truncation (below the 0.05 threshold at H = 15 on
    this oscillator: no finding; a net-force reading gives 1)."""
    model = mmshbm.ClearanceOscillator(1.0, 1.0, 4.0, 1.0).model()
    b = mmshbm.backbone(model, harmonics=15, max_amplitude=5.0)
    pulls = [f["value"] for f in b.metadata["checks"] if f["kind"] == "negative_force"]
    assert not pulls or -min(pulls) < 0.5


# ----------------------------------------------------------------- trust region
def test_jump_iterates_stay_near_the_branch():
    """At H = 15 the beam's jumps solve points at pinned amplitudes; an iterate that ran
    away to 14.9 kHz (the branch lives at 45-71 Hz) made the modal condensation warn that
    a harmonic passed its last mode. The trust region keeps every iterate within [f/2, 2f]
    of the frontier's frequency."""
    import warnings

    beam = mmshbm.default_beam().model(21)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        b = mmshbm.backbone(beam, harmonics=15)
    assert b.status == "bound:amplitude"
    assert not [w for w in caught if "the modal condensation leaves out" in str(w.message)]


def test_a_pinned_solve_stops_at_the_trust_region(stiff_chain):
    from mmshbm.core.pinned import PinnedFailure, solve_at_amplitude

    b = mmshbm.backbone(stiff_chain, harmonics=3, follow="path", max_amplitude=0.03)
    p, u = b.solver, b.states[-1]
    f = p.frequency_of(u)
    assert f == pytest.approx(b.frequency[-1], rel=1e-12)
    u0 = p.scaled_state(u, 1.5)
    with pytest.raises(PinnedFailure, match="trust region"):
        solve_at_amplitude(p, u0, 0.045, admissible=lambda v: abs(p.frequency_of(v) / f - 1) < 1e-9)


def test_the_first_point_has_every_contact_open():
    """Two contact nodes: half the smallest gap at the amplitude DOF would close the other
    contact on the linear mode (no solution there: the start failed). The first point
    is taken at half the amplitude at which the linear mode's first contact closes."""
    from validation import corpus

    case = corpus.generate(135, seed=0)[134]
    assert case.contact == "several"
    model = case.model()
    b = mmshbm.backbone(model, harmonics=case.harmonics)
    assert b.status == "bound:amplitude"
    q = b.time_signals(0, dofs=list(model.contact_dofs))[1]
    for row, ct in zip(q, model.contacts, strict=True):
        assert ct.side * row.max() < ct.gap  # open at the start
    assert b.amplitude[0] < 0.5 * model.gap


def test_an_s_bend_of_the_amplitude_with_the_frequency_rising_is_not_a_tongue():
    """A 3-mass chain (H = 9) whose backbone hands most of its kinetic energy to harmonic 2
    of mode 2 while both keep rising, with an S-bend at 4.06 gaps where the amplitude goes
    back by 0.08 % while the frequency keeps rising: a pending stretch that was reverted
    there as a tongue's fold ended in a failed jump at 2.78 gaps. It is one continuous
    branch to 10 gaps, the one plain path following gives (same point at the bound to the
    Newton tolerance), with no jump."""
    from validation import corpus

    case = corpus.generate(92, seed=0)[91]
    assert (case.kind, case.contact, case.harmonics) == ("chain", "one-sided", 9)
    model = case.model()
    fam = mmshbm.backbone(model, harmonics=9, max_amplitude=10 * model.gap)
    path = mmshbm.backbone(model, harmonics=9, max_amplitude=10 * model.gap, follow="path")
    assert fam.completed and path.status == "bound:amplitude"
    assert not [s for s in fam.special_points if s.kind == "jump"]
    assert abs(fam.frequency[-1] / path.frequency[-1] - 1) < 1e-8
    assert np.all(fam.records["on_family"] == 1.0)
