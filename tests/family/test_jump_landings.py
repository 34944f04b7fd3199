"""Where the search beyond a frontier lands (mmshbm.family.deflation, mmshbm.family.follower)."""

import warnings

import mmshbm


def test_the_beam_passes_its_tongues_to_10_gaps_within_the_truncation_of_h():
    """The 100-element beam at H = 15: tongues with modes 2 and 3 (a 13:1 filtered passage,
    the side of a 12:1 tongue that keeps the fundamental's majority up to a fold near 7
    gaps). The branch reaches 10 gaps on the family, within the truncation of H of the
    H = 11 branch: H = 11 to 15 moves the 21-element beam's frequency at 10 gaps by
    0.19 %, so 5e-3 bounds it with a margin for the finer mesh."""
    model = mmshbm.default_beam().model(100)
    top = 10 * model.gap
    b = mmshbm.backbone(model, harmonics=15, max_amplitude=top)
    assert b.status == "bound:amplitude"
    assert b.records["on_family"][-1] == 1.0 and b.records["fundamental_share"][-1] > 0.5
    h11 = mmshbm.backbone(model, harmonics=11, max_amplitude=top)
    assert abs(b.frequency[-1] / h11.frequency[-1] - 1) < 5e-3


def test_the_family_goes_on_above_a_6_to_1_tongue():
    """A 7-mass chain (one-sided, H = 9) meets the 6:1 resonance with mode 2 at 3.5 gaps:
    below f2/6 its branch becomes the tongue (locked near f2/6, folding back at 7.59
    gaps). A first-mode orbit exists above the tongue: the last jump leaves the family
    below f2/6 and lands above it, and the fundamental holds the majority from there to
    10 gaps (measured 0.82 at the bound); the family does not end at the tongue's fold."""
    from validation import corpus

    case = corpus.generate(79, seed=0, contacts=("one-sided",))[78]
    assert (case.kind, case.harmonics, len(case.params["masses"])) == ("chain", 9, 7)
    model = case.model()
    f2 = model.linear_frequencies(2)[1]
    b = mmshbm.backbone(model, harmonics=9, max_amplitude=10 * model.gap)
    assert b.status == "bound:amplitude" and b.records["on_family"][-1] == 1.0
    last = [s for s in b.special_points if s.kind == "jump"][-1]
    assert last.data["frequency_from"] < f2 / 6 < last.data["frequency_to"]
    front = b.family_front()
    above = front[front >= last.index]
    assert min(b.records["fundamental_share"][above]) >= 0.5


def test_a_bound_the_capped_searches_miss_is_reached_from_above():
    """A 4-mass chain at H = 31 whose branch meets a tongue at 1.33 gaps, with its bound
    at 1.56 gaps: every search capped by the bound misses the family (the run ended
    "jump failed", saying the bound lay inside a tongue). It does not: an independent run
    to 10 gaps jumps from 1.33 gaps, lands at 3.02 gaps and fills the family back down
    to 1.33 gaps, through 1.56 gaps. The search above the bound lands (2.28 gaps) and
    the branch through the landing, followed back down onto the bound, is that orbit:
    the run completes at the frequency the 10-gap run has at 1.56 gaps (``frequency_at``
    solves it there: the same to 1e-9)."""
    from validation import corpus_exact as ce

    model = ce.chains(69, seed=21)[68].model()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        short = mmshbm.backbone(model, harmonics=31, max_amplitude=1.56 * model.gap)
        assert short.completed, short.status
        full = mmshbm.backbone(model, harmonics=31, max_amplitude=10 * model.gap)
        assert full.completed
        assert abs(short.frequency[-1] / full.frequency_at(1.56 * model.gap) - 1) < 1e-9
