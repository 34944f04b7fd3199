"""NASTRAN OUTPUT4 (OP4) files, ASCII and binary, dense and sparse (also BIGMAT).

Written by ``OUTPUT4 KAA,MAA,,,//-1/11/1 $`` (or ``/2`` for formatted text) in the DMAP of a
SOL 103 run, or by pyNastran. Per matrix a header ``NCOL, NROW, NFORM, NTYPE, NAME``
(NROW < 0: BIGMAT sparse layout), then per column ``ICOL, IROW, NW`` and its values from
row IROW on (dense), or with IROW = 0 a sequence of strings, each with a header
``IS = IROW + 65536 (L + 1)`` (L words follow) or, for BIGMAT, ``L, IROW`` (L − 1 words).
A column ``NCOL + 1`` ends the matrix. Text files write the integers as I8 and the values
in the Fortran format the header names (e.g. ``1P,3E23.16``); binary files are Fortran
unformatted records (4-byte markers, either byte order), double precision taking two words
a value. Complex matrices (NTYPE 3, 4) are refused. OP4 files hold no DOF table: the DOFs
are plain indices.
"""

from __future__ import annotations

import re
import struct
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ._build import Part, ReadError
from .names import roles_from_names

__all__ = ["read_op4", "read_matrices", "is_binary_op4"]


def is_binary_op4(head: bytes) -> bool:
    """True when the file starts with a 24-byte Fortran record (an OP4 header)."""
    return len(head) >= 4 and (head[:4] == struct.pack("<i", 24) or head[:4] == struct.pack(">i", 24))


def read_op4(path: Path, names: dict | None = None) -> Part:
    """The mass, stiffness (and damping: B...) matrices of an OP4 file."""
    where = str(path)
    mats = read_matrices(path)
    roles = roles_from_names(mats, where, names)
    if not roles:
        raise ReadError(f"{where}: none of its matrices {list(mats)} is named like a mass (M...) or a "
                        "stiffness (K...); say which with names={'M': ..., 'K': ...}")
    return Part(where, {role: mats[name] for role, name in roles.items()})


def read_matrices(path: Path) -> dict:
    """Every matrix of an OP4 file: name -> scipy CSR matrix."""
    path = Path(path)
    with open(path, "rb") as f:
        head = f.read(4)
    if is_binary_op4(head):
        return _read_binary(path)
    return _read_text(path)


# ---------------------------------------------------------------------- text
_HEADER = re.compile(r"^\s*(-?\d+)\s+(-?\d+)\s+(-?\d+)\s+(-?\d+)\s*([A-Za-z][^\s]*)\s*(.*)$")


def _read_text(path: Path) -> dict:
    where = str(path)
    lines = Path(path).read_text(encoding="ascii", errors="replace").splitlines()
    out, k = {}, 0
    while k < len(lines):
        if not lines[k].strip():
            k += 1
            continue
        m = _HEADER.match(lines[k][:32] + " " + lines[k][32:])
        if not m:
            raise ReadError(f"{where}, line {k + 1}: expected a matrix header 'NCOL NROW NFORM NTYPE NAME "
                            f"FORMAT', got {lines[k][:60]!r}")
        ncol, nrow, _form, ntype = (int(m.group(i)) for i in range(1, 5))
        name, fmt = m.group(5).strip(), m.group(6)
        _check_type(ntype, name, where)
        width = re.search(r"E(\d+)\.\d+", fmt, re.I)
        width = int(width.group(1)) if width else None
        k, A = _text_matrix(lines, k + 1, ncol, abs(nrow), nrow < 0, width, name, where)
        out[name] = A
    if not out:
        raise ReadError(f"{where}: no OP4 matrix")
    return out


def _ints(line: str) -> list | None:
    parts = line.split()
    if not parts or any(not re.fullmatch(r"-?\d+", p) for p in parts):
        return None
    return [int(p) for p in parts]


def _values(line: str, width: int | None) -> list:
    s = line.rstrip()
    if width:
        fields = [s[i:i + width] for i in range(0, len(s), width)]
    else:
        fields = s.split()
    return [float(x.replace("D", "E").replace("d", "e")) for x in fields if x.strip()]


def _text_matrix(lines, k, ncol, nrow, bigmat, width, name, where):
    rows, cols, vals = [], [], []
    icol = irow = 0
    closed = False  # the column NCOL + 1 (the end of the matrix) has been read
    while k < len(lines):
        line = lines[k]
        ints = _ints(line)
        if not line.strip():
            pass
        elif ints is None:
            if closed and _HEADER.match(line[:32] + " " + line[32:]):
                break  # the next matrix
            try:
                values = _values(line, width)
            except ValueError:
                raise ReadError(f"{where}, line {k + 1} (matrix {name}): not a line of values: "
                                f"{line[:60]!r}") from None
            if not closed:
                if icol < 1 or irow < 1:
                    raise ReadError(f"{where}, line {k + 1} (matrix {name}): values before a column or "
                                    "string header")
                rows.extend(range(irow - 1, irow - 1 + len(values)))
                cols.extend([icol - 1] * len(values))
                vals.extend(values)
                irow += len(values)
        elif closed:
            raise ReadError(f"{where}, line {k + 1}: integers {ints} after the end of matrix {name}")
        elif len(ints) == 3:
            icol, irow, _nw = ints
            closed = icol > ncol
        elif len(ints) == 1 and not bigmat:
            IS = ints[0]
            irow = IS - 65536 * (IS // 65536)
        elif len(ints) == 2 and bigmat:
            irow = ints[1]
        else:
            raise ReadError(f"{where}, line {k + 1} (matrix {name}): unexpected integers {ints}")
        k += 1
    if not closed:
        raise ReadError(f"{where}: matrix {name} ends before its closing column {ncol + 1}")
    return k, _assemble(rows, cols, vals, nrow, ncol, name, where)


def _assemble(rows, cols, vals, nrow, ncol, name, where):
    rows, cols = np.asarray(rows, np.int64), np.asarray(cols, np.int64)
    if len(rows) and (rows.max() >= nrow or rows.min() < 0):
        raise ReadError(f"{where}: matrix {name} has an entry in row {int(rows.max()) + 1} of {nrow}")
    return sp.coo_matrix((np.asarray(vals, float), (rows, cols)), shape=(nrow, ncol)).tocsr()


def _check_type(ntype, name, where):
    if ntype in (3, 4):
        raise ReadError(f"{where}: matrix {name} is complex (NTYPE {ntype}); mass and stiffness are real")
    if ntype not in (1, 2):
        raise ReadError(f"{where}: matrix {name} has NTYPE {ntype}; expected 1 (real single) or 2 (real "
                        f"double)")


# ---------------------------------------------------------------------- binary
def _records(data: bytes, where: str):
    end = "<" if data[:4] == struct.pack("<i", 24) else ">"
    k = 0
    while k < len(data):
        if k + 4 > len(data):
            raise ReadError(f"{where}: truncated record marker at byte {k}")
        (n,) = struct.unpack(end + "i", data[k:k + 4])
        body = data[k + 4:k + 4 + n]
        if len(body) != n or data[k + 4 + n:k + 8 + n] != data[k:k + 4]:
            raise ReadError(f"{where}: broken Fortran record at byte {k} (length {n})")
        yield end, body
        k += 8 + n


def _read_binary(path: Path) -> dict:
    where = str(path)
    records = _records(Path(path).read_bytes(), where)
    out = {}
    for end, body in records:
        if len(body) != 24:
            raise ReadError(f"{where}: expected a 24-byte matrix header record, got {len(body)} bytes")
        ncol, nrow, _form, ntype = struct.unpack(end + "4i", body[:16])
        name = body[16:24].decode("ascii", "replace").strip()
        _check_type(ntype, name, where)
        bigmat, nrow = nrow < 0, abs(nrow)
        word = 2 if ntype == 2 else 1
        fmt = "d" if ntype == 2 else "f"
        rows, cols, vals = [], [], []
        for _end, rec in records:
            icol, irow, _nw = struct.unpack(end + "3i", rec[:12])
            if icol > ncol:
                break
            payload = rec[12:]
            if irow > 0:  # dense: one string from irow
                values = struct.unpack(f"{end}{len(payload) // (4 * word)}{fmt}", payload)
                strings = [(irow, values)]
            else:
                strings = _binary_strings(payload, end, bigmat, word, fmt, name, where)
            for r0, values in strings:
                rows.extend(range(r0 - 1, r0 - 1 + len(values)))
                cols.extend([icol - 1] * len(values))
                vals.extend(values)
        else:
            raise ReadError(f"{where}: matrix {name} ends before its closing column {ncol + 1}")
        out[name] = _assemble(rows, cols, vals, nrow, ncol, name, where)
    if not out:
        raise ReadError(f"{where}: no OP4 matrix")
    return out


def _binary_strings(payload, end, bigmat, word, fmt, name, where):
    strings, k = [], 0
    while k < len(payload):
        if bigmat:
            L, irow = struct.unpack(end + "2i", payload[k:k + 8])
            nwords, k = L - 1, k + 8
        else:
            (IS,) = struct.unpack(end + "i", payload[k:k + 4])
            nwords = IS // 65536 - 1
            irow, k = IS - 65536 * (nwords + 1), k + 4
        if nwords < 0 or k + 4 * nwords > len(payload) or nwords % word:
            raise ReadError(f"{where}: matrix {name}: a string header promises {nwords} words, the record "
                            f"holds {(len(payload) - k) // 4}")
        strings.append((irow, struct.unpack(f"{end}{nwords // word}{fmt}", payload[k:k + 4 * nwords])))
        k += 4 * nwords
    return strings
