"""The ``.npz`` archive of results files: arrays plus one JSON ``metadata`` record,
written atomically with the umask's permissions, read back with a message of its own
for every wrong kind of file."""

from __future__ import annotations

import json
import os
import tempfile
import zipfile
from pathlib import Path

import numpy as np

from .._files import apply_umask

__all__ = ["write_archive", "read_archive"]


def write_archive(path, arrays: dict, meta: dict) -> Path:
    """Write ``arrays`` and the JSON ``meta`` to the ``.npz`` file ``path`` (atomically)."""
    path = Path(path)
    if "metadata" in arrays:
        raise ValueError("'metadata' is reserved for the JSON record")
    text = json.dumps(meta, allow_nan=True, default=_json_default)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        apply_umask(fd)
        with os.fdopen(fd, "wb") as f:
            np.savez(f, **arrays, metadata=np.array(text))
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def read_archive(path) -> tuple[dict, dict]:
    """Read an archive written by :func:`write_archive`: (arrays, metadata dict).

    Raises
    ------
    ValueError
        With its own message for each wrong input: a missing file, a folder, a text file,
        a single NumPy array (``.npy``), another binary file, an archive holding Python
        objects (never written by mmshbm and never loaded), a model file
        (:meth:`Model.save_npz`), an archive without the metadata record, a corrupt record.
    """
    path = Path(path)
    where = str(path)
    if not path.exists():
        raise ValueError(f"{where!r}: no such file")
    if path.is_dir():
        raise ValueError(f"{where!r} is a folder, not a results file (.npz of Branch.save or Study.save)")
    try:
        with open(path, "rb") as f:
            head = f.read(512)
    except OSError as err:
        raise ValueError(f"cannot read {where!r}: {err.strerror or err}") from None
    _check_zip_head(where, head)
    try:
        with np.load(path, allow_pickle=False) as f:
            names = list(f.files)
            data = {}
            for k in names:
                try:
                    data[k] = f[k]
                except ValueError as err:
                    if "allow_pickle" in str(err) or "pickle" in str(err):
                        raise ValueError(f"{where!r} holds Python objects (entry {k!r}), which mmshbm never "
                                         "writes and does not load: not an mmshbm results file") from None
                    raise
    except ValueError as err:
        if str(err).startswith(repr(where)):
            raise
        raise ValueError(f"{where!r} is a damaged .npz archive: {err}") from None
    except (OSError, EOFError, zipfile.BadZipFile, AttributeError) as err:
        raise ValueError(f"{where!r} is a damaged .npz archive: {err}") from None
    if "metadata" not in data:
        if {"M", "K"} <= set(data) or {"M_data", "K_data"} <= set(data):
            raise ValueError(f"{where!r} is a model file (Model.save_npz), not results: pass it as a model "
                             "(--model-file, Model.from_npz)")
        raise ValueError(f"{where!r} is an .npz archive but not an mmshbm results file (no metadata record; "
                         f"entries {sorted(data)[:6]})")
    try:
        meta = json.loads(str(data.pop("metadata")))
    except json.JSONDecodeError as err:
        raise ValueError(f"{where!r} has a corrupt metadata record: {err}") from None
    if not isinstance(meta, dict):
        raise ValueError(f"{where!r} has a corrupt metadata record")
    return data, meta


def _check_zip_head(where: str, head: bytes) -> None:
    """Refuse with a message of its own any file that is not a zip (.npz) archive."""
    if head.startswith(b"PK\x03\x04") or head.startswith(b"PK\x05\x06"):
        return
    if not head:
        raise ValueError(f"{where!r} is empty, not a results file")
    if head.startswith(b"\x93NUMPY"):
        raise ValueError(f"{where!r} is a single NumPy array (.npy), not an mmshbm results file (.npz of "
                         "Branch.save or Study.save)")
    try:
        head.decode("utf-8")
        text = True
    except UnicodeDecodeError as err:
        text = err.start > len(head) - 4  # a multi-byte character cut by the 512-byte read
    if text:
        raise ValueError(f"{where!r} is a text file (CSV?), not an mmshbm results file (.npz of Branch.save "
                         "or Study.save)")
    raise ValueError(f"{where!r} is not an .npz archive (not a zip file): not an mmshbm results file")


def _json_default(obj):
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"cannot store {type(obj).__name__} in the metadata")
