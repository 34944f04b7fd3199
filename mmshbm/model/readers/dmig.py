"""NASTRAN DMIG bulk-data cards (the punch file of ``EXTSEOUT(... DMIGPCH)`` or of a
``PARAM,EXTOUT,DMIGPCH`` run, or hand-written bulk data).

A matrix is a header card ``DMIG, NAME, 0, IFO, TIN, TOUT, POLAR, , NCOL`` (IFO 6:
symmetric, one triangle given; TIN 1 or 2: real) followed by one card per column
``DMIG, NAME, GJ, CJ, , G1, C1, A1, B1, G2, C2, A2, B2, ...``: the column's DOF (grid or
scalar point GJ, component CJ; 0 for a scalar point) and its terms (G, C, value; B only
for complex matrices, refused here). Small-field (8-character), large-field (``DMIG*``
and ``*`` continuations, 16-character) and free-field (comma) cards are read; values in
NASTRAN's short forms (``1.5-3``, ``2.D+04``) too. The DOF table is the (grid,
component) of every term.
"""

from __future__ import annotations

import re
from pathlib import Path

from ._build import ReadError, from_labelled
from .names import roles_from_names

__all__ = ["read_dmig", "looks_like", "nastran_real"]


def looks_like(head: str) -> bool:
    return bool(re.search(r"^DMIG\*?[\s,]", head, re.M | re.I))


def nastran_real(text: str) -> float:
    """A NASTRAN real field: ``1.0``, ``1.0E+3``, ``1.0D+3``, ``1.+3``, ``-2.5-4``."""
    s = text.strip().upper().replace("D", "E")
    m = re.fullmatch(r"([+-]?(?:\d+\.?\d*|\.\d+))([+-]\d+)", s)
    if m:
        s = f"{m.group(1)}E{m.group(2)}"
    return float(s)


def _cards(lines, where):
    """[(first line number, [fields 2.. of the card])] for every DMIG card."""
    cards = []
    for number, raw in enumerate(lines, 1):
        line = raw.rstrip("\n")
        if not line.strip() or line.lstrip().startswith("$"):
            continue
        if "," in line:
            head, *fields = [f.strip() for f in line.split(",")]
            fields = (fields + [""] * 8)[:8]
        elif line[:8].strip().endswith("*") or line.startswith("*"):
            head = line[:8].strip()
            fields = [line[8 + 16 * i:24 + 16 * i].strip() for i in range(4)]
        else:
            head = line[:8].strip()
            fields = [line[8 + 8 * i:16 + 8 * i].strip() for i in range(8)]
        name = head.upper().rstrip("*")
        if name in ("DMIG",):
            cards.append((number, fields))
        elif head == "" or head.startswith("+") or head.startswith("*"):
            if cards and cards[-1] is not None:
                cards[-1][1].extend(fields)
        else:
            cards.append(None)  # another card: its continuations are not ours
    return [c for c in cards if c is not None]


def read_dmig(path: Path, names: dict | None = None):
    """The mass, stiffness (and damping) matrices of the DMIG cards in a bulk-data file."""
    where = str(path)
    lines = Path(path).read_text(encoding="ascii", errors="replace").splitlines()
    matrices = {}
    for number, fields in _cards(lines, where):
        name = fields[0]
        try:
            if fields[1] == "0":  # header card
                ifo, tin = int(fields[2]), int(fields[3] or 0)
                if tin not in (1, 2):
                    raise ReadError(f"{where}, line {number}: DMIG {name} has TIN {tin}: only real matrices "
                                    "(1, 2) are mass or stiffness")
                matrices[name] = {"ifo": ifo, "rows": [], "cols": [], "values": []}
                continue
            if name not in matrices:
                raise ReadError(f"{where}, line {number}: DMIG {name} column before its header card")
            col = (int(fields[1]), int(fields[2] or 0))
            terms = fields[4:]
            m = matrices[name]
            for k in range(0, len(terms) - 3, 4):
                g, c, a, b = terms[k:k + 4]
                if not g:
                    continue
                if b:
                    raise ReadError(f"{where}, line {number}: DMIG {name} has an imaginary part: not real")
                m["rows"].append((int(g), int(c or 0)))
                m["cols"].append(col)
                m["values"].append(nastran_real(a))
        except (ValueError, IndexError) as err:
            if isinstance(err, ReadError):
                raise
            raise ReadError(f"{where}, line {number}: DMIG {name}: malformed field ({err})") from None
    if not matrices:
        raise ReadError(f"{where}: no DMIG cards")
    roles = roles_from_names(matrices, where, names)
    if not roles:
        raise ReadError(f"{where}: none of its DMIG matrices {list(matrices)} is named like a mass (M...) or "
                        "a stiffness (K...); say which with names={'M': ..., 'K': ...}")
    return from_labelled(where, {role: (matrices[n]["rows"], matrices[n]["cols"], matrices[n]["values"])
                                 for role, n in roles.items()})
