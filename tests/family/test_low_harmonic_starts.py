"""The deflated search's starts from the low-harmonic problem
(:meth:`mmshbm.methods.mms.family_starts.MMSHBMStarts._low_orbits`): where the family
beyond a frontier coexists with the branch apart from it in frequency, its orbit lies near
the fundamental's at low H, where no start taken from the branch comes."""

import numpy as np
import pytest

import mmshbm
from mmshbm.family.guard import FamilyGuard
from mmshbm.methods.registry import make_problem
from validation import corpus

#: a chain of four masses with two stops (one each side): its H = 9 branch leaves the
#: family at 0.112 m (2.8 gaps, 7.17 Hz; harmonic 2 takes the energy, 2Ω near mode 2),
#: and the family goes on beyond it at 11.0 Hz, a branch of its own from 0.07 m up
CHAIN = {"masses": [0.03785365304653162, 0.0890879739396437, 0.074045239049943, 0.09537022506851092],
         "springs": [2043.106275816331, 528.504805568046, 3316.68023938681, 388.9930417759374],
         "parents": [-1, 0, 1, 2], "ground": [False, False, False, False],
         "ground_k": [3691.189320362668, 22877.0888317719, 81.75257903720465, 128.16262603905537],
         "hosts": [3, 1], "node_k": [659.569855600894, 52370.790562126305],
         "gaps": [0.03957721147350613, 0.050977842034003476], "sides": [1, -1]}


@pytest.fixture(scope="module")
def chain():
    return corpus._spring_mass_model(CHAIN)


def test_the_low_harmonic_orbits_are_orbits_at_h_and_include_the_family_apart_in_frequency(chain):
    """At 0.1146 m (the search's first target) every start offered is an orbit of the
    H = 9 pinned system (residual at most 1e-8, the solves' tolerance 1e-10 times the
    scaling's condition; the amplitude to 1e-8 relative), no two alike, and one is the
    family's orbit near 11 Hz with the fundamental's majority — far from the frontier's
    7.17 Hz."""
    p = make_problem(chain, harmonics=9)
    starts = p.family_starts()
    starts.amplitude_max = 10 * chain.gap
    A = 0.1146
    out = starts._low_orbits(FamilyGuard(0.5, 60), A, [])
    assert out
    for _, u in out:
        assert np.abs(p.residual(u)).max() < 1e-8
        assert abs(p.amplitude_value(u) / A - 1) < 1e-8
    us = [u for _, u in out]
    assert all(np.abs(u - v).max() > 1e-6 for i, u in enumerate(us) for v in us[:i])
    family = [u for u in us if 10.5 < p.frequency_of(u) < 11.5 and p.fundamental_share(u) >= 0.5]
    assert family


def test_the_search_reaches_the_coexisting_family_and_the_bound(chain):
    """The backbone ends at 10 gaps on the family, on the coexisting family that goes on
    near 11 Hz (above 10 Hz: far from the frontier's 7.17 Hz), with the fundamental's
    majority."""
    branch = mmshbm.backbone(chain, harmonics=9)
    assert branch.status == "bound:amplitude", branch.status
    assert branch.records["on_family"][-1] == 1.0
    assert branch.records["fundamental_share"][-1] >= 0.5
    assert branch.frequency[-1] > 10.0
