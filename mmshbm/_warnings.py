"""The package's warning categories (filter them with :mod:`warnings` as usual).

- :class:`MmshbmWarning`: base class of all of them.
- :class:`BranchWarning`: a result that could mislead: the branch left the family of its
  starting mode, its contact force changes sign, the contact DOF passes the stop by more
  than a tolerance, it ended short of its bounds.
- :class:`ModelWarning`: what a model conversion did (mass removed, frequencies shifted).
"""

from __future__ import annotations

__all__ = ["MmshbmWarning", "BranchWarning", "ModelWarning"]


class MmshbmWarning(UserWarning):
    """Base class of mmshbm's warnings."""


class BranchWarning(MmshbmWarning):
    """A computed branch (or response) may not be what it seems; the message says why.

    ``kind`` is the kind of the :class:`~mmshbm.results.findings.Finding` it reports
    (``"left_family"``, ``"penetration"``, ``"incomplete"``, ...), or None for a warning that
    reports no finding: code that sorts warnings reads it, never the message.
    """

    def __init__(self, message: str = "", kind: str | None = None):
        super().__init__(message)
        self.kind = kind


class ModelWarning(MmshbmWarning):
    """A model conversion changed the structure; the message says by how much."""
