"""The forced response of the beam's tip damper across the corners of its branch: where stick
arcs vanish (H = 7 near 22.91 Hz, four of six) the tangent turns by 107° within 1e-3 Hz,
and pseudo-arclength alone stopped there (H = 7) or turned back (H = 11 near 33.12 Hz); the
continuation crosses such corners at fixed frequency (core/steps.py ``_corner_step``,
FrictionForcedProblem.corner_parameter)."""

import numpy as np
import pytest

import mmshbm
from mmshbm.methods.mms.friction_forced import FrictionForcedProblem


@pytest.mark.parametrize(("H", "band", "corner"), [(7, (22.0, 24.0), 22.91), (11, (32.0, 34.0), 33.12)])
def test_the_tip_damper_response_crosses_its_corners(H, band, corner):
    """Measured: 24 and 25 points, monotone in frequency, the continued amplitudes within
    1.1e-7 (H = 7) and 2.2e-6 (H = 11) of fixed-frequency solves from the linear responses
    (the corrector's step tolerance); asserted 1e-5. Within 2e-3 Hz of the corner the
    residual does not bound the error (the friction rows feel the node only on its short stick
    arcs): the continued point at 22.910001 Hz (H = 7) has six stick pieces and a scaled
    residual of 3.4e-11, below the continuation's 1e-10, and lies 1.9e-5 (amplitude) from the
    fixed-frequency solution (two pieces, residual 1e-11), 1e-5 away in the scaled unknowns;
    asserted 3e-5 there."""
    model = mmshbm.tip_damper_model(normal_load=1.0)
    force = mmshbm.tip_damper_force(model, 1.0)
    r = mmshbm.frequency_response(model, force, band, harmonics=H)
    assert r.status == "bound:frequency"
    assert r.frequency[0] == pytest.approx(band[0]) and r.frequency[-1] == pytest.approx(band[1])
    assert np.all(np.diff(r.frequency) > 0)  # no turning back at the corner
    p = FrictionForcedProblem(model, force, H)
    after = np.flatnonzero(r.frequency > corner)[:4]
    for i in np.concatenate([[0], after, [len(r.frequency) - 1]]):
        f = r.frequency[i]
        u, ok = p.solve_at(f, p.start_point(f))
        assert ok
        near = abs(f - corner) < 2e-3
        assert p.monitor(u)["amplitude"] == pytest.approx(r.amplitude[i], rel=3e-5 if near else 1e-5)


def _jenkins_beam():
    """NLvib's example-08 beam with a Jenkins element at node 4 (k_t = 1e7 N/m, μN = 1.5 N),
    0.2 N at the tip, 1 % stiffness-proportional damping at the first stuck mode."""
    import scipy.linalg as la

    from mmshbm.fe.euler_bernoulli import cantilever

    M, K, dofs = cantilever(2.0, 0.3, 0.1, 185e9, 7830.0, 8)
    Md, Kd = M.toarray(), K.toarray()
    node4, tip = int(dofs[3, 0]), int(dofs[-1, 0])
    keep = [i for i in range(len(Md)) if i != node4]
    w_stuck = np.sqrt(la.eigh(Kd[np.ix_(keep, keep)], Md[np.ix_(keep, keep)], eigvals_only=True)[0])
    model = mmshbm.Model.from_matrices(M, K, [], [], [], damping=(2e-2 / w_stuck) * Kd, amplitude_dof=tip)
    model = model.with_friction(node4, 1.0, normal_load=1.5, tangential_stiffness=1e7)
    force = np.zeros(model.n_dof)
    force[tip] = 0.2
    return model, force


def test_the_slip_onset_kink_is_crossed_in_one_step():
    """At the onset of slip of a Jenkins node the slider's harmonics start to grow linearly
    from zero: the branch in the unknowns has a kink (the tangent turns by ~50° at one
    point), not a bend. The continuation crosses it without halving the step down to
    corner_ds (measured on 19.5–21 Hz: 53 points, the smallest step the first, 0.02; halving
    to the kink instead: 90 points, steps down to 6.1e-5), and the points beside the kink are
    those of fixed-frequency solves."""
    model, force = _jenkins_beam()
    r = mmshbm.frequency_response(model, force, (19.5, 21.0), harmonics=13)
    assert r.status == "bound:frequency"
    slip = r.records["slip_fraction"]
    onsets = np.flatnonzero(np.diff((slip > 0).astype(int)) != 0)
    assert len(onsets) == 1  # one slip onset in the band, on the rising flank
    i = int(onsets[0])
    assert r.step_size[1:].min() > 1e-3  # no step halved toward corner_ds = 1e-4
    p = FrictionForcedProblem(model, force, 13)
    for j in (i, i + 1, i + 2):
        u, ok = p.solve_at(r.frequency[j], r.states[j])
        assert ok
        # Newton from the continued point to the fixed-frequency one: both at the corrector's
        # round-off stop, the amplitude well conditioned (no pole nearby)
        assert p.monitor(u)["amplitude"] == pytest.approx(r.amplitude[j], rel=1e-9)
