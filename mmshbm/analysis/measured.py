"""Measured backbone curves: loading and checking a CSV file.

The file is plain CSV with one header line naming the columns ``frequency`` (Hz) and
``amplitude`` (m), and optionally ``contact_force`` (N). Units may be written into the
name (``frequency_hz``, ``amplitude [m]``, ``contact_force (N)``) but must then be
these; ``amplitude_mm`` is refused rather than silently misread. Lines starting with
``#`` and blank lines are skipped, other columns are ignored, and ``,``, ``;`` or tab
separate fields. A branch's :meth:`~mmshbm.results.branch.Branch.to_csv` file is also a valid
measured file.
"""

from __future__ import annotations

import csv
import logging
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["MeasuredBackbone", "load_measured"]

log = logging.getLogger(__name__)

#: column name -> unit it must be in (lower case)
_COLUMNS = {"frequency": "hz", "amplitude": "m", "contact_force": "n"}
#: other accepted names
_ALIASES = {"contact_force_max": "contact_force"}
#: suffixes read as units (others make the whole text a column name)
_UNITS = {"hz", "khz", "m", "mm", "um", "cm", "n", "kn", "rad", "s", "ms", "g"}
_NAME = re.compile(r"^\s*([a-z][a-z_ ]*?)\s*(?:[_ ]([a-z]+)|\[\s*([a-z]+)\s*\]|\(\s*([a-z]+)\s*\))?\s*$")


@dataclass(frozen=True, eq=False)
class MeasuredBackbone:
    """A measured backbone curve.

    Attributes
    ----------
    frequency : ndarray, shape (n,)
        Frequency (Hz), > 0.
    amplitude : ndarray, shape (n,)
        Tip amplitude (m), >= 0.
    contact_force : ndarray, shape (n,), or None
        Peak contact force (N); NaN where a row leaves it empty; None without the column.
    source : str
        Where it came from (file name).
    """

    frequency: np.ndarray
    amplitude: np.ndarray
    contact_force: np.ndarray | None = None
    source: str = ""

    def __len__(self) -> int:
        return len(self.frequency)

    @classmethod
    def from_arrays(cls, frequency, amplitude, contact_force=None, source: str = "") -> MeasuredBackbone:
        """Build from arrays, with the checks of :func:`load_measured`."""
        f = np.asarray(frequency, dtype=float).ravel()
        a = np.asarray(amplitude, dtype=float).ravel()
        if len(f) == 0 or len(f) != len(a):
            raise ValueError(f"frequency and amplitude must be non-empty and of equal length, got {len(f)} "
                             f"and {len(a)}")
        if not (np.all(np.isfinite(f)) and np.all(f > 0)):
            raise ValueError("measured frequencies must be finite and > 0 Hz")
        if not (np.all(np.isfinite(a)) and np.all(a >= 0)):
            raise ValueError("measured amplitudes must be finite and >= 0 m")
        lam = None
        if contact_force is not None:
            lam = np.asarray(contact_force, dtype=float).ravel()
            if len(lam) != len(f):
                raise ValueError(f"contact_force has {len(lam)} values for {len(f)} points")
            if np.any(np.isinf(lam)):
                raise ValueError("measured contact forces must be finite (or empty)")
        return cls(f, a, lam, source)


def load_measured(path) -> MeasuredBackbone:
    """Read a measured backbone from a CSV file.

    Parameters
    ----------
    path : str or Path
        CSV with a header line: ``frequency`` (Hz), ``amplitude`` (m), optionally
        ``contact_force`` (N).

    Returns
    -------
    MeasuredBackbone

    Raises
    ------
    ValueError
        Naming the file, and the line or column, for: a missing or unreadable file, no
        header or no data, a missing required column, a column in other units, a
        repeated column, a row with the wrong number of fields, a value that is not a
        number, non-finite or out of range.
    """
    path = Path(path)
    where = str(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise ValueError(f"measured file {where!r} is not a text (CSV) file: it has binary content") from None
    except OSError as err:
        raise ValueError(f"cannot read measured file {where!r}: {err.strerror or err}") from None
    lines = [(n, line) for n, line in enumerate(text.splitlines(), start=1)
             if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise ValueError(f"measured file {where!r} is empty")
    head_no, head = lines[0]
    delimiter = next((d for d in (",", ";", "\t") if d in head), ",")
    rows = list(csv.reader([line for _, line in lines], delimiter=delimiter))
    columns = _columns(rows[0], where, head_no)
    missing = [c for c in ("frequency", "amplitude") if c not in columns]
    if missing:
        raise ValueError(f"measured file {where!r}: header (line {head_no}) lacks the column(s) {missing}; "
                         f"it has {[c.strip() for c in rows[0]]}")
    if len(rows) == 1:
        raise ValueError(f"measured file {where!r} has a header but no data rows")
    values = {c: [] for c in columns}
    for (n, _), row in zip(lines[1:], rows[1:], strict=True):
        if len(row) != len(rows[0]):
            raise ValueError(f"measured file {where!r}, line {n}: {len(row)} fields, the header has "
                             f"{len(rows[0])}")
        for name, j in columns.items():
            cell = row[j].strip()
            if cell == "" and name == "contact_force":
                values[name].append(float("nan"))
                continue
            try:
                x = float(cell)
            except ValueError:
                raise ValueError(f"measured file {where!r}, line {n}: {name} {cell!r} is not a number") \
                    from None
            if not np.isfinite(x):
                raise ValueError(f"measured file {where!r}, line {n}: {name} is {cell!r}, not finite")
            if name == "frequency" and x <= 0:
                raise ValueError(f"measured file {where!r}, line {n}: frequency must be > 0 Hz, got {x:g}")
            if name == "amplitude" and x < 0:
                raise ValueError(f"measured file {where!r}, line {n}: amplitude must be >= 0 m, got {x:g}")
            values[name].append(x)
    return MeasuredBackbone.from_arrays(values["frequency"], values["amplitude"], values.get("contact_force"),
                                        source=path.name)


def _columns(header: list[str], where: str, line: int) -> dict[str, int]:
    """Map the recognised column names to their positions, checking units."""
    found: dict[str, int] = {}
    for j, raw in enumerate(header):
        m = _NAME.match(raw.lower())
        if not m:
            log.debug("ignoring column %r of %s", raw, where)
            continue
        name = m.group(1).strip().replace(" ", "_")
        unit = next((g for g in m.group(2, 3, 4) if g), None)
        if unit is not None and unit not in _UNITS and m.group(2):
            name, unit = f"{name}_{unit}", None  # "frequency_std": a name, not a unit
        name = _ALIASES.get(name, name)
        if name not in _COLUMNS:
            log.debug("ignoring column %r of %s", raw, where)
            continue
        if unit is not None and unit != _COLUMNS[name]:
            raise ValueError(f"measured file {where!r}, line {line}: column {raw.strip()!r} is in {unit!r}; "
                             f"{name} must be in {_COLUMNS[name]!r} (SI)")
        if name in found:
            raise ValueError(f"measured file {where!r}, line {line}: column {name!r} appears twice")
        found[name] = j
    return found
