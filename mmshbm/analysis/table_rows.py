"""One run's row of a study's frequency table (:meth:`mmshbm.analysis.studies.Study.table`),
computed where the run was made.

A row solves the backbone at the table's amplitudes on the branch's family front, which
needs the run's solver: on the parent side that means rebuilding the model and the solver
of every run after all of them have finished (~30 ms a run on the project's machine, with
the kernels to load), one after the other. :func:`tabulate` computes the row in the worker
right after its run instead, on the branch as the worker returns it (no solver, no model:
both are rebuilt from the branch's metadata exactly as the parent rebuilds them), so the
values are those the parent would compute. What the computation warns is kept in the row
and issued again on the parent side when the table is assembled (:func:`replay`), in the
table's row order, as if the parent had computed it (the study's report lists those
warnings). Log records go where the worker's logging sends them, as those of its runs do.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

__all__ = ["TableRow", "row_values", "tabulate", "replay"]


@dataclass
class TableRow:
    """A table row and what computing it raised.

    Attributes
    ----------
    frequency, mode_share : list of float, shape (n_amplitudes,)
        Hz, and the starting mode's share of the kinetic energy (NaN where unknown).
    partner : list, shape (n_amplitudes,)
        (k, j, share) or None per amplitude.
    notes : list of str, shape (n_amplitudes,)
    warnings : list of (message, category, filename, lineno)
        The warnings raised while computing the row.
    model : bool
        The computation attached the branch's model (rebuilt from its metadata: a solve
        between two stored points needs the solver), as it would have on the parent
        side, where the saved study then records the model's contacts
        (:func:`~mmshbm.results.base.result_payload`): :func:`replay` attaches it.
    """

    frequency: list
    mode_share: list
    partner: list
    notes: list
    warnings: list = field(default_factory=list)
    model: bool = False


def row_values(branch, amplitudes: np.ndarray, unit: str) -> tuple[list, list, list, list]:
    """(frequency, mode_share, partner, notes) of ``branch`` at ``amplitudes`` (in m for
    ``unit="m"``, in gaps of the branch for ``unit="gap"``): the row of
    :meth:`~mmshbm.analysis.studies.Study.table`."""
    from ..results.family_points import frequency_at
    from .skips import explain, mode_share_at, partner_at, skips

    scale = _gap(branch) if unit == "gap" else 1.0
    intervals = skips(branch)
    f, share, partner, notes = [], [], [], []
    for a in amplitudes:
        value = frequency_at(branch, a * scale)  # no warning beyond the branch: notes say why
        f.append(value)
        share.append(mode_share_at(branch, a * scale))
        partner.append(partner_at(branch, a * scale))
        notes.append(explain(branch, a * scale, value, intervals))
    return f, share, partner, notes


def tabulate(branch, amplitudes, unit: str) -> TableRow | None:
    """The row of ``branch`` (:func:`row_values`) with the warnings it raised, or None
    when it raises (the parent then computes it, and raises there as it would have). The
    branch is left as it was given: no solver, and the model it had."""
    model = branch.model
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            values = row_values(branch, np.asarray(amplitudes, dtype=float), unit)
        attached = model is None and branch.model is not None
    except Exception:  # the parent computes the row again and raises there
        return None
    finally:
        branch.solver = None
        branch.model = model
    raised = [(str(w.message), w.category, w.filename, w.lineno) for w in caught]
    return TableRow(*values, warnings=raised, model=attached)


def replay(row: TableRow, branch) -> None:
    """Issue the warnings of ``row`` in this process, and attach the model of ``branch``
    (its row's branch) where computing the row attached it."""
    if row.model and branch.model is None:
        branch.get_model()
    for message, category, filename, lineno in row.warnings:
        warnings.warn_explicit(message, category, filename, lineno)


def _gap(branch) -> float:
    gap = branch.gap
    if gap is None or not gap > 0:
        raise ValueError("amplitudes in gaps need a model with a positive gap; use unit='m'")
    return float(gap)
