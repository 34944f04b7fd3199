"""The sparse bordered solve (block elimination with refinement, full-LU fallback)
against dense NumPy solves, including a fold where the square block is singular."""

import numpy as np
import pytest
import scipy.sparse as sp

from mmshbm.core.bordered import solve_bordered_sparse


def _random_system(n, seed):
    rng = np.random.default_rng(seed)
    A = sp.random(n - 1, n - 1, density=0.05, random_state=seed, format="csr") + sp.eye(n - 1) * 3.0
    b = rng.standard_normal(n - 1)
    J = sp.hstack([A, sp.csr_matrix(b[:, None])], format="csr")
    t = rng.standard_normal(n)
    return J, t / np.linalg.norm(t), rng.standard_normal(n)


@pytest.mark.parametrize("seed", range(5))
def test_equals_dense_solve(seed):
    J, t, rhs = _random_system(60, seed)
    x = solve_bordered_sparse(J, t, rhs)
    ref = np.linalg.solve(np.vstack([J.toarray(), t]), rhs)
    np.testing.assert_allclose(x, ref, rtol=1e-10, atol=1e-12 * np.abs(ref).max())


def test_several_right_hand_sides():
    J, t, rhs = _random_system(40, 7)
    R = np.column_stack([rhs, 2 * rhs + 1])
    ref = np.linalg.solve(np.vstack([J.toarray(), t]), R)
    np.testing.assert_allclose(solve_bordered_sparse(J, t, R), ref, rtol=1e-10, atol=1e-12)


def test_fold_singular_square_block():
    """At a fold in the parameter A = J[:, :-1] is singular but the bordered matrix is not."""
    n = 5
    A = sp.diags([1.0, 2.0, 0.0, 4.0]).tocsr()      # singular: zero pivot in row 2
    b = np.array([0.0, 0.0, 1.0, 0.0])              # the parameter column fills that row
    J = sp.hstack([A, sp.csr_matrix(b[:, None])], format="csr")
    t = np.array([0.0, 0.0, 1.0, 0.0, 0.0])         # the tangent points along the null vector
    rhs = np.arange(1.0, n + 1)
    ref = np.linalg.solve(np.vstack([J.toarray(), t]), rhs)
    np.testing.assert_allclose(solve_bordered_sparse(J, t, rhs), ref, rtol=1e-12)


def test_singular_bordered_matrix_gives_nan():
    J = sp.csr_matrix(np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]]))
    x = solve_bordered_sparse(J, np.array([0.0, 1.0, 0.0]), np.ones(3))
    assert np.all(np.isnan(x))
