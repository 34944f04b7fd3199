"""A forced response through thin folds: a step longer than a fold's radius of curvature
must not land on the piece beyond it (which runs the other way) and send the branch back
along itself.

The damped beam (0.5 % on mode 1, 5 % on modes 2–10), 5 N at DOF 38, H = 10: near 56 Hz
the resonant branch makes narrow loops (5Ω near the second mode), and on long steps the
path follower used to land on the far side of a fold there, turn back at the fold and run
the branch it had come up back down to 40 Hz (385 points, status ``bound:frequency`` at the
lower end). The reference is the same response followed with short steps (``ds_max`` =
0.002, every sign change of the orientation accepted), which resolve the loops: its peak
and the fold where the unstable branch meets the non-resonant one.
"""

from __future__ import annotations

import numpy as np
import pytest

import mmshbm


@pytest.fixture(scope="module")
def beam_and_force():
    m = mmshbm.default_beam().model(21)
    m = m.with_damping(modal_ratio=[0.005] + [0.05] * (len(m.l) - 1))
    F = np.zeros(m.n_dof)
    F[38] = 5.0
    return m, F


def _folds(r):
    return [float(r.frequency[i]) for name, i in r.special_points if name == "fold"]


def test_the_response_passes_the_peak_and_ends_on_the_non_resonant_branch(beam_and_force):
    m, F = beam_and_force
    r = mmshbm.frequency_response(m, F, (40.0, 62.0), harmonics=10, stability=False)
    ref = mmshbm.frequency_response(m, F, (40.0, 62.0), harmonics=10, stability=False, ds=0.002,
                                    ds_max=0.002, branch_point_ds=None)
    assert ref.status == "bound:frequency" and ref.frequency[-1] == pytest.approx(62.0)
    assert r.status == "bound:frequency"
    assert r.frequency[-1] == pytest.approx(62.0, abs=1e-9)
    # the end lies on the non-resonant branch (ref: 0.27 gaps), not on the resonant one
    assert r.amplitude[-1] == pytest.approx(ref.amplitude[-1], rel=1e-6)
    # the peak of the resonant branch (both runs shorten their steps at its fold: 2e-3 Hz
    # and 1e-4 of the amplitude are a few of their steps' share)
    top, top_ref = int(np.argmax(r.amplitude)), int(np.argmax(ref.amplitude))
    assert r.frequency[top] == pytest.approx(ref.frequency[top_ref], abs=2e-3)
    assert r.amplitude[top] == pytest.approx(ref.amplitude[top_ref], rel=1e-4)
    # the unstable branch comes down to the fold near 50.8 Hz and turns up to 62 Hz there
    # (a step's share of the frequency at the fold: 0.02 Hz)
    assert r.frequency[top:].min() == pytest.approx(ref.frequency[top_ref:].min(), abs=0.02)
    assert _folds(r)[-1] == pytest.approx(_folds(ref)[-1], abs=0.02)
    # each frequency is passed as often as the reference passes it (no retraced stretch)
    for f in (45.0, 52.0, 57.0, 60.0):
        crossings = np.count_nonzero(np.diff(np.sign(r.frequency - f)))
        assert crossings == np.count_nonzero(np.diff(np.sign(ref.frequency - f)))
