"""Mass and stiffness matrices exported by FE packages, read into :class:`FEMatrices`.

    fe = mmshbm.read_fe("job_MASS1.mtx", "job_STIF1.mtx")
    fe.frequencies(3)                                        # Hz: check the units
    model = fe.model(contact=[(11, 2, 1e-3, +1)])            # stop under node 11, u_y

One module per format (the format names of ``read_fe(..., format=...)``):

=================  ===========================================  ==========================
format             files                                        module
=================  ===========================================  ==========================
abaqus             ``*MATRIX OUTPUT, FORMAT=MATRIX INPUT`` pair  :mod:`.abaqus`
abaqus-user        ``*SUBSTRUCTURE MATRIX OUTPUT`` (user elem.)  :mod:`.abaqus`
ansys              ``.full`` (ansys-mapdl-reader)               :mod:`.ansys`
op4                NASTRAN OUTPUT4, text or binary              :mod:`.op4`
dmig               NASTRAN DMIG bulk data / punch               :mod:`.dmig`
op2                NASTRAN OP2 (pyNastran)                      :mod:`.op2`
matrix-market      ``.mtx`` pair (``%%MatrixMarket``)           :mod:`.sparse_text`
harwell-boeing     ``.rua`` / ``.rb`` / ``.hb`` pair            :mod:`.sparse_text`
matlab             ``.mat`` v5 (scipy) or v7.3 (h5py)           :mod:`.matlab`
code-aster         ``.npz`` of ``EXTR_MATR(sparse=True)``       :mod:`.code_aster`
npz                mmshbm's own ``.npz``                        :mod:`.npz`
=================  ===========================================  ==========================

The heavy readers (ansys-mapdl-reader, h5py: the extra ``pip install 'mmshbm[fe]'``;
pyNastran: ``'mmshbm[op2]'``) are imported only by the functions that need them.
"""

from __future__ import annotations

import re
import zipfile
from pathlib import Path

from ._build import ReadError
from .fematrices import FEMatrices

__all__ = ["read_fe", "FEMatrices", "ReadError", "FORMATS", "detect_format"]

FORMATS = ("abaqus", "abaqus-user", "ansys", "op4", "dmig", "op2", "matrix-market", "harwell-boeing",
           "matlab", "code-aster", "npz")
#: formats whose files hold one matrix each (mass and stiffness in two files)
_ONE_MATRIX = ("abaqus", "matrix-market", "harwell-boeing")
_EXTENSIONS = {".full": "ansys", ".op2": "op2", ".op4": "op4", ".mat": "matlab", ".rua": "harwell-boeing",
               ".rsa": "harwell-boeing", ".rb": "harwell-boeing", ".hb": "harwell-boeing",
               ".inp": "abaqus-user",
               ".pch": "dmig", ".bdf": "dmig", ".blk": "dmig"}


def read_fe(*paths, format: str | None = None, names: dict | None = None) -> FEMatrices:  # noqa: A002
    """The mass, stiffness (and damping) matrices of an FE export.

    Parameters
    ----------
    *paths : str or Path
        One file holding both matrices (OP4, DMIG, OP2, .full, .mat, .npz, an Abaqus user
        element), or one file per matrix (Abaqus ``*_MASS*.mtx`` / ``*_STIF*.mtx``, Matrix
        Market, Harwell–Boeing). The role of a one-matrix file comes from its name
        (``MASS``/``STIF``/``DMPV``, ``mass``/``stiff``, ``M``/``K``/``C``); failing that
        two files are taken in the order (mass, stiffness).
    format : str, optional
        One of :data:`FORMATS`; default: from the extension and the content.
    names : dict, optional
        For files of named matrices (OP4, DMIG, OP2, .mat): ``{"M": "MAA", "K": "KAA"}``
        when the names do not say it.

    Returns
    -------
    FEMatrices
        Symmetric CSR matrices with the constrained DOFs removed, and the DOF table.

    Raises
    ------
    ValueError
        A file that is not of the format, a malformed entry (file and line or DOF named),
        non-square, non-symmetric or non-finite matrices, DOF counts that differ, a K that
        is not positive definite once the constrained DOFs are removed.
    ImportError
        The optional package a format needs is missing (named, with the pip command).
    FileNotFoundError
        A path that does not exist.
    """
    from ._build import finish

    if not paths:
        raise TypeError("read_fe needs at least one file")
    paths = [Path(p) for p in paths]
    for p in paths:
        if not p.is_file():
            raise FileNotFoundError(f"no such file: {str(p)!r}")
    if format is not None and format not in FORMATS:
        raise ValueError(f"format must be one of {', '.join(FORMATS)}; got {format!r}")
    formats = [format or detect_format(p) for p in paths]
    if len(set(formats)) > 1:
        listed = ", ".join(f"{str(p)!r}: {f}" for p, f in zip(paths, formats, strict=True))
        raise ReadError(f"the files are of different formats ({listed}); give the files of one export")
    fmt = formats[0]
    if fmt not in _ONE_MATRIX and len(paths) > 1:
        raise ReadError(f"{fmt} files hold mass and stiffness together: give one file, got {len(paths)}")
    if fmt in _ONE_MATRIX:
        parts = [_one_matrix(fmt, p, role) for p, role in zip(paths, _roles(paths, fmt), strict=True)]
    else:
        parts = [_both(fmt, paths[0], names)]
    return finish(parts, fmt)


def detect_format(path: Path) -> str:
    """The format of ``path`` from its extension and first bytes (ValueError if unknown)."""
    from . import abaqus, dmig, op4

    path = Path(path)
    ext = path.suffix.lower()
    if ext in _EXTENSIONS and ext not in (".inp", ".bdf", ".pch", ".blk"):
        return _EXTENSIONS[ext]
    with open(path, "rb") as f:
        raw = f.read(4096)
    if zipfile.is_zipfile(path):
        return "code-aster" if _npz_is_aster(path) else "npz"
    if op4.is_binary_op4(raw):
        return "op4"
    if raw[:8] == b"\x89HDF\r\n\x1a\n" or raw[512:520] == b"\x89HDF\r\n\x1a\n" or raw[:10] == b"MATLAB 5.0":
        return "matlab"
    head = raw.decode("ascii", "replace")
    if head.lstrip().startswith("%%MatrixMarket"):
        return "matrix-market"
    kind = abaqus.looks_like(head)
    if kind == "user-element":
        return "abaqus-user"
    if kind == "matrix-input":
        return "abaqus"
    if dmig.looks_like(head):
        return "dmig"
    first = head.splitlines()[0] if head.strip() else ""
    if re.match(r"^\s*\d+\s+-?\d+\s+\d+\s+\d+\s*[A-Za-z]", first):
        return "op4"
    if ext in _EXTENSIONS:
        return _EXTENSIONS[ext]
    raise ReadError(f"cannot tell the format of {str(path)!r}: give format= (one of {', '.join(FORMATS)})")


def _npz_is_aster(path: Path) -> bool:
    from . import code_aster

    with zipfile.ZipFile(path) as z:
        keys = {n[:-4] if n.endswith(".npy") else n for n in z.namelist()}
    return code_aster.looks_like(keys)


def _roles(paths, fmt: str) -> list:
    from .abaqus import role_of

    roles = []
    for p in paths:
        role = role_of(p) if fmt == "abaqus" else None
        roles.append(role or _role_from_name(p))
    if all(r is not None for r in roles):
        return roles
    if len(paths) == 2 and not any(roles):
        return ["M", "K"]
    if len(paths) == 2 and sum(r is None for r in roles) == 1:
        known = next(r for r in roles if r)
        other = {"M": "K", "K": "M"}.get(known)
        return [r or other for r in roles]
    unknown = [str(p) for p, r in zip(paths, roles, strict=True) if r is None]
    raise ReadError(f"cannot tell which matrix {unknown[0]!r} holds: name the files *_MASS* and *_STIF* (or "
                    "mass/stiffness, M/K), or give two files in the order mass, stiffness")


def _role_from_name(path: Path) -> str | None:
    stem = path.stem.lower()
    if "mass" in stem:
        return "M"
    if "stif" in stem:
        return "K"
    if "damp" in stem or "dmpv" in stem:
        return "C"
    tokens = re.split(r"[_\-.\s]+", stem)
    for token, role in (("m", "M"), ("k", "K"), ("c", "C")):
        if token in tokens:
            return role
    return None


def _one_matrix(fmt: str, path: Path, role: str):
    if fmt == "abaqus":
        from .abaqus import read_matrix_input

        return read_matrix_input(path, role)
    from . import sparse_text

    reader = sparse_text.read_matrix_market if fmt == "matrix-market" else sparse_text.read_harwell_boeing
    return reader(path, role)


def _both(fmt: str, path: Path, names):
    if fmt == "abaqus-user":
        from .abaqus import read_user_element

        return read_user_element(path)
    if fmt == "ansys":
        from .ansys import read_full

        return read_full(path)
    if fmt == "op4":
        from .op4 import read_op4

        return read_op4(path, names)
    if fmt == "dmig":
        from .dmig import read_dmig

        return read_dmig(path, names)
    if fmt == "op2":
        from .op2 import read_op2

        return read_op2(path, names)
    if fmt == "matlab":
        from .matlab import read_mat

        return read_mat(path, names)
    from ..files import _load

    data = _load(path)
    if fmt == "code-aster":
        from .code_aster import read_aster

        return read_aster(path, data)
    from .npz import read_own_npz

    return read_own_npz(path, data)
