"""Damped nonlinear modes (EPMC) with Coulomb friction: the stuck limit against the linear
mode of the stuck structure, the energy identity ξ∮q̇ᵀMq̇ = viscous + friction work at every
point, convergence in H, and central differences of the Jacobian."""

import numpy as np
import pytest

import mmshbm
from mmshbm.methods.mms.friction_epmc import FrictionEPMCProblem

M_, K1, K2, C_ = 1.0, 1.0, 2.0, 0.05
S = 0.1  # slip force μN (N); the stuck mode slips from k2·A = s, A = 0.05 m


def jenkins(c=C_):
    M = np.diag([M_, 0.0])
    K = np.array([[K1 + K2, -K2], [-K2, K2]])
    base = mmshbm.Model.from_matrices(M, K, [], [], [], damping=np.diag([c, 0.0]), amplitude_dof=0)
    return base.with_friction(1, 0.5, normal_load=2 * S)


def mass_work(p, u):
    """∮ q̇ᵀ M q̇ dt over a period (Parseval)."""
    Q = p.coefficients(u)[p.model.l]
    _, _, _, _, omega = p.unpack(u)
    k = np.repeat(np.arange(1, p.H + 1), 2)
    return np.pi * omega * float(np.einsum("j,ij,ij->", k**2, Q[:, 1:], p.M @ Q[:, 1:]))


def test_backbone_is_the_stuck_mode_then_friction_damps_it():
    with np.errstate(all="raise"):
        branch = mmshbm.backbone(jenkins(), harmonics=7, max_amplitude=1.0, start_amplitude=0.01)
    assert branch.status.startswith("bound")
    w_stuck = np.sqrt((K1 + K2) / M_)
    stuck = branch.amplitude < 0.049
    assert stuck.sum() >= 3
    np.testing.assert_allclose(branch.damping_ratio[stuck], C_ / (2 * M_ * w_stuck), rtol=1e-10)
    np.testing.assert_allclose(branch.frequency[stuck], w_stuck / (2 * np.pi), rtol=1e-12)
    # slipping: more damping, lower frequency, toward the free structure (ω = √(k1/m)) at large amplitude
    assert branch.damping_ratio.max() > 10 * C_ / (2 * M_ * w_stuck)
    assert np.all(np.diff(branch.frequency[~stuck]) < 1e-12)
    assert branch.frequency[-1] == pytest.approx(np.sqrt(K1 / M_) / (2 * np.pi), rel=0.03)
    # energy identity at every point, refined to round-off (the identity holds to the size of
    # the residual of the uncondensed harmonic-1 rows): ξ ∮q̇ᵀMq̇ = ∮q̇ᵀCq̇ + ∮ f u̇
    p = branch.solver
    col = p.n_x + p.amp_l
    for u in branch.states:
        u = _pinned(p, u, u[col] * p.colscale[col])
        rec = p.monitor(u)
        lhs = rec["xi"] * mass_work(p, u)
        assert abs(lhs - rec["viscous_dissipation"] - rec["friction_dissipation"]) <= 1e-10 * lhs


def _pinned(p, u, a1):
    """Newton on the EPMC equations with the amplitude DOF's cosine of harmonic 1 pinned."""
    col = p.n_x + p.amp_l
    for _ in range(40):
        R, J = p.evaluate(u)
        r = np.append(R, u[col] - a1 / p.colscale[col])
        if np.abs(r).max() < 1e-13:
            return u
        u = u - np.linalg.solve(np.vstack([J, np.eye(len(u))[col]]), r)
    raise AssertionError("no convergence")


@pytest.mark.parametrize("a1", [0.1, 0.8])
def test_damping_ratio_and_frequency_converge_in_H(a1):
    """At a fixed fundamental amplitude: measured |D_H/D_31 − 1| = 7e-5, 8e-6 (a1 = 0.1) and
    7e-5, 1e-5 (0.8) at H = 7, 15."""
    out = {}
    for H in (7, 15, 31):
        p = FrictionEPMCProblem(jenkins(), H)
        u = p.linear_point(0.04)
        for a in np.linspace(0.04, a1, 16):
            u = _pinned(p, u, a)
        rec = p.monitor(u)
        out[H] = (rec["damping_ratio"], rec["frequency"])
    d7, d15 = (abs(out[H][0] / out[31][0] - 1) for H in (7, 15))
    f7, f15 = (abs(out[H][1] / out[31][1] - 1) for H in (7, 15))
    assert d15 < d7 and d15 < 1e-4 and f15 < 1e-5, (d7, d15, f7, f15)


def test_jacobian_against_central_differences():
    p = FrictionEPMCProblem(jenkins(), 4)
    u = p.linear_point(0.04)
    for a in np.linspace(0.04, 0.2, 8):
        u = _pinned(p, u, a)
    u = u * (1 + 1e-3 * np.cos(np.arange(len(u))))
    R0, J = p.evaluate(u)

    def central(h):
        return np.array([(p.evaluate(u + h * e, False) - p.evaluate(u - h * e, False)) / (2 * h)
                         for e in np.eye(len(u))]).T

    h = 1e-6
    D1, D2 = central(h), central(2 * h)
    trunc = np.abs(D2 - D1).max() / 3
    roundoff = 64 * np.finfo(float).eps * (np.abs(R0).max() + np.abs(J).max() * np.abs(u).max()) / h
    assert np.abs(D1 - J).max() <= 2 * (trunc + roundoff)


def test_refusals_are_named():
    free = mmshbm.Model.from_matrices(np.diag([1.0, 0.0]), np.array([[3.0, -2], [-2, 2]]), [], [], [],
                                      amplitude_dof=0).with_friction(1, 0.5, normal_load=0.0)
    with pytest.raises(ValueError, match="slides freely"):
        FrictionEPMCProblem(free, 3)
    with pytest.raises(ValueError, match="must carry mass"):
        FrictionEPMCProblem(jenkins().with_amplitude_dof(1), 3)


@pytest.mark.parametrize("method", ["penalty", "shooting"])
def test_baselines_say_not_yet(method):
    with pytest.raises(NotImplementedError, match="not yet"):
        mmshbm.backbone(jenkins(), method=method, max_amplitude=1.0)


def test_the_default_start_is_stuck():
    """Without a gap the backbone starts at half the amplitude where the stuck mode slips
    (or 1 % of max_amplitude, whichever is smaller)."""
    with pytest.warns(mmshbm.BranchWarning, match="short of its bounds"):
        branch = mmshbm.backbone(jenkins(), harmonics=5, max_amplitude=10.0, max_steps=3)
    assert branch.amplitude[0] == pytest.approx(0.5 * S / K2, rel=1e-12)
    assert branch.damping_ratio[0] == pytest.approx(C_ / (2 * np.sqrt((K1 + K2) * M_)), rel=1e-10)
