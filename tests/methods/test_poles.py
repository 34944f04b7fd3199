"""Poles of the condensed dynamic stiffness carried by extra unknowns (mmshbm.methods.mms.condensation.poles):
the same residual as without them away from the poles, and a regular, precise problem at
kΩ = ω_j exactly."""

import numpy as np
import pytest

import mmshbm
from mmshbm.core.continuation import newton
from mmshbm.methods.mms.conservative import MMSHBMProblem

OSC = mmshbm.OneDofOscillator(1.0, 1.0, 4.0, 1.0)  # node clamped: ω₂ = √5; 2Ω = ω₂ at Ω = √5/2


def test_pole_pairs_are_those_in_the_frequency_range():
    p = MMSHBMProblem(OSC.model(), 5)
    assert p.pole_set.pairs == [(2, 0)]  # √5/2 = 1.118 lies in [ω₁ = 1, ω_zero-gap]; √5/3 = 0.75 does not
    beam = MMSHBMProblem(mmshbm.default_beam().model(21), 15)
    clamped = np.sqrt(beam.pole_set.modes_w[[j for _, j in beam.pole_set.pairs]] ** 2)
    f = clamped / (2 * np.pi) / np.array([k for k, _ in beam.pole_set.pairs])
    lo, hi = (w / (2 * np.pi) for w in beam._omega_range())
    assert np.all((f >= 0.97 * lo) & (f <= 1.03 * hi))
    assert (5, 0) in beam.pole_set.pairs and (14, 1) in beam.pole_set.pairs  # 285.7/5, 782.5/14 Hz


@pytest.mark.parametrize("factor", [0.9, 1.05, 1.3])
def test_same_residual_as_without_poles_away_from_them(factor):
    with_p = MMSHBMProblem(OSC.model(), 5)
    without = MMSHBMProblem(OSC.model(), 5, poles=False)
    rng = np.random.default_rng(3)
    a = rng.normal(size=(6, 1)) * 0.5 ** np.arange(6)[:, None]
    omega = factor * with_p.omega_ref
    R1 = with_p.evaluate(with_p.pack(a, omega), jacobian=False) * with_p.rowscale
    R0 = without.evaluate(without.pack(a, omega), jacobian=False) * without.rowscale
    np.testing.assert_allclose(R1[:6], R0, rtol=0, atol=1e-10 * np.abs(R0).max())
    assert abs(R1[6]) < 1e-10 * abs(with_p._pole_w2[0] * with_p.eta_scale[0])  # η at its value


def test_exactly_on_the_pole_newton_converges_quadratically():
    """At 2Ω = ω₂ exactly, K_ll − (2Ω)² M_ll is singular; with the pole unknown the
    pinned-frequency problem is regular and Newton reaches 1e-13."""
    p = MMSHBMProblem(OSC.model(), 5)
    without = MMSHBMProblem(OSC.model(), 5, poles=False, backend="banded")  # an LU: no pole test of its own
    omega = np.sqrt(5.0) / 2
    br = mmshbm.backbone(OSC.model(), harmonics=5, max_amplitude=10.0)
    i = int(np.argmin(np.abs(2 * np.pi * br.frequency - omega)))
    u = br.states[i].copy()
    u[-1] = omega / p.omega_ref
    t = np.zeros(p.n_unknowns)
    t[-1] = 1.0  # the arclength row pins Ω
    u_sol, nit, hist, J = newton(p, u, t, u, 1e-13, 12)
    assert hist[-1] <= 1e-13 and nit <= 6
    assert np.isfinite(np.linalg.cond(np.vstack([J, t]))) and np.linalg.cond(np.vstack([J, t])) < 1e8
    # without the pole unknown, D_2 is of order 1/eps there: the force D_2 a_2 is ∞·0
    D = without.cond.dynamic_stiffness(omega, 5, derivative=False)
    assert np.abs(D[2]).max() > 1e12 * np.abs(D[0]).max()


def test_batched_contact_signals_equal_the_per_point_ones():
    """contact_signals_many (the branch checks' batch) gives each point's contact_signals,
    pole unknowns included, and leaves the corrector's cached stiffness as it was."""
    br = mmshbm.backbone(OSC.model(), harmonics=5, max_amplitude=6.0)
    p = br._require_solver()
    assert p.n_poles == 1
    tau = np.linspace(0.0, 2 * np.pi, 37)
    cached = p._cached
    q, lam = p.contact_signals_many(br.states, tau)
    assert p._cached is cached
    assert q.shape == lam.shape == (len(br), 1, len(tau))
    for i in (0, len(br) // 2, len(br) - 1):
        _, q_i, lam_i = p.contact_signals(br.states[i], tau)
        np.testing.assert_allclose(q[i, 0], q_i, rtol=0, atol=1e-14 * np.abs(q_i).max())
        np.testing.assert_allclose(lam[i, 0], lam_i, rtol=0, atol=1e-12 * np.abs(lam_i).max())
    with pytest.raises(ValueError, match="states must have shape"):
        p.contact_signals_many(np.zeros((2, p.n_unknowns + 1)), tau)


def test_amplitude_gradient_in_the_pole_unknowns():
    """Amplitude at a DOF with mass, poles sharing harmonics (a beam clearance, 28 poles on
    15 harmonics): the gradient in every η, taken one recovery per group of distinct
    harmonics, is each pole's own recovery (to round-off) and the central difference of
    the amplitude (an error of order h² plus round-off ε·A/h)."""
    from validation import corpus

    model = corpus.generate(291, 29)[290].model()
    br = mmshbm.backbone(model, harmonics=15, max_amplitude=1.1 * model.gap)
    p = br._require_solver()
    assert not p._amp_in_c and p.n_poles > 15 > len(p._pole_groups) > 1
    n_a = (p.H + 1) * p.n_c
    u = br.states[len(br) - 1]
    amplitude, grad = p.amplitude_and_gradient(u)
    a, omega = p.unpack(u)
    _, cosk, _, s = p._amplitude_peak(u)
    zero_a = np.zeros_like(a)
    h = 1e-6
    for q in range(p.n_poles):
        e = np.zeros(p.n_poles)
        e[q] = 1.0
        own = s * (p._amplitude_row(zero_a, omega, e) @ cosk) * p.colscale[n_a + q]
        assert abs(grad[n_a + q] - own) <= 4 * np.finfo(float).eps * abs(own)  # one product either way
        du = np.zeros(p.n_unknowns)
        du[n_a + q] = h
        fd = (p.amplitude_value(u + du) - p.amplitude_value(u - du)) / (2 * h)
        # h² terms of the moving peak, plus the amplitude's round-off (~100 terms of ε·A) over h
        assert abs(fd - grad[n_a + q]) <= 1e-6 * np.abs(grad).max() + 1e-12 * amplitude / h
