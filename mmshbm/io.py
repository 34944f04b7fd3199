"""Reading any mmshbm results file: a saved :class:`~mmshbm.results.branch.Branch` or a
:class:`~mmshbm.analysis.studies.Study`, whichever the file holds."""

from __future__ import annotations

from .analysis.studies import STUDY_FORMAT, Study
from .results.branch import BRANCH_FORMAT, Branch, read_archive

__all__ = ["load"]


def load(path, attach_solver: bool = False):
    """Read a saved :class:`Branch` or :class:`Study`, whichever the file holds.

    Raises
    ------
    ValueError
        If the file is unreadable or holds neither.
    """
    _, meta = read_archive(path)
    if meta.get("format") == BRANCH_FORMAT:
        return Branch.load(path, attach_solver=attach_solver)
    if meta.get("format") == STUDY_FORMAT:
        return Study.load(path, attach_solver=attach_solver)
    raise ValueError(f"{str(path)!r} holds neither a Branch nor a Study (format {meta.get('format')!r})")
