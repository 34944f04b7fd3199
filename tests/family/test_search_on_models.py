"""The search beyond a frontier (:mod:`mmshbm.family.deflation`) on the beam and on a slice
of the random corpus: it reaches the amplitude bound on an orbit that satisfies the
definition (docs/resonances.md), and where plain path following reaches the bound on
the family too, at the same orbit."""

import pytest

import mmshbm
from validation import corpus


@pytest.fixture(scope="module")
def beam21():
    return mmshbm.default_beam().model(21)


@pytest.mark.parametrize("harmonics", [7, 15])
def test_the_search_reaches_10_gaps_on_the_family(beam21, harmonics):
    """H = 7 (6:1 and 5:1 tongues) and H = 15 (tongues, a filtered passage, a fold of the
    backbone near 7 gaps): the branch ends at the bound after at least one search, on an
    orbit whose fundamental holds the majority of the kinetic energy and whose frequency
    lies in the first mode's band (between the linear mode's and the held-contact mode's,
    each widened by the band's 1 % slack)."""
    branch = mmshbm.backbone(beam21, harmonics=harmonics)
    assert branch.status == "bound:amplitude", branch.status
    assert branch.records["on_family"][-1] == 1.0
    assert branch.records["fundamental_share"][-1] >= 0.5
    assert any(s.kind == "jump" for s in branch.special_points)
    f = branch.frequency
    assert 0.99 * f[0] <= f[-1] <= 1.01 * _held_frequency(beam21, harmonics)


def _held_frequency(model, harmonics):
    """The first mode's frequency (Hz) with every contact DOF held (the band's top)."""
    from mmshbm.methods.mms.conservative import MMSHBMProblem

    return float(MMSHBMProblem(model, harmonics=harmonics).family_frequency_ceiling())


#: the slice of tests/harness/test_corpus.py (small H, no beams)
SLICE = [c for c in corpus.generate(40, seed=0, harmonics=(1, 3, 5)) if c.kind != "beam"][:16]


@pytest.mark.parametrize("case", SLICE, ids=lambda c: c.label)
def test_the_deflated_search_reaches_the_bound_on_the_corpus_slice(case):
    """Every case ends at its bound on the family (a run past 30 s of processor time would
    end "interrupted")."""
    r = corpus.run_case(case, time_limit=30.0)
    assert r.completed, (case, r.status)


def test_a_family_that_comes_back_beyond_the_frontier_only_along_the_branch_is_followed_there():
    """A tree of five masses whose one-sided stop is stiffer than its ground springs: the
    backbone's frequency barely moves (0.819–0.823 Hz) while the amplitude folds back and
    forth between 3.4 and 5.25 gaps on the family; past the first fold (5.19 gaps) no
    pinned solve from the frontier converges beyond it, and the family is reached again
    by following the branch on. The orbit at the bound is then the plain path's (one
    solution of the pinned equations: the frequencies agree to the Newton tolerance
    times the condition, 1e-8 relative)."""
    params = {"masses": [0.011765912204887216, 0.29549928060619957, 0.10673599878865297, 1.0840906028984894,
                         1.5397472761873718],
              "springs": [29.51644003555689, 1136.3943781075513, 2266.9443388030386, 29.95178034537588,
                          213.0568810435389],
              "parents": [-1, 0, 1, 1, 1], "ground": [False, True, False, False, False],
              "ground_k": [12.576622058724876, 725.8603506649492, 124.76717049242505, 116.8646231421379,
                           80005.05213016008],
              "hosts": [4], "node_k": [54752.525748633394], "gaps": [0.0078734020723788], "sides": [-1]}
    model = corpus._spring_mass_model(params)
    path = mmshbm.backbone(model, harmonics=15, follow="path")
    deflated = mmshbm.backbone(model, harmonics=15)
    assert path.status == deflated.status == "bound:amplitude", deflated.status
    assert path.records["fundamental_share"][-1] > 0.5
    assert deflated.records["on_family"][-1] == 1.0
    assert abs(deflated.frequency[-1] / path.frequency[-1] - 1) < 1e-8
