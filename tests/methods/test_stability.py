"""Floquet multipliers of harmonic-balance orbits along the exact piecewise-linear flow:
transitions, conservative structure, agreement with shooting, classification."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as la
from test_exact import chain

import mmshbm
from mmshbm.methods.mms.stability import FloquetSolver, classify, conservative_multipliers


def test_phase_transitions_are_matrix_exponentials():
    model = mmshbm.default_beam().model(4).with_damping(modal_ratio=0.02)
    fs = FloquetSolver(model)
    n = fs.n_l
    for closed in (frozenset(), frozenset({(0, 1)})):
        K = fs.stiffness(closed)
        for damping in (True, False):
            A = np.block([[np.zeros((n, n)), np.eye(n)],
                          [-fs.Minv @ K, -fs.Minv @ (fs.C if damping else 0 * fs.C)]])
            for t in (1e-4, 4e-3):
                ref = la.expm(A * t)
                err = np.abs(fs.transition(closed, t, damping=damping) - ref).max()
                assert err < 1e-9 * np.abs(ref).max()


@pytest.fixture(scope="module")
def chain_orbits():
    model = chain()
    out = {}
    for H in (5, 10, 20):
        b = mmshbm.backbone(model, harmonics=H, max_amplitude=0.6)
        out[H] = conservative_multipliers(b.solver, b.states[-1])
    s = mmshbm.backbone(model, method="shooting", steps_per_period=1024, max_amplitude=0.6)
    out["shooting"] = s.solver.floquet_multipliers(s.states[-1])
    return out


def test_conservative_multipliers_come_in_reciprocal_pairs_with_two_at_one(chain_orbits):
    trivial = []
    for H in (5, 10, 20):
        mu = chain_orbits[H]
        mod = np.sort(np.abs(mu))
        assert np.abs(mod * mod[::-1] - 1).max() < 1e-10  # symplectic monodromy: μ and 1/μ
        assert np.prod(mu).real == pytest.approx(1.0, abs=1e-10)
        trivial.append(np.sort(np.abs(mu - 1))[1])  # the second closest to +1
    # the phase and energy multipliers approach +1 as the orbit converges in H (0.53, 0.17, 0.037)
    assert trivial[0] > trivial[1] > trivial[2] and trivial[2] < 0.05


def test_shooting_and_mmshbm_multipliers_agree(chain_orbits):
    mu_s, mu_h = chain_orbits["shooting"], chain_orbits[20]
    assert np.sort(np.abs(mu_s - 1))[1] < 1e-5  # the discrete reversible map keeps both near +1
    dist = max(np.min(np.abs(mu_h - m)) for m in mu_s)
    assert dist < 0.05  # the HBM orbit's own error at H = 20 (trivial pair 0.037 off)


def test_classify_names_the_crossings():
    inside = [0.5, -0.3, 0.2 + 0.3j, 0.2 - 0.3j]

    def pts(*extra):
        return np.array(inside[: 4 - len(extra)] + list(extra), dtype=complex)

    mu = np.array([pts(), pts(1.2), pts(1.3), pts(), pts(-1.4), pts(), pts(0.9 + 0.8j, 0.9 - 0.8j)])
    stable, special = classify(mu, folds=[1])
    assert stable.tolist() == [True, False, False, True, False, True, False]
    kinds = [(p.kind, p.index) for p in special]
    assert kinds == [("branch_point", 3), ("period_doubling", 4), ("period_doubling", 5),
                     ("neimark_sacker", 6)]  # the +1 crossing at index 1 is the fold itself
    # trivial multipliers are left out
    stable, _ = classify(np.array([[1.0 + 1e-3, 1.0 - 1e-3, 0.3]]), trivial=2)
    assert stable.tolist() == [True]


def test_branch_stability_of_a_damped_mode():
    """Below the gap the EPMC cancels mode 1's damping (its pair sits at +1: one trivial, one
    neutral) and every other mode decays; the conservative backbone's two trivial multipliers
    are left out."""
    from mmshbm.methods.mms.stability import branch_stability

    beam = mmshbm.default_beam().model(4)
    b = mmshbm.backbone(beam.with_damping(modal_ratio=0.02), harmonics=3, max_amplitude=2e-3)
    mu, stable, _ = branch_stability(b)
    below = b.amplitude < 0.99 * beam.gap
    w = 2 * np.pi * beam.linear_frequencies(2)
    T = 1 / b.frequency[0]
    mod = np.sort(np.abs(mu[0]))[::-1]
    assert mod[0] == pytest.approx(1.0, abs=1e-9) and mod[1] == pytest.approx(1.0, abs=1e-9)
    # mode 2 decays with its damping less the EPMC's ξ = 2 ζ ω_1
    assert mod[2] == pytest.approx(np.exp(-(0.02 * w[1] - 0.02 * w[0]) * T), rel=1e-6)
    assert stable[below].all()
    cons = mmshbm.backbone(beam, harmonics=3, max_amplitude=2e-3)
    mu_c, stable_c, _ = branch_stability(cons)
    assert np.abs(np.abs(mu_c[0]) - 1).max() < 1e-9 and stable_c[0]
