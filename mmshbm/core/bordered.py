"""Sparse bordered solves of the path follower: block elimination on the square part.

The corrector and the tangent solve ``[J; tᵀ] x = rhs`` with J of shape (n−1, n). For a
sparse J (penalty-HBM on every DOF) a sparse LU of the bordered matrix itself fills in
badly: the arclength row tᵀ and the parameter column (∂R/∂Ω, non-zero on every DOF with
mass) are dense, and SuperLU's fill for the 1000-element beam at H = 5 (12 001 unknowns)
is ~2·10⁶ entries, ~80 ms per solve. Splitting off the last unknown (the continuation
parameter, Ω in every mmshbm problem),

    [A  b] [y]   [r]        A = J[:, :-1] (sparse, square),  b = J[:, -1],
    [cᵀ d] [η] = [s],       c = t[:-1], d = t[-1],

only A is factorised (for harmonic balance on an FE model: block-diagonal over the
harmonics plus the contact coupling, fill ~8·10⁴, ~6 ms) and

    A z = b,  A w = r,  η = (s − cᵀw) / (d − cᵀz),  y = w − z η.

A is singular exactly at a fold of the branch in the parameter, where the block
elimination loses accuracy (Govaerts, *Numerical Methods for Bifurcations of Dynamical
Equilibria*, 2000, ch. 3): one step of iterative refinement with the same factors
restores it, and if the residual of the bordered system is still not small the solve
falls back to the LU of the whole bordered matrix. So the result is always that of a
backward-stable solve; the block path is only the fast one.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["bordered_solve", "bordered_solve_sign", "solve_bordered_sparse"]

#: accept the block-elimination result when ‖[J; tᵀ]x − rhs‖∞ is below this times
#: ‖[J; tᵀ]‖∞‖x‖∞ + ‖rhs‖∞ (a backward error near round-off)
_BACKWARD_TOL = 1e-11


def _bordered_matrix(J: sp.spmatrix, t: np.ndarray) -> sp.csc_matrix:
    return sp.vstack([J, sp.csr_matrix(t[None, :])], format="csc")


def _full_solve(J: sp.spmatrix, t: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    try:
        return spla.splu(_bordered_matrix(J, t)).solve(rhs)
    except RuntimeError:  # exactly singular
        return np.full_like(rhs, np.nan)


def solve_bordered_sparse(J: sp.spmatrix, t: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve ``[J; tᵀ] x = rhs`` for a sparse J of shape (n−1, n).

    Parameters
    ----------
    J : scipy.sparse matrix, shape (n−1, n)
        Jacobian of the residual; its last column belongs to the continuation parameter.
    t : ndarray, shape (n,)
        Bordering row (the tangent).
    rhs : ndarray, shape (n,) or (n, k)

    Returns
    -------
    ndarray, shape of ``rhs``
        The solution; all NaN if the bordered matrix is singular.
    """
    J = J.tocsr() if not sp.isspmatrix_csr(J) else J
    m, n = J.shape
    data, indices, indptr = J.data, J.indices, J.indptr
    # split off the last column with raw index arithmetic (scipy slicing is slow at this size)
    border = indices == n - 1
    rows = np.repeat(np.arange(m), np.diff(indptr))
    b = np.zeros(m)
    np.add.at(b, rows[border], data[border])
    keep = ~border
    counts = np.bincount(rows[keep], minlength=m)
    # the CSR arrays of A are the CSC arrays of Aᵀ: factorise Aᵀ, solve with trans="T"
    At = sp.csc_matrix((data[keep], indices[keep], np.concatenate(([0], np.cumsum(counts)))), shape=(m, m))
    c, d = t[:-1], t[-1]
    try:
        lu = spla.splu(At, permc_spec="MMD_AT_PLUS_A")
    except RuntimeError:  # A exactly singular: a fold in the parameter
        return _full_solve(J, t, rhs)

    z = lu.solve(b, trans="T")
    denom = d - c @ z

    def block_solve(r):
        r2 = r.reshape(n, -1)
        w = lu.solve(np.ascontiguousarray(r2[:-1]), trans="T")
        eta = (r2[-1] - c @ w) / denom
        return np.vstack([w - np.outer(z, eta), eta[None, :]]).reshape(r.shape)

    def bordered_product(x):
        x2 = x.reshape(n, -1)
        return np.vstack([J @ x2, t @ x2]).reshape(x.shape)

    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        x = block_solve(rhs)
        x = x + block_solve(rhs - bordered_product(x))  # one step of iterative refinement
        resid = np.abs(rhs - bordered_product(x)).max() if np.all(np.isfinite(x)) else np.inf
        row_norm = np.bincount(rows, np.abs(data), minlength=m).max()
        scale = (row_norm + np.abs(t).sum()) * np.abs(x).max() + np.abs(rhs).max()
    if np.isfinite(resid) and resid <= _BACKWARD_TOL * scale:
        return x
    return _full_solve(J, t, rhs)


def bordered_solve(J, t: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve [J; tᵀ] x = rhs for dense or sparse J, or an operator J with its own
    ``bordered_solve(t, rhs)`` (all NaN when singular)."""
    return _solve(J, t, rhs, False)[0]


def bordered_solve_sign(J, t: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, float]:
    """:func:`bordered_solve`, and the sign of det [J; tᵀ] (+1/−1; 0 when singular or for a
    sparse J, whose determinant is not tracked)."""
    return _solve(J, t, rhs, True)


def _solve(J, t: np.ndarray, rhs: np.ndarray, with_sign: bool) -> tuple[np.ndarray, float]:
    """(x, sign) of :func:`bordered_solve_sign`; the LAPACK path leaves the sign (0)
    uncomputed unless ``with_sign``."""
    if hasattr(J, "bordered_solve"):  # an operator that solves its own bordered systems
        return J.bordered_solve(t, rhs), 0.0
    if not isinstance(J, np.ndarray) and sp.issparse(J):
        return solve_bordered_sparse(J, t, rhs), 0.0  # block elimination, full LU fallback
    n = len(rhs)
    A = np.empty((n, n))
    A[:-1] = J
    A[-1] = t
    if n <= _SMALL_DENSE:
        x = np.empty(n)
        sign = np.zeros(1)
        if _small_dense_solver()(A, np.ascontiguousarray(rhs, dtype=float), np.empty((n, n)), x, sign):
            return np.full_like(rhs, np.nan), 0.0
        return x, float(sign[0])
    # LAPACK's getrf/getrs called directly: what scipy.linalg.lu_factor/lu_solve call,
    # without their ~15 µs of argument handling per call
    getrf, getrs = _lapack_lu()
    lu, piv, info = getrf(A, overwrite_a=True)
    if info < 0:
        return np.full_like(rhs, np.nan), 0.0
    d = lu.diagonal()
    if (d == 0).any() or not np.isfinite(d).all():
        return np.full_like(rhs, np.nan), 0.0
    sign = 0.0
    if with_sign:
        swaps = np.count_nonzero(piv != np.arange(n))
        sign = float(np.prod(np.sign(d))) * (-1.0 if swaps % 2 else 1.0)
    x, info = getrs(lu, piv, np.asarray(rhs, dtype=float))
    if info < 0:
        return np.full_like(rhs, np.nan), 0.0
    return x, sign


def _lapack_lu():
    """(dgetrf, dgetrs) of scipy's LAPACK (looked up on first use)."""
    global _getrf_getrs
    if _getrf_getrs is None:
        from scipy.linalg import lapack

        _getrf_getrs = lapack.get_lapack_funcs(("getrf", "getrs"), (np.empty((1, 1)),))
    return _getrf_getrs


_getrf_getrs = None


#: bordered systems up to this size are solved by a Numba LU (LAPACK's call overhead
#: dominates below it; measured 2.1 against 7.6 µs at n = 13, 10 against 16 µs at n = 33,
#: 53 against 37 µs at n = 64)
_SMALL_DENSE = 40


def _small_dense_solver():
    """The Numba LU kernel (imported on first use: importing numba is not cheap)."""
    global _dense_solve
    if _dense_solve is None:
        from ..harmonic.kernels import _dense_solve
    return _dense_solve


_dense_solve = None
