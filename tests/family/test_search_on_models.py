"""The deflated search beyond a frontier (``family_search="deflated"``) on the beam and on a
slice of the random corpus: it reaches the amplitude bound on the family, and where the
staged search reaches it too, at the same orbit."""

import pytest

import mmshbm
from validation import corpus


@pytest.fixture(scope="module")
def beam21():
    return mmshbm.default_beam().model(21)


@pytest.mark.parametrize("harmonics", [7, 15])
def test_the_deflated_search_reaches_10_gaps_at_the_staged_searchs_orbit(beam21, harmonics):
    """H = 7 (6:1 and 5:1 tongues) and H = 15 (tongues, a filtered passage, a fold of the
    backbone near 7 gaps): both searches end at the bound; the orbit there is one solution
    of the pinned equations, so the frequencies agree to the Newton tolerance times the
    condition (1e-8 relative; measured below 1e-12)."""
    staged = mmshbm.backbone(beam21, harmonics=harmonics)
    deflated = mmshbm.backbone(beam21, harmonics=harmonics, family_search="deflated")
    assert staged.status == deflated.status == "bound:amplitude", deflated.status
    assert deflated.records["on_family"][-1] == 1.0
    assert any(s.kind == "jump" for s in deflated.special_points)
    assert abs(deflated.frequency[-1] / staged.frequency[-1] - 1) < 1e-8


#: the slice of tests/test_corpus.py (small H, no beams), run with the deflated search
SLICE = [c for c in corpus.generate(40, seed=0, harmonics=(1, 3, 5)) if c.kind != "beam"][:16]


@pytest.mark.parametrize("case", SLICE, ids=lambda c: c.label)
def test_the_deflated_search_reaches_the_bound_on_the_corpus_slice(case):
    """Every case ends at its bound on the family (a run past 30 s of processor time would
    end "interrupted")."""
    r = corpus.run_case(case, time_limit=30.0, options={"family_search": "deflated"})
    assert r.completed, (case, r.status)
