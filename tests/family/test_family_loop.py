"""A branch that goes round a closed loop of orbits off the family (a clearance whose
frequency climbs six-fold within a few tenths of a gap past grazing, through tongues of
harmonics up to 15 of four modes): the family guard asks for a jump on the loop's second
round, and the backbone goes on to its bound on the first mode's family."""

import numpy as np
import scipy.linalg as sl

import mmshbm
from validation import corpus


def test_a_closed_loop_is_left_by_a_jump_and_the_family_reaches_its_bound():
    """5-mass chain, symmetric clearance of 2 cm at the last mass (a stiff node spring),
    H = 15: the branch used to go round a loop between 0.74 and 1.09 gaps at 0.3639 Hz
    until its step budget ("max_steps"). The family's frequency rises from the open f₁
    toward the first frequency with the node held, its limit as the amplitude grows
    (independent of the code: an eigenproblem of M and K); at 10 gaps it lies within
    10 % below that limit, with the fundamental's majority, where plain path following
    reaches 10 gaps locked in a tongue at 0.301 Hz."""
    model = corpus.generate(226, 28)[225].model()
    assert model.n_contacts == 2
    b = mmshbm.backbone(model, harmonics=15, max_amplitude=10 * model.gap)
    assert b.status == "bound:amplitude" and b.completed
    assert "loop" in {s.data.get("reason") for s in b.special_points if s.kind == "jump"}
    M, K = (np.asarray(x.toarray() if hasattr(x, "toarray") else x) for x in (model.M, model.K))
    held = model.l  # the DOFs with mass; the massless node held at rest
    w2_held = sl.eigh(K[np.ix_(held, held)], M[np.ix_(held, held)], eigvals_only=True)[0]
    f_held = np.sqrt(w2_held) / (2 * np.pi)
    f_open = model.linear_frequencies(1)[0]
    assert f_held > 6 * f_open
    assert 0.9 * f_held < b.frequency[-1] < f_held
    assert b.records["on_family"][-1] == 1.0 and b.records["fundamental_share"][-1] >= 0.5
