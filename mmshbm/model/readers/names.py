"""Which of a file's named matrices is the mass, the stiffness and the damping."""

from __future__ import annotations

import re

from ._build import ReadError

__all__ = ["roles_from_names"]

_PATTERNS = {"M": r"^(M|MASS)", "K": r"^(K|STIF)", "C": r"^(B|C|D(?!OF)|DAMP)"}
#: preferred names when a file holds several candidates (a-set, then g-set, then h-set)
_PREFERRED = {"M": ("MAA", "MGG", "MHH", "M2GG", "MAAX", "M", "MASS"),
              "K": ("KAA", "KGG", "KHH", "K2GG", "KAAX", "K", "STIFFNESS"),
              "C": ("BAA", "BGG", "BHH", "B2GG", "C", "D", "DAMPING")}


def roles_from_names(names, where: str, given: dict | None = None) -> dict:
    """Role ("M", "K", "C") -> the name of the matrix that plays it.

    ``given`` ({"M": "MAA", "K": "KAA"}) overrides the guess. A role with several
    candidates and none of the usual names is an error that lists them."""
    names = list(names)
    out = {}
    for role, name in (given or {}).items():
        if role not in _PATTERNS:
            raise ValueError(f"names: roles are 'M', 'K' and 'C', got {role!r}")
        if name not in names:
            raise ReadError(f"{where} has no matrix {name!r} (it has {names})")
        out[role] = name
    for role, pattern in _PATTERNS.items():
        if role in out:
            continue
        found = [n for n in names if re.match(pattern, n.strip().upper()) and n not in out.values()]
        if len(found) > 1:
            best = [n for p in _PREFERRED[role] for n in found if n.strip().upper() == p]
            if not best:
                raise ReadError(f"{where}: several matrices could be {role} ({found}); say which with "
                                f"names={{'{role}': ...}}")
            found = best[:1]
        if found:
            out[role] = found[0]
    return out
