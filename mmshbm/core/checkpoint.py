"""Checkpoint files of a running continuation: every converged point, written as it comes.

Format: JSON lines (UTF-8). The first line is a header (format name and version, and the
configuration that fixes the branch, as the caller gives it: this module stores and
compares it without knowing what its entries mean);
then one line per accepted point holding the full driver state
(:class:`~mmshbm.core.continuation.ContinuationState`: scaled unknowns ``u``, unit
``tangent``, the step ``ds`` that led to the point and the step ``ds_next`` the driver
tries next, the step count, Newton iterations and residual history, the monitored
record, the special points at that index, and the terminal status if the point ends
the branch); a last line ``{"end": status}`` when the run returns. Floats are written
with Python's shortest round-trip repr, so a point reads back bit for bit.

Safety. The file is created (and rewritten on resume) atomically: written to a
temporary file in the same directory, flushed to disk, then ``os.replace``-d. Points are
appended one ``write`` per line and flushed; a write interrupted by Ctrl-C is truncated
back to the last complete line, and a process killed mid-write leaves at most one
partial last line, which :func:`read_checkpoint` ignores. A damaged line anywhere else
is an error.

Resume. :func:`read_checkpoint` returns the header and the points;
:meth:`Checkpoint.state` turns them into a :class:`ContinuationState` from which
:func:`~mmshbm.core.continuation.continue_branch` goes on exactly as the uninterrupted run
would (a method's ``resume=path``).
"""

from __future__ import annotations

import json
import logging
import os
import tempfile
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._files import apply_umask
from .continuation import ContinuationState
from .special_points import SpecialPoint, special_from_json, special_to_json

__all__ = ["CheckpointWriter", "Checkpoint", "read_checkpoint", "model_fingerprint", "header_differences",
           "CHECKPOINT_FORMAT"]

log = logging.getLogger(__name__)

CHECKPOINT_FORMAT = "mmshbm.checkpoint"
CHECKPOINT_VERSION = 1


def model_fingerprint(model) -> str:
    """SHA-256 of a model's matrices, contacts, damping and amplitude DOF
    (:meth:`Model.fingerprint <mmshbm.model.model.Model.fingerprint>`)."""
    return model.fingerprint()


#: the types :func:`_plain` returns as they are, without looking further
_LEAVES = frozenset({float, int, str, bool, type(None)})


def _plain(x):
    """JSON-ready copy of ``x``: arrays to lists, NumPy scalars to Python numbers; a complex
    number or array (a forced response's Floquet multipliers) to ``{"complex": [re, im]}``,
    which :func:`_restore` reads back."""
    if type(x) in _LEAVES:  # the common case first
        return x
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_plain(v) for v in x]
    if isinstance(x, np.ndarray | complex | np.complexfloating) and np.iscomplexobj(x):
        return {"complex": [np.real(x).tolist(), np.imag(x).tolist()]}
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    return x


def _restore(x):
    """Inverse of :func:`_plain` for a record's value: ``{"complex": [re, im]}`` to a complex
    array (bit for bit), anything else as read."""
    if isinstance(x, dict) and set(x) == {"complex"}:
        re, im = (np.asarray(v, dtype=float) for v in x["complex"])
        out = np.empty(re.shape, dtype=complex)
        out.real, out.imag = re, im
        return out
    return x


def header_differences(stored: dict, current: dict, keys, *, names: Mapping[str, str] | None = None,
                       by_entry: Iterable[str] = (), fingerprints: Iterable[str] = (),
                       last: Iterable[str] = ()) -> list[str]:
    """The entries ``keys`` of a run's checkpoint header ``current`` that differ from a
    file's header ``stored``, one phrase each ("harmonics (H): file 5, now 8").

    The caller (the method that wrote the header) says what its entries mean; this module
    names no setting of its own.

    Parameters
    ----------
    stored, current : dict
        The file's header and the run's.
    keys : iterable of str
        The entries compared, in the order they are named.
    names : mapping, optional
        How a phrase names an entry (or an entry of a ``by_entry`` dict): the argument that
        sets it; an entry not in it is named by its key.
    by_entry : iterable of str
        Entries whose values are dicts of settings of their own, compared and named entry
        by entry (a solver's settings).
    fingerprints : iterable of str
        Entries whose values are hashes, named without their values (a model's fingerprint).
    last : iterable of str
        Entries that follow from the others (a number of unknowns): named after all the
        others, and only when nothing else differs.
    """
    names = dict(names or {})
    by_entry, fingerprints, last = set(by_entry), set(fingerprints), set(last)
    out, after = [], []
    for key in keys:
        old, new = stored.get(key), current.get(key)
        if old == new:
            continue
        if key in last:
            after.append(_difference(key, stored, current, names))
        elif key in fingerprints:
            out.append(names.get(key, key) + " (another fingerprint)")
        elif key in by_entry and isinstance(old, dict) and isinstance(new, dict):
            for name in sorted(set(old) | set(new), key=str):
                if old.get(name) != new.get(name):
                    out.append(_difference(name, old, new, names))
        else:
            out.append(_difference(key, stored, current, names))
    return out + after


def _difference(name: str, stored: dict, current: dict, names: Mapping[str, str]) -> str:
    return f"{names.get(name, name)}: file {_shown(stored, name)}, now {_shown(current, name)}"


def _shown(settings: dict, name: str) -> str:
    return repr(settings[name]) if name in settings else "not set"


def _line(obj) -> str:
    return json.dumps(_plain(obj), separators=(",", ":")) + "\n"


@dataclass
class Checkpoint:
    """A checkpoint file read back.

    Attributes
    ----------
    header : dict
        Format, version and the run's configuration.
    points : list of dict
        One entry per accepted point (see the module docstring).
    end : str or None
        The status the run returned with, or None if it was killed.
    path : Path
    """

    header: dict
    points: list = field(default_factory=list)
    end: str | None = None
    path: Path | None = None

    @property
    def terminal(self) -> str | None:
        """The status of a last point that ended the branch (a bound hit), else None."""
        return self.points[-1].get("status") if self.points else None

    def state(self) -> ContinuationState:
        """The driver state after the last point."""
        if not self.points:
            raise ValueError(f"checkpoint {str(self.path)!r} holds no converged point")
        p = self.points
        special = special_from_json([s for q in p for s in q.get("special", ())])
        return ContinuationState(
            u=[np.array(q["u"], dtype=float) for q in p],
            records=[{k: _restore(v) for k, v in q["record"].items()} for q in p],
            newton_iterations=[int(q["newton"]) for q in p],
            step_size=[float(q["ds"]) for q in p],
            residual_histories=[np.array(q["history"], dtype=float) for q in p],
            special_points=[SpecialPoint("start", 0)] + [s for s in special if s[0] != "start"],
            tangent=np.array(p[-1]["tangent"], dtype=float),
            ds=float(p[-1]["ds_next"]),
            steps=int(p[-1]["steps"]),
            previous_tangent=np.array(p[-2]["tangent"], dtype=float) if len(p) > 1 else None,
        )


def read_checkpoint(path) -> Checkpoint:
    """Read a checkpoint file written by :class:`CheckpointWriter`.

    A partial last line (a process killed mid-write) is ignored.

    Raises
    ------
    ValueError
        If the file is missing, unreadable, not a checkpoint, of another version, or
        damaged before its last line.
    """
    path = Path(path)
    try:
        text = path.read_bytes().decode("utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise ValueError(f"cannot read checkpoint file {str(path)!r}: {err}") from None
    lines = text.split("\n")
    complete = lines[:-1]  # whatever follows the last newline is a partial line
    if lines[-1]:
        log.warning("checkpoint %s: ignoring a partial last line (%d bytes)", path, len(lines[-1]))
    if not complete:
        raise ValueError(f"{str(path)!r} is not an mmshbm checkpoint (empty or no complete line)")
    try:
        header = json.loads(complete[0])
    except json.JSONDecodeError:
        header = None
    if not isinstance(header, dict) or header.get("format") != CHECKPOINT_FORMAT:
        raise ValueError(f"{str(path)!r} is not an mmshbm checkpoint (first line is not its header)")
    if header.get("version") != CHECKPOINT_VERSION:
        raise ValueError(f"checkpoint {str(path)!r} has format version {header.get('version')!r}; "
                         f"this mmshbm reads version {CHECKPOINT_VERSION}")
    ck = Checkpoint(header=header, path=path)
    for number, raw in enumerate(complete[1:], start=2):
        try:
            entry = json.loads(raw)
            if "end" in entry:
                ck.end = str(entry["end"])
                continue
            if entry["index"] != len(ck.points):
                raise ValueError(f"point index {entry['index']} where {len(ck.points)} was expected")
            for key in ("u", "tangent", "ds", "ds_next", "steps", "newton", "history", "record"):
                entry[key]  # noqa: B018 - a KeyError names a missing entry
        except (json.JSONDecodeError, KeyError, TypeError, ValueError) as err:
            raise ValueError(f"checkpoint {str(path)!r} is damaged at line {number}: {err!r}") from None
        ck.points.append(entry)
    return ck


class CheckpointWriter:
    """Append-only writer of a checkpoint file (see the module docstring).

    Parameters
    ----------
    path : str or Path
        The file; its directory must exist. An existing file is replaced atomically.
    header : dict
        The run's configuration (JSON-serialisable); format and version are added.
    points : list of dict, optional
        Points already computed (on resume), written before any new point.
    """

    def __init__(self, path, header: dict, points=()):
        self.path = Path(path)
        directory = self.path.parent
        if not directory.is_dir():
            raise ValueError(f"checkpoint directory {str(directory)!r} does not exist")
        if self.path.is_dir():
            raise ValueError(f"checkpoint {str(self.path)!r} is a directory; give a file name")
        self.header = {"format": CHECKPOINT_FORMAT, "version": CHECKPOINT_VERSION, **header}
        body = _line(self.header) + "".join(_line(p) for p in points)
        fd, tmp = tempfile.mkstemp(prefix=f".{self.path.name}.", suffix=".tmp", dir=directory)
        try:
            apply_umask(fd)
            with os.fdopen(fd, "w", encoding="utf-8") as f:
                f.write(body)
                f.flush()
                os.fsync(f.fileno())
            os.replace(tmp, self.path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        self._file = open(self.path, "a", encoding="utf-8")  # noqa: SIM115 - closed by close()
        self.n_points = len(points)

    def _append(self, obj) -> None:
        text = _line(obj)
        f = self._file
        offset = f.tell()
        try:
            f.write(text)
            f.flush()
        except BaseException:  # Ctrl-C mid-write: leave only complete lines behind
            f.truncate(offset)
            f.flush()
            raise

    def point(self, event: dict) -> None:
        """Append one accepted point (the dict ``continue_branch`` gives ``on_point``)."""
        entry = {k: event[k] for k in ("index", "u", "tangent", "ds", "ds_next", "steps", "newton",
                                       "history", "record", "status")}
        entry["special"] = special_to_json(event["special"])
        self._append(entry)
        self.n_points += 1

    def end(self, status: str) -> None:
        """Append the final status."""
        self._append({"end": status})

    def close(self) -> None:
        """Flush to disk and close."""
        if not self._file.closed:
            self._file.flush()
            try:
                os.fsync(self._file.fileno())
            except OSError:  # pragma: no cover - e.g. a pipe or special file
                pass
            self._file.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
