"""Jumps that land by continuing the orbit in the harmonics (mmshbm.family.stages's last
resort, MMS-HBM's ``harmonic_landing``)."""

import numpy as np
import scipy.linalg as la

import mmshbm
from validation import corpus


def _held_frequency(model) -> float:
    """First eigenfrequency (Hz) with every contact DOF held (K_ll, M_ll): the frequency a
    clearance's backbone tends to far above the gaps, where the mass spends the period in
    contact with both stops' springs as with one linear spring."""
    b = model.blocks
    K, M = (np.asarray(x.toarray() if hasattr(x, "toarray") else x) for x in (b["K_ll"], b["M_ll"]))
    return float(np.sqrt(la.eigh(K, M, eigvals_only=True)[0]) / (2 * np.pi))


def test_a_clearance_lands_from_the_fundamental_alone_where_the_h3_family_ends():
    """A heavy mass (84.8 kg) held by a stiff clearance in a 3-mass chain, H = 15: the
    backbone climbs from the open frequency (0.050 Hz) towards the one with the contact
    held (0.2512 Hz) and meets the second open mode (0.266 Hz) on the way; the branch
    climbs the tongue onto that mode (the fundamental's share 0), and so does the
    auxiliary H = 3 branch, which ends below 1.8 gaps, so no predictor reaches the family
    above. The family with the fundamental alone (H = 1) meets no such tongue; its orbit
    raised to H = 15 two harmonics at a time lands, and the backbone reaches 10 gaps just
    below the held frequency (closed form: the eigenvalue with the contact held;
    measured 1.5e-5 below it)."""
    case = corpus.generate(169, seed=0, contacts=("clearance",))[168]
    assert (case.kind, case.harmonics, len(case.params["masses"])) == ("chain", 15, 3)
    model = case.model()
    b = mmshbm.backbone(model, harmonics=15, max_amplitude=10 * model.gap)
    assert b.status == "bound:amplitude" and b.records["on_family"][-1] == 1.0
    assert b.records["fundamental_share"][-1] > 0.99
    f_held = _held_frequency(model)
    assert 0 < 1 - b.frequency[-1] / f_held < 1e-4
