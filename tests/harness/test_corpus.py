"""The corpus of random models (validation.corpus): reproducible cases, valid models,
and a fast slice of the defaults' figures (every model of the slice reaches its bound on
the first mode's family, none raises, none runs past its limit)."""

import re

import numpy as np
import pytest

import mmshbm
from validation import corpus
from validation.__main__ import main as validation_main


def test_cases_are_reproducible_and_independent_of_the_count():
    a = corpus.generate(30, seed=4)
    b = corpus.generate(12, seed=4)
    assert a[:12] == b
    assert corpus.generate(5, seed=5) != corpus.generate(5, seed=4)
    kinds = {(c.kind, c.contact) for c in corpus.generate(200, seed=0)}
    assert {("chain", "one-sided"), ("tree", "clearance"), ("beam", "one-sided"), ("beam", "clearance"),
            ("chain", "several")} <= kinds
    assert ("beam", "several") not in kinds


def test_models_are_valid_and_clearances_measure_a_dof_with_mass():
    for case in corpus.generate(60, seed=1):
        m = case.model()
        assert m.massless_contacts
        if case.contact == "clearance":
            assert m.n_contacts == 2 and len(set(m.contact_dofs)) == 1
            assert m.amplitude_dof in set(m.l.tolist())
        elif case.contact == "several":
            assert len(set(m.contact_dofs)) == 2
        assert np.all(np.isfinite(m.linear_frequencies(1)))


def test_bad_corpus_requests():
    with pytest.raises(ValueError, match="unknown kind"):
        corpus.generate(3, kinds=("plate",))
    with pytest.raises(ValueError, match="unknown contact type"):
        corpus.generate(3, contacts=("glue",))


#: a slice chosen for speed (small H), not for success: every case of it is run
SLICE = [c for c in corpus.generate(40, seed=0, harmonics=(1, 3, 5)) if c.kind != "beam"][:16]


@pytest.mark.parametrize("case", SLICE, ids=lambda c: c.label)
def test_the_defaults_reach_the_bound_on_the_family(case):
    r = corpus.run_case(case, time_limit=30.0)
    assert r.completed, (case, r.status)
    assert r.seconds < 30.0


def test_cli_corpus(tmp_path, capsys):
    assert validation_main(["corpus", "4", "--seed", "2", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "complete" in out and "exceptions: 0" in out
    rows = (tmp_path / "corpus.csv").read_text().splitlines()
    assert len(rows) == 5


def test_a_clearance_whose_unknowns_grow_along_a_pole_reaches_its_bound():
    """A heavy mass held by a clearance: past 2.5 gaps the branch moves along the pole
    unknown of the first clamped mode (Ω near its frequency), which moves the amplitude
    DOF 0.02 gaps per step of ds_max; with ds_max as a hard cap the run ran out of its
    1000 steps at 3.1 gaps. The cap grows where the amplitude barely moves."""
    case = corpus.generate(8, seed=0)[7]
    assert (case.kind, case.contact) == ("chain", "clearance")
    r = corpus.run_case(case)
    assert r.completed and r.points < 700, r.status


def test_where_orbits_coexist_the_branch_is_the_first_modes():
    """A chain near a 9:2 internal resonance (9Ω about 2 % above f2) at 1.3 gaps: the exact
    single-contact symmetric orbit found from the linear mode's shape is at 0.57656 Hz, the
    default branch at 0.57312 Hz (the same at H = 31 and 62 to 1e-5). Continuing the exact
    orbit from the linear mode through grazing gives the branch's orbit (three contacts
    per period at 1.3 gaps): the single-contact orbit coexists with the first mode's."""
    import mmshbm
    from validation import corpus_exact as ce

    case = ce.chains(137, seed=100)[136]
    model = case.model()
    A = 1.3 * model.gap
    single = mmshbm.exact.periodic_orbit(model, A)
    assert single.converged and single.n_contacts == 1
    continued = mmshbm.exact.backbone(model, np.linspace(0.5 * model.gap, A, 81))
    assert continued.converged[-1] and continued.n_contacts[-1] > 1
    b = mmshbm.backbone(model, harmonics=31, max_amplitude=1.2 * A)
    f = b.frequency_at(A)
    assert abs(f / continued.frequency[-1] - 1) < 1e-4
    assert abs(f / single.frequency - 1) > 3e-3


def test_a_jump_lands_where_the_backbone_rises_steeply_past_a_tongue():
    """Two jumps whose landings on the family were refused: a chain whose 3:1 tongue sits
    25 % above the frequency of the point near grazing the predictor came from (the
    family lands at 0.304 Hz, the predictor said 0.25 Hz: refused as "another branch"
    although above the frontier's frequency), and a clearance whose frontier sits on a
    fold at the tongue's foot (the last two family points saw no rise, so the family at
    5.1 Hz, 2.6 gaps, lay outside a window capped at the frontier's 3.8 Hz). Both reach
    10 gaps on the family and end where plain path following ends (same point at the
    bound: the Newton tolerance bounds the difference). The chain's excursion returns above
    the frontier after 52 steps since the pole unknowns are scaled by the motion they give
    (a passage within the default 60 steps): it runs with ``max_excursion=40`` so that it
    still jumps."""
    cases = corpus.generate(138, seed=0)
    for i, excursion in ((137, 40), (51, 60)):
        case = cases[i]
        model = case.model()
        b = mmshbm.backbone(model, harmonics=case.harmonics, max_amplitude=10 * model.gap,
                            max_excursion=excursion)
        assert b.completed and b.status == "bound:amplitude", (i, b.status)
        jumps = [s for s in b.special_points if s.kind == "jump"]
        assert jumps
        for s in jumps:  # every landing lies at or above the frontier's frequency
            below = b.amplitude[: s.index] <= s.data["amplitude_frontier"] * (1 + 1e-9)
            front = b.frequency[: s.index][below]
            assert s.data["frequency_to"] >= 0.99 * front.max()
        p = mmshbm.backbone(model, harmonics=case.harmonics, max_amplitude=10 * model.gap, follow="path")
        assert p.status == "bound:amplitude"
        assert abs(b.frequency[-1] / p.frequency[-1] - 1) < 1e-7


def test_where_two_family_orbits_reach_the_bound_the_backbone_is_the_larger_share():
    """A 4-mass chain (H = 9) whose branch hands most of its energy to harmonic 2 of mode 2
    from 2.8 gaps on and folds back and forth (an S over 5.2-9.2 gaps): plain path
    following comes back to the fundamental's majority only near 10 gaps (share 0.52 at
    1.84 Hz). Another orbit of the family coexists above 2.7 gaps at higher frequency,
    with the fundamental's share 0.6-0.7 all the way to 10 gaps. Both satisfy the
    definition at the bound; the backbone is the one of larger share (docs/resonances.md),
    reached without a hole: every interval the branch skips is at most 10 % of its lower
    end, and frequency_at is NaN inside."""
    case = corpus.generate(48, seed=1)[47]
    assert (case.kind, case.contact, case.harmonics) == ("chain", "one-sided", 9)
    model = case.model()
    b = mmshbm.backbone(model, harmonics=9, max_amplitude=10 * model.gap)
    assert b.completed, b.status
    p = mmshbm.backbone(model, harmonics=9, max_amplitude=10 * model.gap, follow="path")
    assert p.status == "bound:amplitude"
    share, path_share = b.records["fundamental_share"][-1], p.records["fundamental_share"][-1]
    assert 0.5 <= path_share < share
    assert b.frequency[-1] > p.frequency[-1]
    for s in (s for s in b.special_points if s.kind == "jump"):
        lo, hi = s.data["amplitude_frontier"], s.data["amplitude_to"]
        assert hi <= 1.1 * lo
        if hi > lo * 1.01:
            assert np.isnan(b.frequency_at(0.5 * (lo + hi)))


def test_a_clearance_jump_lands_where_the_backbone_climbs_towards_the_held_frequency():
    """A clamped beam with a clearance at its tip (H = 9): a 6:2 tongue at grazing, the
    frontier at 1.15 gaps and 15.9 Hz; beyond it the backbone climbs steeply towards the
    frequency with both stops held (62.9 Hz), so the family at 1.2 gaps (29.8 Hz) lies
    above the window extrapolated from points near grazing (22 Hz) and every landing was
    refused or left the trust region. The far search's window reaches the problem's
    frequency limit: the branch completes, each landing point is on the family and none
    is above the held frequency."""
    from mmshbm.methods.mms.held import _held_frequency

    case = corpus.generate(318, seed=0)[317]
    assert (case.kind, case.contact, case.harmonics) == ("beam", "clearance", 9)
    model = case.model()
    b = mmshbm.backbone(model, harmonics=9, max_amplitude=10 * model.gap)
    assert b.completed, b.status
    held = _held_frequency(model, [c.dof for c in model.contacts], 1)
    jumps = [s for s in b.special_points if s.kind == "jump"]
    assert jumps and max(s.data["frequency_to"] for s in jumps) > 1.3 * 22.22
    for s in jumps:
        assert b.records["on_family"][s.index] == 1.0 and s.data["frequency_to"] < held
    assert b.frequency.max() < held


def test_a_clearance_locked_at_its_held_frequency_reaches_its_bound():
    """A 7-mass chain (H = 1) whose heavy masses swing on a clearance with a stiff contact
    spring: from 1.36 gaps on the frequency stays at 0.7317 Hz (the held limit) while the
    amplitude grows only through the pole unknown of the first clamped mode, about
    2·10⁻⁶ gaps per unit of arclength. The step cap stopped growing at 1000 ds_max and the
    run ran out of its 1000 steps at 5.1 gaps; with the cap limited only by the 2 % change
    of amplitude it reaches 10 gaps in under 300 points."""
    case = corpus.generate(150, seed=0, contacts=("clearance",))[149]
    assert (case.kind, case.harmonics) == ("chain", 1)
    r = corpus.run_case(case)
    assert r.completed and r.points < 300, r.status


def _bilinear_frequency(m: float, k: float, k_c: float, g: float, X: float) -> float:
    """Exact frequency (Hz) of a mass ``m`` on a spring ``k`` whose massless contact node
    (spring ``k_c``) meets two stops at ±``g``, free oscillation of amplitude ``X`` > g:
    a quarter period is the soft motion from 0 to g plus the stiff motion (about the
    offset k_c g/(k + k_c)) from g to X, each a piece of a sinusoid."""
    w1, w2 = np.sqrt(k / m), np.sqrt((k + k_c) / m)
    x_e = k_c * g / (k + k_c)
    v_g2 = (k * X**2 + k_c * (X - g) ** 2 - k * g**2) / m
    t_soft = np.arcsin(g / np.sqrt(g**2 + v_g2 / w1**2)) / w1
    t_stiff = np.arccos((g - x_e) / (X - x_e)) / w2
    return 1.0 / (4.0 * (t_soft + t_stiff))


@pytest.mark.parametrize("seed, index, contacts, tol", [
    (0, 97, ("clearance",), 5e-4),  # H = 15: measured 0.4-1.5e-4
    (8, 241, corpus.CONTACTS, 2e-2),  # H = 1: measured 0.03-1.3 %
])
def test_a_mass_on_a_very_stiff_clearance_reaches_its_bound(seed, index, contacts, tol):
    """One mass on a clearance whose contact spring is 10⁴-10⁵ times its own: the
    frequency climbs from the open to near the held one (up to a hundredfold) while the
    amplitude grows through the pole unknown of the clamped mode. Scaled as a force that
    unknown reached 10⁵ (the pole row's scaled residual that much more sensitive to Ω), the
    residual step control held every step to a 0.2 % change of amplitude and the H = 15
    run ran out of its 1000 steps at 3.2 gaps; scaled by the motion it gives the mass, both
    reach 10 gaps in under 300 points, on the exact bilinear frequency within the
    truncation of H (closed form, both stops at the same gap)."""
    case = corpus.generate(index + 1, seed=seed, contacts=contacts)[index]
    p = case.params
    assert case.contact == "clearance" and len(p["masses"]) == 1 and not p["ground"][0]
    assert p["gaps"][0] == p["gaps"][1] and p["node_k"][0] > 1e4 * p["springs"][0]
    model = case.model()
    b = mmshbm.backbone(model, harmonics=case.harmonics, max_amplitude=10 * model.gap)
    assert b.status == "bound:amplitude" and len(b) < 300, (b.status, len(b))
    for a in (2.0, 5.0, 10.0 * (1 - 1e-9)):
        f = _bilinear_frequency(p["masses"][0], p["springs"][0], p["node_k"][0], p["gaps"][0], a * model.gap)
        assert abs(b.frequency_at(a * model.gap) / f - 1) < tol, a


def test_a_chain_whose_jump_skipped_the_compared_amplitude_now_lands_below_it():
    """A 3-mass chain (gap 1 cm, H = 31) whose last jump below the bound once skipped
    1.296-1.399 gaps (no frequency at 1.3 gaps, reported as skipped). With the pole
    unknowns scaled by the motion they give, the branch's steps differ and its jump (at
    1.0 gaps) skips nothing: at 1.3 gaps it has a frequency 0.87 % below the exact
    single-contact orbit, which is the Fourier series' truncation (at 2H the error falls
    to 0.1 %), and the branch says so. Inside any skipped interval frequency_at is NaN."""
    from validation import corpus_exact as ce

    case = ce.chains(14, seed=0)[13]
    model = case.model()
    A = 1.3 * model.gap
    b = mmshbm.backbone(model, harmonics=31, max_amplitude=1.2 * A)
    assert np.isfinite(b.frequency_at(A))
    for s in (s for s in b.special_points if s.kind == "jump"):
        lo, hi = s.data["amplitude_frontier"], s.data["amplitude_to"]
        if hi > lo * 1.01:
            assert np.isnan(b.frequency_at(0.5 * (lo + hi)))
            assert "skipped" in ce._reported(b, 0.5 * (lo + hi))
    r = ce.compare(case)
    assert r.clean and r.explained and r.truncation
    assert r.error_2h < 0.2 * r.error


def test_exact_chains_with_contact_springs_drawn_like_the_others():
    """``contact_decades`` redraws only the contact node's spring, inside its range, the same
    for the same seed; the rest of each chain is the corpus's."""
    from validation import corpus_exact as ce

    base = ce.chains(12, seed=4)
    soft = ce.chains(12, seed=4, contact_decades=(1.0, 2.0))
    again = ce.chains(12, seed=4, contact_decades=(1.0, 2.0))
    assert [c.params["node_k"] for c in soft] == [c.params["node_k"] for c in again]
    for a, b in zip(base, soft, strict=True):
        assert 10.0 <= b.params["node_k"][0] <= 100.0
        assert a.params["masses"] == b.params["masses"] and a.params["springs"] == b.params["springs"]


def test_cli_corpus_exact(tmp_path, capsys):
    """Two chains whose branches agree with the exact orbit to 1e-3: exit 0, a row each."""
    assert validation_main(["exact", "2", "--seed", "3", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "on the first mode's orbit" in out
    rows = (tmp_path / "corpus_exact.csv").read_text().splitlines()
    assert len(rows) == 3 and rows[2].split(",")[8] == "1"


def test_the_time_limit_holds_inside_a_jump(monkeypatch):
    """A search's pinned solves call no continuation callback, so a limit checked at the
    points alone lets a slow search run on. Each deflated solve made to burn 2 s of
    processor time: with a 0.5 s limit the case is interrupted inside the first one, not
    after it."""
    import time

    import mmshbm.family.deflation as family

    original = family.deflated_solve

    def slow(*args, **kwargs):
        t0 = time.process_time()
        while time.process_time() - t0 < 2.0:
            pass
        return original(*args, **kwargs)

    monkeypatch.setattr(family, "deflated_solve", slow)
    case = corpus.generate(14, seed=0)[13]  # a tree whose branch jumps twice in 0.03 s
    r = corpus.run_case(case, time_limit=0.5)
    assert not r.completed and r.status.startswith("interrupted")
    assert r.cpu_seconds < 1.9  # stopped inside the first slow solve


def test_the_summary_counts_ended_families():
    """Families that end are counted on a line of their own (they stay failures)."""
    cases = corpus.generate(3, 0)
    results = [corpus.CaseResult(cases[0], True, "bound:amplitude", 0.1, 10, 0, 1.0),
               corpus.CaseResult(cases[1], False, "jump failed: the branch turns back", 0.1, 10, 1, 1.0),
               corpus.CaseResult(cases[2], False, "family ended: at amplitude 0.1 (1 Hz): ...", 0.1, 10, 1,
                                 1.0)]
    text = corpus.summary(results)
    assert re.search(r"^family ended \(.*\): 1$", text, re.M)
