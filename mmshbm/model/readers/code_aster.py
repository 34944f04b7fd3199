"""code_aster matrices: the triplets of ``EXTR_MATR(sparse=True)`` saved with NumPy.

``EXTR_MATR(sparse=True)`` returns ``(values, rows, columns, size)`` of an assembled
matrix (0-based indices; one triangle of a symmetric matrix, or both). Saved from the
code_aster script as

    np.savez("beam_aster.npz", K_data=v, K_rows=r, K_cols=c, M_data=..., M_rows=...,
             M_cols=..., dim=size, nodes=..., components=...)

(``C_*`` for damping; ``nodes`` and ``components`` optional: the node number and the
component name, ``DX`` ... ``DRZ``, of each row from the matrix's DOF numbering). Boundary
conditions imposed by ``AFFE_CHAR_MECA(DDL_IMPO=...)`` are dualised: the matrices hold
Lagrange-multiplier rows, named ``LAGR...`` in ``components`` or, without names, found as
the rows with zero mass and a stiffness diagonal <= 0. They are removed together with the
DOF each of them fixes (a multiplier tying several DOFs, a ``LIAISON_*`` relation, is
refused). ``AFFE_CHAR_CINE`` (eliminated conditions) needs none of this.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ._build import Part, ReadError

__all__ = ["read_aster", "looks_like", "COMPONENTS"]

#: component names -> 1..6
COMPONENTS = {"DX": 1, "DY": 2, "DZ": 3, "DRX": 4, "DRY": 5, "DRZ": 6}


def looks_like(keys) -> bool:
    return {"K_data", "K_rows", "K_cols"} <= set(keys)


def read_aster(path: Path, data: dict) -> Part:
    where = str(path)
    if "dim" not in data:
        raise ReadError(f"{where}: no 'dim' (the size EXTR_MATR returns)")
    n = int(np.asarray(data["dim"]).ravel()[0])
    mats = {}
    for role in ("M", "K", "C"):
        parts = [f"{role}_{p}" for p in ("data", "rows", "cols")]
        if not all(p in data for p in parts):
            continue
        v, r, c = (np.asarray(data[p]).ravel() for p in parts)
        if not len(v) == len(r) == len(c):
            raise ReadError(f"{where}: {role}_data, {role}_rows, {role}_cols differ in length "
                            f"({len(v)}, {len(r)}, {len(c)})")
        if len(r) and (min(r.min(), c.min()) < 0 or max(r.max(), c.max()) >= n):
            raise ReadError(f"{where}: {role} has an index outside 0..{n - 1} (dim {n}; EXTR_MATR "
                            f"indices are "
                            "0-based)")
        mats[role] = sp.coo_matrix((v.astype(float), (r.astype(np.int64), c.astype(np.int64))),
                                   shape=(n, n)).tocsr()
    dofs, lagrange = None, None
    if "components" in data:
        names = [str(s).strip().upper() for s in np.asarray(data["components"]).ravel()]
        if len(names) != n:
            raise ReadError(f"{where}: 'components' has {len(names)} names for {n} DOFs")
        lagrange = np.array([s.startswith("LAGR") for s in names])
        unknown = sorted({s for s in names if not s.startswith("LAGR") and s not in COMPONENTS})
        if unknown:
            raise ReadError(f"{where}: unknown components {unknown} (expected {sorted(COMPONENTS)} or "
                            f"LAGR...)")
        nodes = np.asarray(data["nodes"]).ravel() if "nodes" in data else np.arange(n)
        if len(nodes) != n:
            raise ReadError(f"{where}: 'nodes' has {len(nodes)} entries for {n} DOFs")
        # multipliers get component 0 and a negative row id (they are removed, their labels only keep
        # the table unique)
        comps = [COMPONENTS.get(s, 0) for s in names]
        dofs = np.column_stack([np.where(lagrange, -1 - np.arange(n), nodes.astype(np.int64)), comps])
    elif "K" in mats and "M" in mats:
        K, M = mats["K"], mats["M"]
        massless = np.asarray(abs(M).sum(axis=1)).ravel() == 0
        lagrange = massless & ((K + K.T).diagonal() <= 0)
    return Part(where, mats, dofs, lagrange if lagrange is not None and lagrange.any() else None)
