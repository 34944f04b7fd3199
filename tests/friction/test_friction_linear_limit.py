"""Friction with zero normal load leaves the linear system:
the forced response of MMS-HBM must then equal the linear response solved per harmonic
directly, (K − (kΩ)² M + i kΩ C) Q̂_k = F̂ δ_k1, to the solve's round-off at every point
of the branch (the corrector stops at round-off, not at its acceptance tolerance).

The bound: the dynamic stiffness of these 2-DOF systems has a condition number below
~60 over the range (damping ratio 1.4 %: the resonance amplification ~35 times the
static stiffness' condition ~10), so a backward-stable solve lands within ~1e-13
relative; 1e-10 leaves room for the condensation and the scaling of the unknowns and
is still a thousand times below the error of the old stopping rule (1.5e-7)."""

import numpy as np
import pytest

import mmshbm
from mmshbm.methods.mms.friction_forced import FrictionForcedProblem

M_, K1, K2, C_, F_ = 1.0, 1.0, 2.0, 0.05, 0.1
H = 15


def _matrices():
    """Mass m on spring k1 to ground and spring k2 to a massless node (N/m, kg, N·s/m)."""
    M = np.diag([M_, 0.0])
    K = np.array([[K1 + K2, -K2], [-K2, K2]])
    C = np.diag([C_, 0.0])
    return M, K, C


def _linear(omega: float) -> np.ndarray:
    """NLvib-ordered coefficients (2, 2H+1) of the linear response to F̂ = [F, 0] cos Ωt:
    only harmonic 1 is excited; every other harmonic's equation is homogeneous and
    nonsingular, so its coefficients are 0."""
    M, K, C = _matrices()
    Q1 = np.linalg.solve(K - omega**2 * M + 1j * omega * C, np.array([F_, 0.0]))
    out = np.zeros((2, 2 * H + 1))
    out[:, 1], out[:, 2] = Q1.real, -Q1.imag
    return out


def _jenkins_without_load():
    M, K, C = _matrices()
    base = mmshbm.Model.from_matrices(M, K, [], [], [], damping=C, amplitude_dof=0)
    return base.with_friction(1, 0.5, normal_load=0.0)


def _worst_relative_error(fr) -> float:
    worst = 0.0
    for u in fr.states:
        Q = fr.solver.coefficients(u)
        ref = _linear(fr.solver.angular_frequency(u))
        worst = max(worst, float(np.abs(Q - ref).max() / np.abs(ref).max()))
    return worst


@pytest.mark.parametrize("law", ["play", "velocity"])
def test_zero_normal_load_is_the_linear_response_at_every_point(law):
    fr = mmshbm.frequency_response(_jenkins_without_load(), [F_, 0.0], (0.05, 0.4), harmonics=H, law=law)
    assert fr.status.startswith("bound")
    assert len(fr.states) > 50  # the resonance (0.159 Hz) is crossed
    assert _worst_relative_error(fr) <= 1e-10


@pytest.mark.parametrize("f", [0.1, 0.159, 0.3])
def test_zero_normal_load_solved_at_a_fixed_frequency_is_linear(f):
    p = FrictionForcedProblem(_jenkins_without_load(), [F_, 0.0], H)
    u, ok = p.solve_at(f, p.start_point(f))
    assert ok
    ref = _linear(2 * np.pi * f)
    assert np.abs(p.coefficients(u) - ref).max() <= 1e-10 * np.abs(ref).max()

