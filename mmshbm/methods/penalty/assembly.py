"""The fixed CSR pattern of the penalty-HBM Jacobian (:mod:`mmshbm.methods.penalty.hbm`):
built once per problem, it records where each kind of entry sits, so that each evaluation
only fills the data vector (:func:`~mmshbm.methods.penalty._kernels._penalty_hbm_jacobian`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

__all__ = ["_Pattern", "_jacobian_pattern"]


@dataclass(frozen=True)
class _Pattern:
    """Fixed CSR pattern of the Jacobian and where each kind of entry sits in it.

    Attributes
    ----------
    indices, indptr : ndarray of int32
        CSR column indices (nnz,) and row pointers (n_rows + 1,).
    shape : tuple of int
        (n(H+1), n(H+1) + 1).
    K_data, M_data : ndarray, shape (nnz_A,)
        K and M on the union pattern A of one harmonic block.
    block_pos : ndarray of int64, shape (H+1, nnz_A)
        CSR position of entry e of block k.
    coupling_pos : ndarray of int64, shape (n_d, H+1, H+1)
        CSR position of (row m·n + d, column k·n + d) for each distinct contact DOF d.
    omega_rows : ndarray of int64, shape (n_l,)
        DOFs with mass: the rows of the Ω column in each harmonic k >= 1.
    omega_pos : ndarray of int64, shape (H, n_l)
        CSR position of (row k·n + omega_rows[r], Ω column), k = 1..H.
    """

    indices: np.ndarray
    indptr: np.ndarray
    shape: tuple
    K_data: np.ndarray
    M_data: np.ndarray
    block_pos: np.ndarray
    coupling_pos: np.ndarray
    omega_rows: np.ndarray
    omega_pos: np.ndarray

    @property
    def rows(self) -> np.ndarray:
        """Row index of every stored entry, shape (nnz,)."""
        return np.repeat(np.arange(self.shape[0]), np.diff(self.indptr))


def _jacobian_pattern(K: sp.csr_matrix, M: sp.csr_matrix, harmonics: int, contact_dofs,
                      mass_dofs: np.ndarray) -> _Pattern:
    """Build the CSR pattern of the penalty-HBM Jacobian once.

    Rows and columns are numbered k·n + i (harmonic k, DOF i); the last column is Ω.
    ``contact_dofs`` (n_d,) are the distinct DOFs with a penalty spring: each couples its
    harmonics in its own row and column.
    """
    n, H1 = K.shape[0], harmonics + 1
    contact_dofs = np.atleast_1d(np.asarray(contact_dofs, dtype=np.int64))
    n_d = len(contact_dofs)
    A = (abs(K) + abs(M)).tocsr()
    A.sum_duplicates()
    A.sort_indices()
    a_rows = np.repeat(np.arange(n), np.diff(A.indptr))
    a_cols = A.indices.astype(np.int64)
    K_data = np.asarray(K[a_rows, a_cols]).ravel()
    M_data = np.asarray(M[a_rows, a_cols]).ravel()
    diag = np.empty(n_d, dtype=np.int64)
    for j, d in enumerate(contact_dofs):
        where = np.flatnonzero((a_rows == d) & (a_cols == d))
        if len(where) != 1:  # pragma: no cover - K is positive definite, its diagonal is stored
            raise ValueError(f"K has no stored diagonal entry at the contact DOF {d}")
        diag[j] = where[0]

    k = np.arange(H1)
    blk_r = (k[:, None] * n + a_rows[None, :]).ravel()
    blk_c = (k[:, None] * n + a_cols[None, :]).ravel()
    m_, k_ = np.nonzero(~np.eye(H1, dtype=bool))
    cpl_r = (m_[None, :] * n + contact_dofs[:, None]).ravel()
    cpl_c = (k_[None, :] * n + contact_dofs[:, None]).ravel()
    mass_dofs = np.asarray(mass_dofs, dtype=np.int64)
    om_r = ((k[1:, None]) * n + mass_dofs[None, :]).ravel()
    om_c = np.full(om_r.shape, H1 * n)

    rows = np.concatenate([blk_r, cpl_r, om_r])
    cols = np.concatenate([blk_c, cpl_c, om_c])
    order = np.lexsort((cols, rows))  # CSR order
    position = np.empty_like(order)
    position[order] = np.arange(len(order))
    n_blk, n_cpl = len(blk_r), len(cpl_r)
    block_pos = position[:n_blk].reshape(H1, len(a_rows))
    coupling_pos = np.empty((n_d, H1, H1), dtype=np.int64)
    off = position[n_blk : n_blk + n_cpl].reshape(n_d, len(m_))
    for j in range(n_d):
        coupling_pos[j, m_, k_] = off[j]
        coupling_pos[j, k, k] = block_pos[k, diag[j]]
    omega_pos = position[n_blk + n_cpl :].reshape(harmonics, len(mass_dofs))
    n_rows = H1 * n
    indptr = np.zeros(n_rows + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows, minlength=n_rows), out=indptr[1:])
    itype = np.int32 if max(len(rows), n_rows + 1) < np.iinfo(np.int32).max else np.int64
    return _Pattern(indices=cols[order].astype(itype), indptr=indptr.astype(itype),
                    shape=(n_rows, n_rows + 1), K_data=K_data, M_data=M_data,
                    block_pos=np.ascontiguousarray(block_pos), coupling_pos=coupling_pos,
                    omega_rows=mass_dofs, omega_pos=np.ascontiguousarray(omega_pos))
