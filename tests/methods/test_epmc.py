"""Damped nonlinear modes (EPMC): the linear limit, the conservative limit, the Jacobian,
the backbone dispatch."""

from __future__ import annotations

import numpy as np
import pytest
from finite_differences import assert_jacobian

import mmshbm
from mmshbm.core.continuation import newton
from mmshbm.methods.mms.epmc import EPMCProblem
from mmshbm.results.branch import Branch


def test_linear_damped_mode_is_the_modal_ratio_at_the_undamped_frequency():
    beam = mmshbm.default_beam().model(8)
    for zeta in (0.0, 0.004, 0.03):
        p = EPMCProblem(beam.with_damping(modal_ratio=zeta), harmonics=3)
        u = p.linear_point(0.5e-3)
        R = p.evaluate(u, False)
        assert np.abs(R).max() < 1e-12  # the linear mode solves the EPMC exactly below the gap
        rec = p.monitor(u)
        assert rec["damping_ratio"] == pytest.approx(zeta, abs=1e-14)
        assert rec["frequency"] == pytest.approx(beam.linear_frequencies(1)[0], rel=1e-13)
        assert rec["amplitude"] == pytest.approx(0.5e-3, rel=1e-12)


@pytest.mark.parametrize("projection", ["exact", "sampled"])
def test_jacobian_matches_finite_differences(projection):
    model = mmshbm.default_beam().model(8).with_damping(rayleigh=(3.0, 2e-6))
    p = EPMCProblem(model, harmonics=3, projection=projection)
    rng = np.random.default_rng(7)
    u = p.linear_point(2.5e-3) + np.r_[0.3 * rng.standard_normal(p.n_x), 0.01, 0.02]
    R, J = p.evaluate(u)
    assert_jacobian(lambda v: p.evaluate(v, False), u, J, 1e-5)


@pytest.mark.parametrize("name, H, amax", [("oscillator", 7, 5.0), ("beam8", 5, 6e-3)])
def test_zero_damping_gives_the_conservative_backbone(name, H, amax):
    """With C = 0 the EPMC branch is the conservative one: ξ = 0 and, at equal amplitude, the same
    frequency (both use the exact contact projection by default: the same equations)."""
    if name == "oscillator":
        model = mmshbm.OneDofOscillator(1, 1, 4, 1).model()
    else:
        model = mmshbm.default_beam().model(8)
    cons = mmshbm.backbone(model, harmonics=H, max_amplitude=amax)
    damped = mmshbm.backbone(model.with_damping(modal_ratio=0.0), harmonics=H, max_amplitude=amax)
    assert damped.method == "epmc" and damped.status == cons.status == "bound:amplitude"
    assert np.abs(damped.damping_ratio).max() < 1e-12
    assert damped.frequency[-1] == pytest.approx(cons.frequency[-1], rel=1e-8)
    # every EPMC point, solved by the conservative problem at the same fundamental cosine
    p = cons.solver
    e = damped.solver
    worst = 0.0
    for u in damped.states[:: max(1, len(damped) // 12)]:
        x, xi, omega = e.unpack(u)
        a = np.zeros((H + 1, p.n_c))
        a[0], a[1:] = x[:p.n_c], np.array([x[(2 * k - 1) * p.n_c:2 * k * p.n_c] for k in range(1, H + 1)])
        assert np.abs(x[2 * p.n_c::2 * p.n_c]).max() < 1e-10 * np.abs(x).max()  # no sine terms
        v = p.pack(a, omega)
        t = np.zeros(p.n_unknowns)
        t[p.n_c + int(p.cdof[0])] = 1.0  # the cosine of the contact DOF's fundamental
        v2, *_ = newton(p, v, t, v.copy(), 1e-10, 20, 1e-12)
        worst = max(worst, abs(p.unpack(v2)[1] / omega - 1))
    assert worst < 1e-8


def test_damped_backbone_dispatch_and_files(tmp_path):
    osc = mmshbm.OneDofOscillator(1, 1, 4, 1).model().with_damping(modal_ratio=0.03)
    b = mmshbm.backbone(osc, harmonics=5, max_amplitude=4.0)
    assert b.method == "epmc" and b.completed
    assert b.damping_ratio[0] == pytest.approx(0.03, rel=1e-12)
    # above the gap the stiffer closed phase raises Ω while C stays: the ratio falls
    assert b.damping_ratio[-1] < 0.03 and b.frequency[-1] > b.frequency[0]
    back = Branch.load(b.save(tmp_path / "b.npz"))
    np.testing.assert_array_equal(back.damping_ratio, b.damping_ratio)
    assert back.get_model().same_as(osc)
    np.testing.assert_allclose(back.time_signals(3, dofs=[1])[1], b.time_signals(3, dofs=[1])[1], rtol=1e-12)
    assert mmshbm.backbone(mmshbm.OneDofOscillator().model(), max_amplitude=2.0).damping_ratio.max() == 0


def test_amplitude_gradient_matches_finite_differences():
    """The pinned solves of the family guard's jumps use the amplitude's gradient."""
    model = mmshbm.default_beam().model(8).with_damping(modal_ratio=0.01)
    p = EPMCProblem(model, harmonics=5)
    b = mmshbm.backbone(model, harmonics=5, max_amplitude=3 * model.gap)
    for u in b.states[[5, len(b) // 2, -1]]:
        A, g = p.amplitude_and_gradient(u)
        assert A == p.monitor(u)["amplitude"]
        fd = np.array([(p.amplitude_value(u + e) - p.amplitude_value(u - e)) / 2e-7
                       for e in 1e-7 * np.eye(len(u))])
        # the peak's instant is refined by a parabola through the fine samples: its error,
        # O(h^3) of the grid, moves the gradient by well under 1e-3 of its size
        assert np.abs(g - fd).max() <= 1e-3 * np.abs(fd).max()


@pytest.mark.slow
def test_damped_mode_jumps_over_the_internal_resonance_loop():
    """At H = 20 the damped beam's mode meets harmonics 4 and 5 near its second mode at
    3.8 gaps, where plain path following closes into a loop; the family guard jumps over
    it to the bound, and below the loop the damped mode (0.5 % damping of mode 1) stays
    at the conservative backbone's frequency: the damping shifts it by O(ζ²) and the
    higher modes' damping by less than 0.5 %."""
    beam = mmshbm.default_beam().model(21)
    damped = beam.with_damping(modal_ratio=[0.005] + [0.05] * (len(beam.l) - 1))
    with pytest.warns(mmshbm.BranchWarning):
        b = mmshbm.backbone(damped, harmonics=20)
    assert b.status == "bound:amplitude"
    front = b.family_front()
    assert b.amplitude[front].max() >= 6 * beam.gap
    assert any(s.kind == "jump" for s in b.special_points)
    with pytest.warns(mmshbm.BranchWarning):
        ref = mmshbm.backbone(beam, harmonics=20, max_amplitude=4.2 * beam.gap)
    for gaps in (3.0, 4.0):
        assert b.frequency_at(gaps * beam.gap) == pytest.approx(ref.frequency_at(gaps * beam.gap), rel=5e-3)


@pytest.mark.slow
def test_damped_mode_follows_the_path_past_a_tongue_it_comes_back_from():
    """0.5 % on every mode, H = 7: the branch dips below its frontier at the 6:1 tongue
    (1.3 gaps) and comes back up by itself; the jump lands where the path does, and the
    mode reaches 10 gaps at the conservative backbone's frequency (the damping shifts it by
    O(ζ²) ~ 1e-5, far below the 1e-3 asked)."""
    beam = mmshbm.default_beam().model(21)
    with pytest.warns(mmshbm.BranchWarning):
        b = mmshbm.backbone(beam.with_damping(modal_ratio=0.005), harmonics=7)
        ref = mmshbm.backbone(beam, harmonics=7)
    assert b.status == ref.status == "bound:amplitude"
    assert b.frequency[-1] == pytest.approx(ref.frequency[-1], rel=1e-3)
