"""From what a reader found in a file to checked :class:`FEMatrices`: DOF tables merged
across files, symmetric matrices from one stored triangle, constrained DOFs removed, and
the import checks (matching sizes, symmetry, finite entries, K positive definite).

Every reader returns :class:`Part` values: the matrices of one file (by role ``"M"``,
``"K"``, ``"C"``) with the DOF labels of their rows, or ``None`` where the format has none.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

__all__ = ["Part", "finish", "from_labelled", "full_symmetric", "ReadError"]

#: symmetric to this fraction of the largest entry (text files round to 16 digits)
SYMMETRY_RTOL = 1e-10
ROLES = ("M", "K", "C")
_ROLE_NAMES = {"M": "mass", "K": "stiffness", "C": "damping"}


class ReadError(ValueError):
    """A file that cannot be read as an FE export (the message names the file and entry)."""


@dataclass
class Part:
    """The matrices one file holds.

    Attributes
    ----------
    source : str
        The file (for messages).
    matrices : dict
        Role ("M", "K", "C") -> sparse matrix, shape (n, n), indexed like ``dofs``.
    dofs : ndarray of int, shape (n, 2), or None
        (node, component) of each row; None: the format names no DOFs (plain indices).
    lagrange : ndarray of bool, shape (n,), or None
        Rows that are Lagrange multipliers (removed with the DOFs they constrain).
    """

    source: str
    matrices: dict
    dofs: np.ndarray | None = None
    lagrange: np.ndarray | None = None
    notes: list = field(default_factory=list)


def from_labelled(source: str, entries: dict) -> Part:
    """A :class:`Part` from labelled triplets: ``entries[role] = (row_labels, col_labels,
    values)`` with labels of shape (m, 2) (node, component); the DOF table is the sorted
    union of every label the file names."""
    labels = [np.asarray(lab, dtype=np.int64).reshape(-1, 2)
              for rows, cols, _ in entries.values() for lab in (rows, cols)]
    table = np.unique(np.concatenate(labels), axis=0) if labels else np.zeros((0, 2), np.int64)
    matrices = {}
    for role, (rows, cols, values) in entries.items():
        i, j = _positions(table, rows), _positions(table, cols)
        matrices[role] = sp.coo_matrix((np.asarray(values, float), (i, j)), shape=(len(table),) * 2).tocsr()
    return Part(source, matrices, table)


def _positions(table: np.ndarray, labels) -> np.ndarray:
    labels = np.asarray(labels, dtype=np.int64).reshape(-1, 2)
    keys = table[:, 0] * (1 << 20) + table[:, 1]
    return np.searchsorted(keys, labels[:, 0] * (1 << 20) + labels[:, 1])


def full_symmetric(A, name: str, where: str, dofs: np.ndarray | None = None) -> sp.csr_matrix:
    """The symmetric matrix of which ``A`` holds one triangle (lower or upper) or both.

    A full matrix must be symmetric to :data:`SYMMETRY_RTOL` of its largest entry; it is
    returned as ``(A + Aᵀ)/2``. Raises :class:`ReadError` naming the worst entry."""
    A = sp.csr_matrix(A, dtype=float)
    A.sum_duplicates()
    if A.shape[0] != A.shape[1]:
        raise ReadError(f"{where}: {name} is not square ({A.shape[0]} x {A.shape[1]})")
    if A.nnz and not np.all(np.isfinite(A.data)):
        k = int(np.argmax(~np.isfinite(A.data)))
        i = int(np.searchsorted(A.indptr, k, side="right") - 1)
        raise ReadError(f"{where}: {name} has a non-finite entry at {_label(dofs, i)}: {A.data[k]!r}")
    A.eliminate_zeros()
    off = (A - sp.diags(A.diagonal())).tocsr()
    off.eliminate_zeros()
    pattern = off.copy()
    pattern.data[:] = 1.0
    mirrored = pattern.multiply(pattern.T).nnz
    if mirrored == 0:  # one triangle, in whatever order the file numbers its DOFs
        return (A + off.T).tocsr()
    if mirrored != off.nnz:
        both = np.asarray(pattern.multiply(pattern.T).sum(axis=1)).ravel()
        k = int(np.argmax(both < np.diff(pattern.indptr)))
        raise ReadError(f"{where}: {name} gives some entries in both triangles and some in one only (e.g. in "
                        f"the row of {_label(dofs, k)}): give one triangle or the full matrix")
    scale = abs(A).max()
    asym = abs(A - A.T).tocoo()
    if asym.nnz and asym.data.max() > SYMMETRY_RTOL * scale:
        k = int(np.argmax(asym.data))
        i, j = int(asym.row[k]), int(asym.col[k])
        raise ReadError(f"{where}: {name} is not symmetric: the entry at ({_label(dofs, i)}; "
                        f"{_label(dofs, j)}) "
                        f"is {float(A[i, j])!r}, its mirror {float(A[j, i])!r}")
    return ((A + A.T) * 0.5).tocsr()


def _label(dofs, i: int) -> str:
    if dofs is None or dofs[i, 1] == 0:
        return f"row {i}"
    return f"node {int(dofs[i, 0])} component {int(dofs[i, 1])}"


def _merge(parts: list[Part]) -> tuple[dict, np.ndarray | None, np.ndarray | None, dict]:
    """One matrix per role on a common DOF table (the union of the parts' labels)."""
    where = {}
    for part in parts:
        for role in part.matrices:
            if role in where:
                raise ReadError(f"two files give the {_ROLE_NAMES[role]} matrix {role}: {where[role]!r} and "
                                f"{part.source!r}")
            where[role] = part.source
    labelled = [p.dofs is not None for p in parts]
    if any(labelled) and not all(labelled):
        plain = [p.source for p in parts if p.dofs is None]
        raise ReadError(f"{plain[0]!r} names no DOFs (nodes and components) but "
                        f"{[p.source for p in parts if p.dofs is not None][0]!r} does: give files of "
                        f"one format")
    if not all(labelled):
        sizes = {p.source: A.shape[0] for p in parts for A in p.matrices.values()}
        if len(set(sizes.values())) > 1:
            listed = ", ".join(f"{s!r}: {n}" for s, n in sizes.items())
            raise ReadError(f"the matrices have different numbers of DOFs ({listed}); they must be of "
                            f"one model")
        mats = {role: A for p in parts for role, A in p.matrices.items()}
        lag = next((p.lagrange for p in parts if p.lagrange is not None), None)
        return mats, None, lag, where
    table = np.unique(np.concatenate([p.dofs for p in parts]), axis=0)
    mats, lag = {}, np.zeros(len(table), bool)
    for p in parts:
        pos = _positions(table, p.dofs)
        if p.lagrange is not None:
            lag[pos[p.lagrange]] = True
        for role, A in p.matrices.items():
            A = sp.coo_matrix(A)
            mats[role] = sp.coo_matrix((A.data, (pos[A.row], pos[A.col])), shape=(len(table),) * 2).tocsr()
    return mats, table, lag if lag.any() else None, where


def finish(parts: list[Part], fmt: str):
    """Checked :class:`~mmshbm.model.readers.FEMatrices` from the parts of one model."""
    from .fematrices import FEMatrices

    mats, dofs, lagrange, where = _merge(parts)
    for role in ("M", "K"):
        if role not in mats:
            given = ", ".join(repr(p.source) for p in parts)
            raise ReadError(f"no {_ROLE_NAMES[role]} matrix {role} in {given}: give the "
                            f"{_ROLE_NAMES[role]} file too (or name it so: *_MASS*, *_STIF*, M.mtx, K.mtx)")
    mats = {role: full_symmetric(A, role, where[role], dofs) for role, A in mats.items()}
    n = mats["K"].shape[0]
    if dofs is None:
        dofs = np.column_stack([np.arange(n), np.zeros(n, np.int64)])
    keep, removed = _unconstrained(mats, lagrange, dofs, where)
    if not keep.all():
        mats = {role: A[keep][:, keep].tocsr() for role, A in mats.items()}
        dofs = dofs[keep]
    for A in mats.values():
        A.eliminate_zeros()
        A.sort_indices()
    _check_definite(mats, dofs, where)
    return FEMatrices(M=mats["M"], K=mats["K"], C=mats.get("C"), dofs=np.ascontiguousarray(dofs),
                      source=tuple(p.source for p in parts), format=fmt, removed=removed)


def _unconstrained(mats: dict, lagrange, dofs: np.ndarray, where: dict) -> tuple[np.ndarray, np.ndarray]:
    """The DOFs kept (bool mask) and the (node, component) table of those removed: rows of
    K that are zero (constrained DOFs exported as zero rows), Lagrange multipliers and the
    DOF each of them fixes."""
    K = mats["K"]
    n = K.shape[0]
    drop = np.zeros(n, bool)
    if lagrange is not None:
        drop |= lagrange
        coupling = K[lagrange][:, ~lagrange].tocsr()
        per_row = np.diff(coupling.indptr)
        if np.any(per_row > 1):
            r = int(np.flatnonzero(lagrange)[np.argmax(per_row > 1)])
            raise ReadError(f"{where['K']}: the Lagrange multiplier at {_label(dofs, r)} ties several DOFs "
                            "(a linear relation); only fixed DOFs (DDL_IMPO = 0) can be removed: eliminate "
                            "relations before exporting (e.g. AFFE_CHAR_CINE)")
        fixed = np.flatnonzero(~lagrange)[np.unique(coupling.indices)]
        drop[fixed] = True
    empty = np.diff(K.indptr) == 0
    if K.nnz:
        empty |= np.asarray(abs(K).sum(axis=1)).ravel() == 0
    drop |= empty
    M = mats["M"]
    mass_only = drop & ~(lagrange if lagrange is not None else np.zeros(n, bool))
    inertia = np.asarray(abs(M[mass_only]).sum(axis=1)).ravel() if mass_only.any() else np.zeros(0)
    if np.any(inertia > 0) and lagrange is None:
        r = int(np.flatnonzero(mass_only)[np.argmax(inertia > 0)])
        raise ReadError(f"{where['K']}: the DOF at {_label(dofs, r)} has mass but no stiffness: the "
                        f"structure "
                        "is not fixed there (or M and K are swapped)")
    physical = drop if lagrange is None else drop & ~lagrange
    return ~drop, dofs[physical]


def _check_definite(mats: dict, dofs: np.ndarray, where: dict) -> None:
    from ..linear_modes import _require_positive_definite

    M, K = mats["M"], mats["K"]
    if K.shape[0] == 0:
        raise ReadError(f"{where['K']}: every DOF is constrained: nothing is left")
    if M.shape != K.shape:
        raise ReadError(f"{where['M']} and {where['K']}: M is {M.shape[0]} x {M.shape[0]}, K {K.shape[0]} x "
                        f"{K.shape[0]}: the DOF counts must match")
    d = M.diagonal()
    if np.any(d < 0):
        r = int(np.argmin(d))
        raise ReadError(f"{where['M']}: M has a negative diagonal entry at {_label(dofs, r)}: {d[r]!r} (is "
                        "it a mass matrix?)")
    d = K.diagonal()
    if np.any(d <= 0):
        r = int(np.argmin(d))
        raise ReadError(f"{where['K']}: K has a diagonal entry {d[r]!r} <= 0 at {_label(dofs, r)}: it is not "
                        "positive definite (a Lagrange multiplier or a free DOF left in?)")
    try:
        _require_positive_definite(K, "K")
    except ValueError as err:
        raise ReadError(f"{where['K']}: {err} (after removing the constrained DOFs)") from None
