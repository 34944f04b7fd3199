"""ANSYS ``.full`` files (the assembled matrices of a modal analysis, ``WRFULL`` or a
``MODOPT`` solve), read by ansys-mapdl-reader (``pip install 'mmshbm[fe]'``).

``read_binary(path).load_km()`` gives the DOF table (node, component 0..) and the upper
triangles of K and M; constrained DOFs are there as zero rows and are removed. Components
are numbered from 1 here (1 = UX, 2 = UY, 3 = UZ, 4..6 = ROTX..ROTZ), as the other formats.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._build import Part, ReadError

__all__ = ["read_full"]


def read_full(path: Path) -> Part:
    try:
        from ansys.mapdl import reader as mapdl_reader
    except ImportError:
        raise ImportError("reading ANSYS .full files needs ansys-mapdl-reader: pip install "
                          "'mmshbm[fe]'") from None
    where = str(path)
    try:
        full = mapdl_reader.read_binary(str(path))
        dof_ref, K, M = full.load_km(as_sparse=True, sort=False)
    except (OSError, ValueError, RuntimeError, KeyError) as err:
        raise ReadError(f"cannot read {where!r} as an ANSYS .full file: {err}") from None
    dofs = np.asarray(dof_ref, dtype=np.int64).copy()
    dofs[:, 1] += 1
    if len(np.unique(dofs, axis=0)) != len(dofs):
        raise ReadError(f"{where}: its DOF table names a DOF twice")
    order = np.lexsort((dofs[:, 1], dofs[:, 0]))
    return Part(where, {"K": K.tocsr()[order][:, order], "M": M.tocsr()[order][:, order]}, dofs[order])
