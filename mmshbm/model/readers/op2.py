"""NASTRAN OP2 files with matrices (``PARAM,POST,-1`` plus ``PARAM,EXTOUT,MATRIXDB`` or
``OUTPUT2`` of KAA/MAA), read by pyNastran (``pip install 'mmshbm[op2]'``, apart from the
``fe`` extra: pyNastran 1.4 requires NumPy < 2). OP2 matrices carry no DOF table here:
plain indices.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ._build import Part, ReadError
from .names import roles_from_names

__all__ = ["read_op2"]


def read_op2(path: Path, names: dict | None = None) -> Part:
    try:
        from pyNastran.op2.op2 import OP2
    except ImportError:
        raise ImportError("reading NASTRAN .op2 files needs pyNastran: pip install 'mmshbm[op2]' (pyNastran "
                          "1.4 requires NumPy < 2; OP4 and DMIG need nothing extra)") from None
    except AttributeError as err:  # pyNastran releases that predate the installed NumPy
        raise ImportError(f"pyNastran cannot be imported with NumPy {np.__version__} ({err}); install a "
                          "pyNastran release that supports it, or export OP4 (OUTPUT4) instead") from None
    where = str(path)
    op2 = OP2(debug=False)
    try:
        op2.read_op2(str(path), skip_undefined_matrices=False)
    except (OSError, ValueError, RuntimeError, KeyError) as err:
        raise ReadError(f"cannot read {where!r} as an OP2 file: {err}") from None
    found = {name: getattr(m, "data", m) for name, m in getattr(op2, "matrices", {}).items()}
    if not found:
        raise ReadError(f"{where}: no matrices in the OP2 file (write them with PARAM,EXTOUT,MATRIXDB or "
                        "OUTPUT2)")
    roles = roles_from_names(found, where, names)
    return Part(where, {role: sp.csr_matrix(found[name], dtype=float) for role, name in roles.items()})
