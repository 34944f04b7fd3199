"""MATLAB ``.mat`` files: version 5 (``save``, ``save -v7``; scipy) and version 7.3
(``save -v7.3``, HDF5; needs h5py: ``pip install 'mmshbm[fe]'``).

The variables: the mass ``M`` (or ``Mass``, ``MAA``...), the stiffness ``K``, optionally
the damping ``C`` or ``D`` (NLvib's name), dense or sparse, and optionally ``dofs``, an
(n, 2) array of node and component (otherwise the DOFs are plain indices). Which variable
is which follows the names (:mod:`mmshbm.model.readers.names`); ``names=`` overrides.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ._build import Part, ReadError
from .names import roles_from_names

__all__ = ["read_mat", "is_hdf5"]

_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def is_hdf5(path: Path) -> bool:
    """True for an HDF5 file (its signature at byte 0 or at 512, after MATLAB's header)."""
    with open(path, "rb") as f:
        head = f.read(520)
    return head[:8] == _HDF5_SIGNATURE or head[512:520] == _HDF5_SIGNATURE


def read_mat(path: Path, names: dict | None = None) -> Part:
    where = str(path)
    variables = _read_v73(path) if is_hdf5(path) else _read_v5(path)
    roles = roles_from_names([k for k in variables if k.lower() != "dofs"], where, names)
    if "M" not in roles or "K" not in roles:
        raise ReadError(f"{where}: expected variables M and K (mass and stiffness), found "
                        f"{sorted(variables)}")
    mats = {}
    for role, name in roles.items():
        A = variables[name]
        A = sp.csr_matrix(A, dtype=float) if sp.issparse(A) or np.ndim(A) == 2 else None
        if A is None:
            raise ReadError(f"{where}: variable {name!r} is not a 2-D matrix")
        mats[role] = A
    dofs = None
    if "dofs" in {k.lower() for k in variables}:
        raw = np.asarray(next(v for k, v in variables.items() if k.lower() == "dofs"))
        if raw.ndim == 2 and raw.shape[0] == 2 and raw.shape[1] != 2:
            raw = raw.T
        if raw.ndim != 2 or raw.shape[1] != 2 or raw.shape[0] != mats["K"].shape[0]:
            raise ReadError(f"{where}: 'dofs' must be an (n, 2) array of node and component, n = "
                            f"{mats['K'].shape[0]}; got shape {raw.shape}")
        if not np.all(raw == np.round(raw)):
            raise ReadError(f"{where}: 'dofs' must hold integers (node, component)")
        dofs = raw.astype(np.int64)
        if len(np.unique(dofs, axis=0)) != len(dofs):
            raise ReadError(f"{where}: 'dofs' names a DOF twice")
        order = np.lexsort((dofs[:, 1], dofs[:, 0]))
        dofs = dofs[order]
        mats = {role: A[order][:, order].tocsr() for role, A in mats.items()}
    return Part(where, mats, dofs)


def _read_v5(path: Path) -> dict:
    import scipy.io

    try:
        data = scipy.io.loadmat(str(path))
    except (OSError, ValueError, TypeError) as err:
        raise ReadError(f"cannot read {str(path)!r} as a MATLAB file: {err}") from None
    return {k: v for k, v in data.items() if not k.startswith("__")}


def _read_v73(path: Path) -> dict:
    try:
        import h5py
    except ImportError:
        raise ImportError("reading MATLAB v7.3 (HDF5) .mat files needs h5py: pip install 'mmshbm[fe]' (or "
                          "save with -v7 in MATLAB)") from None
    out = {}
    with h5py.File(path, "r") as f:
        for key, item in f.items():
            if key.startswith("#"):
                continue
            if isinstance(item, h5py.Group) and {"data", "ir", "jc"} <= set(item):
                n_rows = int(item.attrs.get("MATLAB_sparse"))
                jc = np.asarray(item["jc"], dtype=np.int64)
                ir = np.asarray(item["ir"], np.int64)
                out[key] = sp.csc_matrix((np.asarray(item["data"], float), ir, jc),
                                         shape=(n_rows, len(jc) - 1))
            elif isinstance(item, h5py.Dataset):
                out[key] = np.asarray(item).T  # MATLAB stores columns first
    return out
