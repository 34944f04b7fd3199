"""The project's own ``.npz`` models (:mod:`mmshbm.model.files`, :meth:`Model.save_npz`):
their M, K and C; a ``dofs`` entry ((n, 2) node and component) when the file has one,
plain indices otherwise. The file's contacts are not part of :class:`FEMatrices` (name
them in :meth:`FEMatrices.model`; ``Model.from_npz`` keeps them)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._build import Part, ReadError

__all__ = ["read_own_npz"]


def read_own_npz(path: Path, data: dict) -> Part:
    from ..files import _matrix

    where = f"model file {str(path)!r}"
    mats = {"M": _matrix(data, "M", where), "K": _matrix(data, "K", where)}
    C = _matrix(data, "C", where, required=False)
    if C is not None:
        mats["C"] = C
    dofs = None
    if "dofs" in data:
        dofs = np.asarray(data["dofs"])
        if dofs.ndim != 2 or dofs.shape != (mats["K"].shape[0], 2) or dofs.dtype.kind not in "iu":
            raise ReadError(f"{where}: 'dofs' must be an (n, 2) integer array, got {dofs.shape} {dofs.dtype}")
        order = np.lexsort((dofs[:, 1], dofs[:, 0]))
        dofs = dofs[order].astype(np.int64)
        mats = {k: A[order][:, order] if hasattr(A, "tocsr") else np.asarray(A)[np.ix_(order, order)]
                for k, A in mats.items()}
    return Part(str(path), mats, dofs)
