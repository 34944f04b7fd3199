"""The DOF partition of a :class:`~mmshbm.model.Model`: the massless DOFs ``c`` and the DOFs
with mass ``l``, the partitioned matrices, the static condensation of ``c``, and the checks
that the partition is one the methods can use (a mixin of the model)."""

from __future__ import annotations

from functools import cached_property

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp

from .linear_modes import _require_positive_definite

__all__ = ["PartitionMixin"]


class PartitionMixin:
    """The partition ``c`` / ``l`` of a model's DOFs and what follows from it (needs the
    attributes of :class:`~mmshbm.model.Model`: ``M``, ``K``, ``damping``, ``contacts``)."""

    # ------------------------------------------------------------------ partition
    @property
    def n_dof(self) -> int:
        """Number of DOFs of the whole model."""
        return self.M.shape[0]

    @cached_property
    def c(self) -> np.ndarray:
        """Indices of the massless DOFs, sorted; shape (n_c,)."""
        row_mass = np.asarray(abs(self.M).sum(axis=1)).ravel()
        return np.flatnonzero(row_mass == 0.0)

    @cached_property
    def l(self) -> np.ndarray:  # noqa: E743 - the DOF set's name in the literature
        """Indices of the DOFs carrying mass (the linear subsystem); shape (n_l,)."""
        return np.setdiff1d(np.arange(self.n_dof), self.c)

    @property
    def contact_index(self) -> int:
        """Position of ``contact_dof`` inside ``c`` (single massless contact)."""
        dof = self.contact_dof
        i = int(np.searchsorted(self.c, dof))
        if i >= len(self.c) or self.c[i] != dof:
            raise ValueError(f"contact_dof {dof} carries mass: it is not among the massless DOFs")
        return i

    @cached_property
    def w_c(self) -> np.ndarray:
        """Contact direction restricted to ``c``: g_N = gap + w_c · q_c; shape (n_c,)
        (single massless contact)."""
        w = np.zeros(len(self.c))
        w[self.contact_index] = -self.stop_side
        return w

    @cached_property
    def blocks(self) -> dict:
        """The partitioned matrices: ``M_ll``, ``K_ll`` (CSC), ``K_lc`` (dense (n_l, n_c)),
        ``K_cc`` (dense (n_c, n_c)), and ``C_ll`` (CSC, or None without damping)."""
        l, c = self.l, self.c
        K = self.K.tocsr()
        return {
            "M_ll": self.M[l][:, l].tocsc(),
            "K_ll": K[l][:, l].tocsc(),
            "K_lc": K[l][:, c].toarray(),
            "K_cc": K[c][:, c].toarray(),
            "C_ll": None if self.damping is None else self.damping.tocsr()[l][:, l].tocsc(),
        }

    def _check_partition(self) -> None:
        c, l = self.c, self.l
        if len(l) == 0:
            raise ValueError("the model has no DOF with mass")
        M_lc = self.M[l][:, c]
        if M_lc.nnz and abs(M_lc).max() > 0:
            raise ValueError("massless DOFs must have zero mass rows and columns (M_lc != 0)")
        if self.damping is not None and len(c):
            C = self.damping.tocsr()
            rows = np.asarray(abs(C[c]).sum(axis=1)).ravel()
            cols = np.asarray(abs(C[:, c]).sum(axis=0)).ravel()
            coupled = (rows > 0) | (cols > 0)
            if np.any(coupled):
                raise ValueError(f"damping acts on the massless DOFs {c[coupled].tolist()}: massless DOFs "
                                 "are static, so their rows and columns of C must be zero")
        b = self.blocks
        _require_positive_definite(b["K_cc"], "K restricted to the massless DOFs")
        _require_positive_definite(b["M_ll"], "M restricted to the DOFs with mass")
        _require_positive_definite(self.reduced_stiffness, "K statically condensed on the DOFs with mass")

    # ------------------------------------------------------------------ condensation
    @cached_property
    def reduced_stiffness(self) -> sp.csc_matrix:
        """Exact static condensation of the massless DOFs:
        K_ll - K_lc K_cc⁻¹ K_cl, sparse (n_l, n_l)."""
        b = self.blocks
        if not len(self.c):
            return b["K_ll"]
        K_lc = sp.csr_matrix(b["K_lc"])
        correction = K_lc @ sp.csr_matrix(la.solve(b["K_cc"], b["K_lc"].T))
        return (b["K_ll"] - correction).tocsc()
