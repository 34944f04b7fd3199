"""The frequency of a linear mode with DOFs held fixed: the upper end of a backbone's
frequency range (every contact closed at once), kept per model."""

from __future__ import annotations

import weakref

import numpy as np

from ...model.model import Model

__all__ = ["_held_frequency", "_held_frequency_solve"]

#: model -> {(held DOFs, mode): frequency (Hz)} of :func:`_held_frequency`
_HELD: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _held_frequency(model: Model, dofs, mode: int) -> float:
    """Frequency (Hz) of linear mode ``mode`` with the DOFs ``dofs`` held fixed (all
    contacts closed at once: the upper end of a backbone's frequency range); kept per
    model (immutable) and (dofs, mode).

    Up to ``_DENSE_EIG_LIMIT`` DOFs with mass a dense eigen-solve; above, the sparse path
    of :meth:`Model.linear_modes` (static condensation of the other massless DOFs,
    shift-invert ARPACK at 0 with a minimum-degree LU): nothing of size n_dof² is formed.
    """
    memo = _HELD.setdefault(model, {})
    key = (tuple(int(d) for d in np.atleast_1d(dofs)), int(mode))
    if key not in memo:
        memo[key] = _held_frequency_solve(model, dofs, mode)
    return memo[key]


def _held_frequency_solve(model: Model, dofs, mode: int) -> float:
    import scipy.linalg as la
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    from ...model.linear_modes import _DENSE_EIG_LIMIT

    keep = np.setdiff1d(np.arange(model.n_dof), np.asarray(dofs))
    M = sp.csr_matrix(model.M)[keep][:, keep]
    K = sp.csr_matrix(model.K)[keep][:, keep]
    massless = np.asarray(abs(M).sum(axis=1)).ravel() == 0
    l, c = np.flatnonzero(~massless), np.flatnonzero(massless)
    if len(l) <= _DENSE_EIG_LIMIT:
        Kd = K.toarray()
        K_red = Kd[np.ix_(l, l)]
        if len(c):
            K_red = K_red - Kd[np.ix_(l, c)] @ np.linalg.solve(Kd[np.ix_(c, c)], Kd[np.ix_(c, l)])
        w2 = la.eigh(K_red, M.toarray()[np.ix_(l, l)], eigvals_only=True,
                     subset_by_index=(mode - 1, mode - 1))
        return float(np.sqrt(max(w2[0], 0.0)) / (2 * np.pi))
    K_red = K[l][:, l].tocsc()
    if len(c):
        K_lc = K[l][:, c].tocsc()
        X = spla.splu(K[c][:, c].tocsc()).solve(K_lc.T.toarray())  # (n_c', n_l): massless DOFs only
        K_red = (K_red - K_lc @ sp.csr_matrix(X)).tocsc()
    lu = spla.splu(K_red, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    op = spla.LinearOperator(K_red.shape, matvec=lu.solve, dtype=float)
    w2 = spla.eigsh(K_red, k=mode, M=M[l][:, l].tocsc(), sigma=0.0, which="LM", v0=np.ones(len(l)), OPinv=op,
                    return_eigenvectors=False)
    return float(np.sqrt(max(np.sort(w2)[mode - 1], 0.0)) / (2 * np.pi))
