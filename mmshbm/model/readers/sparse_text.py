"""Matrix Market (``.mtx``, ``%%MatrixMarket`` header) and Harwell–Boeing (``.rb``,
``.rsa``, ``.hb``) files: one matrix a file, no DOF table (plain indices). ANSYS
``*EXPORT`` writes both (``MMF`` / ``HBMAT``), as do many codes; a symmetric file holding
one triangle is completed.
"""

from __future__ import annotations

from pathlib import Path

from ._build import Part, ReadError

__all__ = ["read_matrix_market", "read_harwell_boeing"]


def read_matrix_market(path: Path, role: str) -> Part:
    import scipy.io

    try:
        A = scipy.io.mmread(str(path))
    except (OSError, ValueError, TypeError) as err:
        raise ReadError(f"cannot read {str(path)!r} as Matrix Market: {err}") from None
    if not hasattr(A, "tocsr"):
        from scipy import sparse

        A = sparse.csr_matrix(A)
    if A.dtype.kind == "c":
        raise ReadError(f"{str(path)!r}: a complex matrix; mass and stiffness are real")
    return Part(str(path), {role: A.tocsr()})


def read_harwell_boeing(path: Path, role: str) -> Part:
    """Real assembled matrices, unsymmetric (RUA) or symmetric (RSA) storage: an RSA file's
    columns hold one triangle, which is read as an RUA file of that triangle and completed
    later (scipy reads RUA only)."""
    import io

    import scipy.io

    try:
        lines = Path(path).read_text(encoding="ascii", errors="replace").splitlines(keepends=True)
        if len(lines) > 2 and lines[2][:3].upper() == "RSA":
            lines[2] = "RUA" + lines[2][3:]
        A = scipy.io.hb_read(io.StringIO("".join(lines)))
    except (OSError, ValueError, TypeError) as err:
        raise ReadError(f"cannot read {str(path)!r} as Harwell-Boeing: {err}") from None
    return Part(str(path), {role: A.tocsr()})
