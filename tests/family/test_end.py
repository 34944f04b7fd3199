"""Why the family following ends a branch is a value on the result
(:class:`mmshbm.family.end.FamilyEnd`), and its status text is built from it."""

import pickle

import numpy as np

import mmshbm
from mmshbm.core.status import Status
from mmshbm.family.end import FamilyEnd


def test_a_family_that_ends_carries_what_was_tried():
    """A threshold too strict to land (97 % of the energy in the fundamental, beam on 21
    elements at H = 7): the continued orbit loses it and no search lands. The status's
    cause says where the share crosses 0.97 (between the frontier point and the next, as
    the branch's records have it), up to where the family was sought, and every pinned
    solve tried (each beyond the frontier, none landed); the text is the value's."""
    model = mmshbm.default_beam().model(21)
    b = mmshbm.backbone(model, harmonics=7, family_share=0.97)
    assert b.status.kind == Status.FAMILY_ENDED
    end = b.status.cause
    assert isinstance(end, FamilyEnd) and end.ended
    assert str(b.status) == f"family ended: {end.detail()}"
    c = end.crossing
    assert c.share_before >= 0.97 > c.share_after
    assert c.amplitude_before <= c.amplitude <= c.amplitude_after or \
        c.amplitude_after <= c.amplitude <= c.amplitude_before
    shares = b.records["fundamental_share"]
    i = int(np.flatnonzero(np.isclose(b.amplitude, c.amplitude_before, rtol=0, atol=0))[0])
    assert shares[i] == c.share_before and shares[i + 1] == c.share_after
    assert end.frontier == c.amplitude_before and end.searched_to > end.frontier
    assert end.attempts and all(a.amplitude > end.frontier for a in end.attempts)
    assert "landed" not in end.outcomes()
    again = pickle.loads(pickle.dumps(b.status))
    assert again == b.status and repr(again.cause) == repr(end)  # repr: nan == nan


def test_a_status_without_cause_reads_as_before():
    """Other statuses carry no cause; the text and its parse are unchanged."""
    s = Status.parse("jump failed: no orbit")
    assert s.cause is None and s.kind == Status.JUMP_FAILED and s.detail == "no orbit"
    assert Status("family ended", "x", cause=1).with_detail("y").cause == 1
