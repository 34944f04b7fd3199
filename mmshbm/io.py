"""Reading any mmshbm results file: a saved :class:`~mmshbm.results.branch.Branch`, a
:class:`~mmshbm.analysis.studies.Study` or a :class:`~mmshbm.results.response.FrequencyResponse`,
whichever the file holds."""

from __future__ import annotations

from .analysis.studies import STUDY_FORMAT, Study
from .results.branch import BRANCH_FORMAT, Branch, read_archive
from .results.response import RESPONSE_FORMAT, FrequencyResponse

__all__ = ["load"]


def load(path, attach_solver: bool = False):
    """Read a saved :class:`Branch`, :class:`Study` or :class:`FrequencyResponse`, whichever the
    file holds.

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
    if meta.get("format") == RESPONSE_FORMAT:
        response = FrequencyResponse.load(path)
        if attach_solver:
            response.attach_solver()
        return response
    raise ValueError(f"{str(path)!r} holds neither a Branch nor a Study (format {meta.get('format')!r})")
