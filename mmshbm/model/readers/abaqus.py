"""Abaqus matrix files.

``*MATRIX GENERATE, STIFFNESS, MASS`` with ``*MATRIX OUTPUT, STIFFNESS, MASS,
FORMAT=MATRIX INPUT`` writes ``<job>_STIF<step>.mtx`` and ``<job>_MASS<step>.mtx``: one
entry a line, ``row node, row DOF, column node, column DOF, value`` (comma separated),
the lower triangle, the upper one or the full matrix (the ``*MATRIX INPUT`` rules). The
role comes from the file name (``STIF``, ``MASS``, ``DMPV`` for viscous damping).

``*SUBSTRUCTURE MATRIX OUTPUT, OUTPUT FILE=USER DEFINED, FILE NAME=...`` writes a
``*USER ELEMENT, NODES=n, ..., LINEAR`` block: data lines give the active DOFs (the first
line for the first node, later lines "node position, DOFs" where they change), then
``*MATRIX, TYPE=STIFFNESS`` and ``*MATRIX, TYPE=MASS``, each with the upper triangle stored
by columns ((1,1), (1,2), (2,2), (1,3), ...), four entries a line. Node ids come from an
``*ELEMENT`` line of the user element's type in the same file when there is one, else
they are the element's node positions 1..n.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ._build import Part, ReadError, from_labelled

__all__ = ["read_matrix_input", "read_user_element", "looks_like", "ROLE_BY_NAME"]

#: file-name marker -> role
ROLE_BY_NAME = {"STIF": "K", "MASS": "M", "DMPV": "C"}


def looks_like(head: str) -> str | None:
    """"matrix-input", "user-element" or None, from a file's first lines."""
    if re.search(r"^\s*\*\s*USER\s+ELEMENT", head, re.I | re.M):
        return "user-element"
    for line in head.splitlines():
        s = line.strip()
        if not s or s.startswith("**"):
            continue
        return "matrix-input" if len(s.split(",")) == 5 and not s.startswith("%") else None
    return None


def role_of(path: Path) -> str | None:
    stem = path.stem.upper()
    for marker, role in ROLE_BY_NAME.items():
        if re.search(rf"(^|[_\-.]){marker}\d*$", stem) or f"_{marker}" in stem:
            return role
    return None


def read_matrix_input(path: Path, role: str) -> Part:
    """One ``FORMAT=MATRIX INPUT`` file as the matrix ``role``."""
    where = str(path)
    rows, cols, values = [], [], []
    with open(path, encoding="ascii", errors="replace") as f:
        for number, line in enumerate(f, 1):
            s = line.strip()
            if not s or s.startswith("**"):
                continue
            if s.startswith("*"):
                raise ReadError(f"{where}, line {number}: a keyword line {s[:40]!r} in a matrix-input file "
                                "(entries only: row node, row DOF, column node, column DOF, value)")
            fields = s.rstrip(",").split(",")
            if len(fields) != 5:
                raise ReadError(f"{where}, line {number}: expected 'row node, row DOF, column node, "
                                f"column DOF, "
                                f"value', got {s[:60]!r}")
            try:
                a, b, c, d = (int(x) for x in fields[:4])
                v = float(fields[4].replace("D", "E").replace("d", "e"))
            except ValueError:
                raise ReadError(f"{where}, line {number}: not four integers and a number: "
                                f"{s[:60]!r}") from None
            rows.append((a, b))
            cols.append((c, d))
            values.append(v)
    if not values:
        raise ReadError(f"{where}: no matrix entries")
    return from_labelled(where, {role: (rows, cols, values)})


def read_user_element(path: Path) -> Part:
    """A ``*USER ELEMENT, LINEAR`` block (substructure output) with its ``*MATRIX`` data."""
    where = str(path)
    text = Path(path).read_text(encoding="ascii", errors="replace")
    blocks = _keyword_blocks(text)
    head = next((b for b in blocks if b[0] == "USER ELEMENT"), None)
    if head is None:
        raise ReadError(f"{where}: no *USER ELEMENT keyword")
    params, lines = head[1], head[2]
    try:
        n_nodes = int(params.get("NODES", ""))
    except ValueError:
        raise ReadError(f"{where}: *USER ELEMENT needs NODES=<number of nodes>, got {params}") from None
    dof_lists = _active_dofs(lines, n_nodes, where)
    labels = np.array([(node, c) for node in range(1, n_nodes + 1) for c in dof_lists[node - 1]])
    element = next((b for b in blocks if b[0] == "ELEMENT" and
                    b[1].get("TYPE", "").upper() == params.get("TYPE", "").upper()), None)
    if element is not None and element[2]:
        ids = [int(x) for x in ",".join(element[2]).replace(" ", "").strip(",").split(",")[1:] if x]
        if len(ids) != n_nodes:
            raise ReadError(f"{where}: *ELEMENT of type {params.get('TYPE')} lists {len(ids)} nodes, "
                            f"the user "
                            f"element has NODES={n_nodes}")
        labels[:, 0] = np.array(ids)[labels[:, 0] - 1]
    n = len(labels)
    entries = {}
    for name, bparams, blines in blocks:
        if name != "MATRIX":
            continue
        kind = bparams.get("TYPE", "").upper()
        role = {"STIFFNESS": "K", "MASS": "M"}.get(kind)
        if role is None:
            raise ReadError(f"{where}: *MATRIX, TYPE={kind or '?'}: expected TYPE=STIFFNESS or TYPE=MASS")
        try:
            values = np.array([float(x.replace("D", "E")) for line in blines for x in line.split(",")
                               if x.strip()])
        except ValueError as err:
            raise ReadError(f"{where}: *MATRIX, TYPE={kind}: {err}") from None
        if len(values) != n * (n + 1) // 2:
            raise ReadError(f"{where}: *MATRIX, TYPE={kind} has {len(values)} entries; {n} DOFs need "
                            f"{n * (n + 1) // 2} (one triangle)")
        j = np.repeat(np.arange(n), np.arange(1, n + 1))   # column of each packed entry
        i = np.arange(len(values)) - j * (j + 1) // 2      # its row, 0..j
        entries[role] = (labels[i], labels[j], values)
    if not entries:
        raise ReadError(f"{where}: no *MATRIX, TYPE=STIFFNESS or TYPE=MASS block")
    part = from_labelled(where, entries)
    return part


def _active_dofs(lines: list, n_nodes: int, where: str) -> list:
    if not lines:
        raise ReadError(f"{where}: *USER ELEMENT has no data line with the active DOFs")
    current, changes = None, {}
    for k, line in enumerate(lines):
        try:
            values = [int(x) for x in line.split(",") if x.strip()]
        except ValueError:
            raise ReadError(f"{where}: *USER ELEMENT data line {line!r} is not a list of integers") from None
        if k == 0:
            current = values
        else:
            changes[values[0]] = values[1:]
    out = []
    for node in range(1, n_nodes + 1):
        current = changes.get(node, current)
        out.append(list(current))
    return out


def _keyword_blocks(text: str) -> list:
    """[(KEYWORD, {PARAM: value}, [data lines])] of an Abaqus input text."""
    blocks = []
    for raw in text.splitlines():
        s = raw.strip()
        if not s or s.startswith("**"):
            continue
        if s.startswith("*"):
            name, *rest = s[1:].split(",")
            params = {}
            for p in rest:
                key, _, value = p.partition("=")
                params[key.strip().upper()] = value.strip()
            blocks.append((" ".join(name.upper().split()), params, []))
        elif blocks:
            blocks[-1][2].append(s)
    return blocks
