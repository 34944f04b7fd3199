"""Vectorised assembly of element matrices into sparse global matrices, and DOF removal.

Global DOFs are numbered node-wise, ``[w0, θ0, w1, θ1, ..., wn, θn]`` for a chain of
``n`` two-node elements (node 0 at the root). Assembly follows scikit-fem: a loop over the
16 local DOF pairs, each pass handling all elements at once, into COO triplets converted
to CSR once (duplicates are summed).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .. import _validate as check

__all__ = ["chain_dofs", "assemble", "remove_dofs", "clamped_root_dofs"]

DOFS_PER_NODE = 2


def chain_dofs(n_elements: int) -> np.ndarray:
    """Element-to-global DOF map of a chain of 2-node beam elements.

    Returns
    -------
    ndarray of int, shape (n_elements, 4)
        Row ``e`` holds the global indices of ``[w_e, θ_e, w_{e+1}, θ_{e+1}]``.
    """
    n_elements = check.integer("n_elements", n_elements, minimum=1)
    first = DOFS_PER_NODE * np.arange(n_elements)
    return first[:, None] + np.arange(2 * DOFS_PER_NODE)[None, :]


def assemble(element_matrices: np.ndarray, dofs: np.ndarray, n_dof: int | None = None) -> sp.csr_matrix:
    """Sum element matrices into a global sparse matrix.

    Parameters
    ----------
    element_matrices : ndarray, shape (n_e, n_loc, n_loc)
        One matrix per element, local DOF order as in ``dofs``.
    dofs : ndarray of int, shape (n_e, n_loc)
        Global index of each local DOF of each element.
    n_dof : int, optional
        Size of the global matrix; default ``dofs.max() + 1``.

    Returns
    -------
    scipy.sparse.csr_matrix, shape (n_dof, n_dof)
    """
    Ae = np.asarray(element_matrices, dtype=float)
    dofs = np.asarray(dofs)
    if dofs.ndim != 2 or dofs.dtype.kind not in "iu":
        raise ValueError(f"dofs must be a 2-D integer array (n_e, n_loc), got {dofs.dtype} array of shape "
                         f"{dofs.shape}")
    n_e, n_loc = dofs.shape
    if Ae.shape != (n_e, n_loc, n_loc):
        raise ValueError(f"element_matrices must have shape {(n_e, n_loc, n_loc)}, got {Ae.shape}")
    if n_dof is None:
        n_dof = int(dofs.max()) + 1
    n_dof = check.integer("n_dof", n_dof, minimum=1)
    outside = (dofs < 0) | (dofs >= n_dof)
    if outside.any():
        e, i = np.argwhere(outside)[0]
        raise ValueError(f"dofs[{e}, {i}] = {dofs[e, i]} is outside [0, {n_dof - 1}]")
    rows = np.empty((n_loc, n_loc, n_e), dtype=np.int64)
    cols = np.empty_like(rows)
    data = np.empty((n_loc, n_loc, n_e))
    for i in range(n_loc):
        for j in range(n_loc):
            rows[i, j] = dofs[:, i]
            cols[i, j] = dofs[:, j]
            data[i, j] = Ae[:, i, j]
    A = sp.coo_matrix((data.ravel(), (rows.ravel(), cols.ravel())), shape=(n_dof, n_dof)).tocsr()
    A.sum_duplicates()
    return A


def remove_dofs(A: sp.spmatrix, removed) -> sp.csr_matrix:
    """Delete rows and columns ``removed`` (fixed DOFs) from a square sparse matrix.

    The remaining DOFs keep their relative order. Returns CSR, shape (n − len(removed),)*2.
    """
    A = sp.csr_matrix(A)
    removed = np.atleast_1d(np.asarray(removed))
    if removed.size and (removed.dtype.kind not in "iu" or removed.min() < 0 or removed.max() >= A.shape[0]):
        raise ValueError(f"removed DOFs must be integers in [0, {A.shape[0] - 1}], got {removed.tolist()}")
    keep = np.setdiff1d(np.arange(A.shape[0]), removed)
    return A[keep][:, keep].tocsr()


def clamped_root_dofs() -> np.ndarray:
    """The DOFs a clamped root removes: ``[w0, θ0]`` = ``[0, 1]``.

    After removing them the order is ``[w1, θ1, ..., wn, θn]``: the tip deflection of an
    ``n``-element chain is DOF ``2n − 2`` and the tip rotation ``2n − 1``.
    """
    return np.arange(DOFS_PER_NODE)
