"""The pinned Newton (mmshbm.core.pinned.solve_at_amplitude) evaluates the Jacobian and
the amplitude's gradient at a full step's trial point and, where the step is taken, starts
the next iteration from them: one Jacobian per iteration and no other evaluation where
every full step is taken, against the analytic solution of a smooth problem. (The iterates
on nonsmooth problems, with halvings, are checked against a reference that evaluates every
trial in full in tests/family/test_pinned_backtracking.py.)"""

import math

import numpy as np
import pytest

from mmshbm.core.pinned import solve_at_amplitude
from mmshbm.core.problem import ContinuationProblemBase


class _Ellipse(ContinuationProblemBase):
    """One equation in two unknowns, (u0/a)² + (u1/b)² − 1 = 0, amplitude A(u) = u1: the
    point at amplitude A* is (a √(1 − (A*/b)²), A*). Counts its evaluations."""

    def __init__(self, a, b):
        self.a, self.b = a, b
        self.n_unknowns = 2
        self.counts = {"jacobian": 0, "residual": 0, "amplitude": 0, "gradient": 0}

    def _r(self, u):
        return np.array([(u[0] / self.a) ** 2 + (u[1] / self.b) ** 2 - 1.0])

    def residual(self, u):
        self.counts["residual"] += 1
        return self._r(u)

    def residual_and_jacobian(self, u):
        self.counts["jacobian"] += 1
        return self._r(u), np.array([[2 * u[0] / self.a**2, 2 * u[1] / self.b**2]])

    def monitor(self, u):
        return {"amplitude": float(u[1])}

    def amplitude_value(self, u):
        self.counts["amplitude"] += 1
        return float(u[1])

    def amplitude_and_gradient(self, u):
        self.counts["gradient"] += 1
        return float(u[1]), np.array([0.0, 1.0])


@pytest.mark.parametrize(("a", "b", "target", "start"), [(1.0, 1.0, 0.6, (0.9, 0.5)),
                                                         (2.0, 0.5, 0.3, (1.7, 0.25)),
                                                         (3.0, 2.0, 1.9, (1.0, 1.8))])
def test_a_taken_full_step_carries_its_jacobian(a, b, target, start):
    """Newton from near the solution takes every full step (quadratic convergence): one
    Jacobian and one gradient per iterate (the start and each step's trial), no separate
    residual or amplitude evaluation, and the point is the analytic one to the solve's
    tolerance (the residual row's error, 1e-12, moves u0 by at most 1e-12 · a² / (2 u0))."""
    p = _Ellipse(a, b)
    u, it, history, tangent = solve_at_amplitude(p, np.array(start), target, tol=1e-12)
    want = np.array([a * math.sqrt(1 - (target / b) ** 2), target])
    bound = 1e-12 * a**2 / (2 * want[0]) + 1e-15
    assert abs(u[0] - want[0]) <= bound and abs(u[1] / target - 1) <= 1e-12
    assert np.all(np.diff(history) < 0) and it >= 3  # every step lowered the residual: all taken
    assert p.counts == {"jacobian": it + 1, "gradient": it + 1, "residual": 0, "amplitude": 0}
    assert abs(np.linalg.norm(tangent) - 1) <= 1e-15
