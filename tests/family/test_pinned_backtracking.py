"""Newton with the amplitude pinned (core.pinned) against a plain reference that evaluates
every backtracking trial in full, on nonsmooth problems where the halving, the step taken
whatever its residual and the trust region all act; and the dense bordered solve above
the Numba kernel's size against scipy's LU."""

import math

import numpy as np
import pytest
import scipy.linalg as la

from mmshbm.core.bordered import _SMALL_DENSE, bordered_solve, bordered_solve_sign
from mmshbm.core.pinned import PinnedFailure, solve_at_amplitude
from mmshbm.core.problem import ContinuationProblemBase


class _Kinked(ContinuationProblemBase):
    """n−1 equations in n unknowns, linear plus a one-sided stop on every unknown
    (K·max(u − g, 0)) and a sine; the amplitude is the largest |u_i| (a kinked A(u), its
    gradient the signed unit vector of the largest entry). Counts its evaluations."""

    def __init__(self, n, seed):
        rng = np.random.default_rng(seed)
        self.n_unknowns = n
        self.L = rng.standard_normal((n - 1, n)) + 2.0 * np.eye(n - 1, n)
        self.K = 40.0 * rng.random(n - 1)
        self.g = 0.3 + rng.random(n - 1)
        self.b = rng.standard_normal(n - 1)
        self.counts = {"residual": 0, "amplitude": 0}

    def _r(self, u):
        x = u[:-1]
        return self.L @ u + self.K * np.maximum(x - self.g, 0.0) + 0.5 * np.sin(3.0 * x) - self.b

    def residual(self, u):
        self.counts["residual"] += 1
        return self._r(u)

    def residual_and_jacobian(self, u):
        x = u[:-1]
        J = self.L.copy()
        J[:, :-1] += np.diag(self.K * (x > self.g) + 1.5 * np.cos(3.0 * x))
        return self._r(u), J

    def monitor(self, u):
        return {"amplitude": self.amplitude_value(u)}

    def amplitude_value(self, u):
        self.counts["amplitude"] += 1
        return float(np.abs(u).max())

    def amplitude_and_gradient(self, u):
        i = int(np.argmax(np.abs(u)))
        grad = np.zeros(len(u))
        grad[i] = math.copysign(1.0, u[i])
        return float(abs(u[i])), grad


def _reference(problem, u0, amplitude, tol, max_iter, admissible):
    """The pinned Newton as its docstring states it, every trial evaluated in full:
    (u, iterations, history, amplitude evaluations) or the PinnedFailure's message."""
    u = np.array(u0, dtype=float)
    history, du_norm, evaluated = [], math.inf, 0
    for it in range(max_iter + 1):
        R, J = problem.residual_and_jacobian(u)
        A, g = problem.amplitude_and_gradient(u)
        c = A / amplitude - 1.0
        norm = max(float(np.abs(R).max()), abs(c))
        history.append(norm)
        if norm <= tol or (du_norm <= 1e-8 and norm <= math.sqrt(tol)):
            return u, it, history, evaluated
        if it == max_iter:
            break
        du = np.linalg.solve(np.vstack([J, g / amplitude]), np.r_[R, c])
        du_norm = float(np.abs(du).max())
        lam = 1.0
        for _ in range(7):
            trial = u - lam * du
            if admissible is not None and not admissible(trial):
                if lam < 0.05:
                    return f"Newton left the trust region (iteration {it + 1})"
                lam *= 0.5
                continue
            evaluated += 1
            A_t = float(np.abs(trial).max())
            n_t = max(float(np.abs(problem._r(trial)).max()), abs(A_t / amplitude - 1.0))
            if n_t < norm or lam < 0.05:
                break
            lam *= 0.5
        u = u - lam * du
    return f"no convergence in {max_iter} iterations (residual {history[-1]:.2e})"


def _dense(J, g, rhs):
    return np.linalg.solve(np.vstack([J, g]), rhs)


def _cases():
    for seed in range(40):
        rng = np.random.default_rng(100 + seed)
        n = 4 + seed % 3
        u0 = rng.standard_normal(n)
        amplitude = float(np.abs(u0).max()) * (0.5 + 1.5 * rng.random())
        window = 1.0 + 2.0 * rng.random() if seed % 4 == 0 else None  # the trust region on u[-1]
        yield seed, n, u0, amplitude, window


def test_same_iterates_as_full_backtracking():
    """Every outcome (point, iterations, residual history or failure message) equals the
    reference's exactly, with fewer amplitude evaluations; the cases include solves that
    converge, that run out of iterations, that leave the trust region, and steps taken at
    λ = 1/32, so neither shortcut can go untested."""
    seen = set()
    saved = 0
    for seed, n, u0, amplitude, window in _cases():
        admissible = None if window is None else (lambda u, w=window: abs(u[-1]) <= w)
        if admissible is not None and not admissible(u0):
            continue
        ref = _reference(_Kinked(n, seed), u0, amplitude, 1e-10, 30, admissible)
        problem = _Kinked(n, seed)
        try:
            u, it, hist, _ = solve_at_amplitude(problem, u0, amplitude, tol=1e-10, max_iter=30,
                                                solve=_dense, admissible=admissible)
        except PinnedFailure as err:
            assert str(err) == ref, seed
            seen.add(str(err).split(" ")[0])
            continue
        u_ref, it_ref, hist_ref, evaluated = ref
        # the reference performs the same NumPy operations on the same numbers (solve=_dense)
        assert it == it_ref and np.array_equal(u, u_ref) and np.array_equal(hist, hist_ref), seed
        assert problem.counts["amplitude"] <= evaluated
        saved += evaluated - problem.counts["amplitude"]
        seen.add("converged")
    assert seen == {"converged", "no", "Newton"}, seen
    assert saved > 0


def _halvings_taken():
    """Steps taken at λ = 1/32 over the cases (from the reference's trials)."""
    count = 0
    for seed, n, u0, amplitude, _ in _cases():
        p = _Kinked(n, seed)
        u = np.array(u0)
        for _ in range(30):
            R, J = p.residual_and_jacobian(u)
            A, g = p.amplitude_and_gradient(u)
            norm = max(np.abs(R).max(), abs(A / amplitude - 1))
            if norm <= 1e-10:
                break
            du = np.linalg.solve(np.vstack([J, g / amplitude]), np.r_[R, A / amplitude - 1])
            lam = 1.0
            while lam >= 0.05 and not max(np.abs(p._r(u - lam * du)).max(),
                                          abs(np.abs(u - lam * du).max() / amplitude - 1)) < norm:
                lam *= 0.5
            count += lam < 0.05
            u = u - lam * du
    return count


def test_cases_take_the_last_halving():
    assert _halvings_taken() > 0


@pytest.mark.parametrize("n", [_SMALL_DENSE + 1, 64])
def test_dense_bordered_equals_scipy_lu(n):
    """Above the Numba kernel's size: the bits of scipy.linalg.lu_factor/lu_solve, and the
    sign of the determinant."""
    rng = np.random.default_rng(n)
    J, t, rhs = rng.standard_normal((n - 1, n)), rng.standard_normal(n), rng.standard_normal(n)
    x, sign = bordered_solve_sign(J, t, rhs)
    M = np.vstack([J, t])
    assert np.array_equal(x, la.lu_solve(la.lu_factor(M), rhs))  # the same LAPACK getrf/getrs calls
    assert sign == np.sign(np.linalg.det(M))
    R = np.column_stack([rhs, 2.0 * rhs])
    np.testing.assert_allclose(bordered_solve(J, t, R), np.linalg.solve(M, R), rtol=1e-9, atol=1e-12)


def test_dense_bordered_singular_gives_nan():
    n = _SMALL_DENSE + 5
    J = np.random.default_rng(0).standard_normal((n - 1, n))
    J[3] = 0.0
    x, sign = bordered_solve_sign(J, np.ones(n), np.ones(n))
    assert np.all(np.isnan(x)) and sign == 0.0
