"""Models on disk: ``.npz`` archives (written by :meth:`Model.save_npz` or any FE package
that writes NumPy arrays) and Matrix Market files.

An ``.npz`` model holds ``M`` and ``K`` either as dense 2-D arrays or as CSR parts
(``M_data``, ``M_indices``, ``M_indptr``, ``M_shape`` and the same for ``K``), optionally
a damping matrix ``C`` in either form, and the contact data ``contact_dof``, ``gap``,
``stop_side`` (scalars or equal-length 1-D arrays), ``amplitude_dof`` and a JSON
``description``. Arguments given to the reader override the file.
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np
import scipy.sparse as sp

__all__ = ["read_npz", "write_npz", "read_matrix_market"]


def _load(path: Path) -> dict:
    where = f"model file {str(path)!r}"
    try:
        if path.is_file() and not zipfile.is_zipfile(path):
            raise ValueError("not an .npz archive")
        loaded = np.load(path, allow_pickle=False)
        if not hasattr(loaded, "files"):
            raise ValueError("not an .npz archive (it holds a single array)")
        with loaded as f:
            return {k: f[k] for k in f.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as err:
        raise ValueError(f"cannot read {where}: {err}") from None


def _matrix(data: dict, name: str, where: str, required: bool = True):
    if name in data:
        return data[name]
    parts = [f"{name}_{p}" for p in ("data", "indices", "indptr", "shape")]
    if all(p in data for p in parts):
        d, i, p, s = (data[q] for q in parts)
        try:
            A = sp.csr_matrix((d, i, p), shape=tuple(int(v) for v in s))
            A.check_format(full_check=True)
        except (TypeError, ValueError, IndexError) as err:
            raise ValueError(f"{where}: the CSR parts of {name!r} are malformed: {err}") from None
        return A
    if required:
        raise ValueError(f"{where} has no matrix {name!r} (keys: {sorted(data)})")
    return None


def _entry(data: dict, name: str, given, where: str, default=None, integer: bool = False):
    """A scalar or 1-D entry of the file (``given`` overrides it)."""
    if given is not None:
        return given
    if name not in data:
        if default is not None:
            return default
        raise ValueError(f"{where} has no {name!r}; pass {name}=...")
    value = data[name]
    if value.ndim > 1 or value.dtype.kind not in "biuf":
        raise ValueError(f"{where}: {name!r} must be a number or a 1-D array of numbers, got {value!r}")
    if integer and value.dtype.kind == "f":
        if not np.all(value == np.round(value)):
            raise ValueError(f"{where}: {name!r} must hold integers, got {value!r}")
        value = value.astype(np.int64)
    return value.item() if value.ndim == 0 else value.tolist()


def read_npz(path, contact_dof=None, gap=None, stop_side=None, amplitude_dof=None) -> dict:
    """Keyword arguments of :meth:`Model.from_matrices` read from an ``.npz`` model file.

    Raises
    ------
    ValueError
        For an unreadable file, a missing or malformed entry (named).
    """
    path = Path(path)
    where = f"model file {str(path)!r}"
    data = _load(path)
    description = {}
    if "description" in data:
        try:
            description = json.loads(str(data["description"]))
        except json.JSONDecodeError as err:
            raise ValueError(f"{where}: 'description' is not valid JSON ({err})") from None
        if not isinstance(description, dict):
            raise ValueError(f"{where}: 'description' must be a JSON object, got {description!r}")
    amp = amplitude_dof
    if amp is None and "amplitude_dof" in data:
        amp = _entry(data, "amplitude_dof", None, where, integer=True)
        amp = None if amp == -1 else amp  # -1: not set
    return {
        "M": _matrix(data, "M", where), "K": _matrix(data, "K", where),
        "contact_dof": _entry(data, "contact_dof", contact_dof, where, integer=True),
        "gap": _entry(data, "gap", gap, where),
        "stop_side": _entry(data, "stop_side", stop_side, where, default=1, integer=True),
        "description": description, "damping": _matrix(data, "C", where, required=False),
        "amplitude_dof": amp,
        **({"friction": _friction(data, where)} if "friction" in data else {}),
    }


def _friction(data: dict, where: str) -> list[dict]:
    from .friction import friction_from_json

    try:
        return friction_from_json(data["friction"])
    except (json.JSONDecodeError, ValueError) as err:
        raise ValueError(f"{where}: 'friction' is malformed: {err}") from None


def write_npz(path, model) -> None:
    """Write ``model`` (CSR parts, contacts, damping, friction, description) to ``path``."""
    from .friction import friction_to_json

    parts = {}
    mats = [("M", model.M), ("K", model.K)] + ([("C", model.damping)] if model.damping is not None else [])
    for name, A in mats:
        A = sp.csr_matrix(A)
        parts.update({f"{name}_data": A.data, f"{name}_indices": A.indices,
                      f"{name}_indptr": A.indptr, f"{name}_shape": np.array(A.shape)})
    contacts = model.contacts
    single = len(contacts) == 1
    np.savez(path, **parts,
             contact_dof=contacts[0].dof if single else np.array([c.dof for c in contacts]),
             gap=contacts[0].gap if single else np.array([c.gap for c in contacts]),
             stop_side=contacts[0].side if single else np.array([c.side for c in contacts]),
             amplitude_dof=-1 if model._amplitude_dof is None else model._amplitude_dof,
             description=json.dumps(model.description),
             **({"friction": friction_to_json(model.friction)} if model.friction else {}))


def read_matrix_market(M_path, K_path) -> tuple:
    """(M, K) read from two Matrix Market (``.mtx``) files."""
    import scipy.io

    mats = []
    for name, p in (("M", M_path), ("K", K_path)):
        try:
            mats.append(scipy.io.mmread(str(p)))
        except (OSError, ValueError) as err:
            raise ValueError(f"cannot read {name} from {str(p)!r}: {err}") from None
    return mats[0], mats[1]
