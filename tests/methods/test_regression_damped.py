"""The damped paths (forced response, EPMC) change no result beyond round-off when their
residual is compiled: values stored from mmshbm at commit 8719e8d (the projection in Python).

Forced response of the damped beam (0.5 % on mode 1, 5 % above; 5 N at the last node with
mass, 40–62 Hz): the amplitude at fixed frequencies on the rising flank, solved by Newton at
that frequency (to 1e-13 of the row scales) from the interpolation between the response's
two points around it, so the value does not depend on where the step control put them.
EPMC: ``Branch.frequency_at`` (pinned Newton to 1e-12). Tolerance 1e-9 relative."""

import functools

import numpy as np
import pytest

import mmshbm
from mmshbm.methods.mms.forced import ForcedResponseProblem

#: amplitude (m) at frequency (Hz) of the forced response, per H, computed at 8719e8d
FORCED = {5: {45.0: 0.001153027556667583, 50.0: 0.001388189011135052, 55.0: 0.0017822987353867843},
          20: {45.0: 0.0011212537083791197, 50.0: 0.001354288474164128, 55.0: 0.0017605610788110552}}
#: points of those responses at 8719e8d
FORCED_POINTS = {5: 30, 20: 122}
#: frequency (Hz) at amplitude (gaps) of the EPMC backbone, H = 5, computed at 8719e8d
EPMC = {0.8: 45.81453551856432, 1.5: 54.52633541252886, 2.5: 61.46541254916839}


@functools.cache
def _beam():
    m = mmshbm.default_beam().model(21)
    return m.with_damping(modal_ratio=[0.005] + [0.05] * (len(m.l) - 1))


def _force(m):
    F = np.zeros(m.n_dof)
    F[38] = 5.0
    return F


@pytest.mark.parametrize("H", sorted(FORCED))
def test_forced_response_equals_the_stored_one(H):
    m = _beam()
    r = mmshbm.frequency_response(m, _force(m), (40.0, 62.0), harmonics=H, stability=False)
    assert len(r) == FORCED_POINTS[H]
    p = ForcedResponseProblem(m, _force(m), harmonics=H, stability=False)
    for freq, want in FORCED[H].items():
        i = int(np.flatnonzero(r.frequency > freq)[0])
        t = (freq - r.frequency[i - 1]) / (r.frequency[i] - r.frequency[i - 1])
        x = (1 - t) * r.solver.unpack(r.states[i - 1])[0] + t * r.solver.unpack(r.states[i])[0]
        w = 2 * np.pi * freq
        for _ in range(30):
            R, Jx, _, _ = p.residual_parts(x, w, 1.0, True)
            if np.abs(R / p.rowscale).max() < 1e-13:
                break
            x = x - np.linalg.solve(Jx, R)
        else:
            raise AssertionError(f"no convergence at {freq} Hz")
        got = p.amplitude(p._coefficients(x, w, 1.0)[p.amplitude_dof])
        assert abs(got / want - 1) < 1e-9, (H, freq, got, want)


@pytest.mark.filterwarnings("ignore::mmshbm.BranchWarning")
def test_epmc_backbone_equals_the_stored_one():
    m = _beam()
    b = mmshbm.backbone(m, harmonics=5, max_amplitude=3 * m.gap)
    assert b.status == "bound:amplitude"
    for gaps, want in EPMC.items():
        got = b.frequency_at(gaps * m.gap, tol=1e-12)
        assert abs(got / want - 1) < 1e-9, (gaps, got, want)
