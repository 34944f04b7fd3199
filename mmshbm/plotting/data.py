"""The data of the backbone plots without matplotlib: a branch's plotted arrays
(:class:`BranchData`) and the reference frequencies (:func:`reference_frequencies`).
Importing this module imports numpy only."""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

__all__ = ["BranchData", "amplitude_name", "reference_frequencies", "resonance_label", "resonance_orders",
           "resonances_met", "symmetric_clearance", "marked_run"]

log = logging.getLogger(__name__)


def _gap(branch) -> float:
    gap = branch.gap
    if gap is None:
        try:
            gap = branch.get_model().gap
        except ValueError:
            gap = 0.0
    return float(gap)


@dataclass
class BranchData:
    """What the backbone plots read from a :class:`~mmshbm.results.branch.Branch`, without
    its solver or model: cheap to pickle and to unpickle (the command line draws its
    figures in a child process that imports matplotlib while the parent computes, see
    :mod:`mmshbm.cli._plot_worker`). :func:`~mmshbm.plotting.plot_backbone` and
    :func:`~mmshbm.plotting.plot_frequency_energy` accept it in place of a Branch; pass the reference
    lines as ``model=reference_frequencies(model)``."""

    frequency: np.ndarray
    amplitude: np.ndarray
    energy: np.ndarray
    contact_force_max: np.ndarray
    status: str
    method: str
    harmonics: int
    special_points: list = field(default_factory=list)
    metadata: dict = field(default_factory=dict)
    gap: float | None = None
    records: dict = field(default_factory=dict)
    odd_harmonics: bool = False
    amplitude_name: str = "amplitude"

    #: the per-point records the plots read (the family front: mmshbm.results.family_points)
    RECORDS = ("on_family", "mode_share")

    @classmethod
    def of(cls, branch) -> BranchData:
        """The plotted data of ``branch``."""
        meta = {key: branch.metadata[key] for key in ("model", "continuation") if key in branch.metadata}
        records = {key: np.asarray(branch.records[key]) for key in cls.RECORDS
                   if key in getattr(branch, "records", {})}
        return cls(np.asarray(branch.frequency), np.asarray(branch.amplitude), np.asarray(branch.energy),
                   np.asarray(branch.contact_force_max), str(branch.status), str(branch.method),
                   int(branch.harmonics), list(branch.special_points), meta, _gap(branch), records,
                   odd_harmonics(branch), amplitude_name(branch))

    def __len__(self) -> int:
        return len(self.frequency)

    def get_model(self):
        raise ValueError("BranchData carries no model: pass the reference lines as model=(f_lin, f_zero)"
                         " or model=reference_frequencies(model)")


def amplitude_name(branch) -> str:
    """What the branch's amplitude measures, for an axis label: "tip amplitude" (a beam's
    tip deflection), "node 3 amplitude", "contact DOF amplitude" or "amplitude of q[d]"
    (a user's model), plain "amplitude" where the branch carries no model."""
    if isinstance(branch, BranchData):
        return branch.amplitude_name
    try:
        model = branch.get_model()
    except ValueError:
        return "amplitude"
    dof = int(model.amplitude_dof)
    meta = branch.metadata.get("model", {})
    if meta.get("kind") == "TimoshenkoBeam":
        n_el, node = int(meta["n_elements"]), dof // 2 + 1
        where = "tip" if node == n_el else f"node {node}"
        return f"{where} amplitude" if dof % 2 == 0 else f"{where} rotation amplitude"
    if model.n_contacts and dof == int(model.contacts[0].dof) and all(c.dof == dof for c in model.contacts):
        return "contact DOF amplitude"
    return f"amplitude of q[{dof}]"


def _is_clearance(model) -> bool:
    """Two stops with positive gaps on one DOF, one on each side."""
    contacts = list(model.contacts)
    return (len(contacts) == 2 and contacts[0].dof == contacts[1].dof
            and {int(c.side) for c in contacts} == {1, -1} and all(c.gap > 0 for c in contacts))


def reference_frequencies(model, modes=(2, 3)) -> tuple[np.ndarray, float | None, bool] | None:
    """(linear frequencies of modes 1..max(modes) (Hz), zero-gap limit (Hz) or None, whether
    that limit is exact) of ``model`` (sparse eigen-solves on large models); None when they
    cannot be computed. The limit of one one-sided contact, 2/(1/f_open + 1/f_held), is
    exact with one DOF with mass only (a chain's first mode can pass it by a third,
    docs/resonances.md); a clearance's, the frequency with the node held between its
    stops, is exact. A tuple (f_lin, f_zero[, exact]) given as ``model`` is returned as it
    is."""
    if isinstance(model, tuple):
        return model
    n = max(max(modes, default=1), 1)
    try:
        f_lin = model.linear_frequencies(min(n, len(model.l)))
        f_zero = model.zero_gap_frequency() if model.n_contacts == 1 and model.gap > 0 else None
        exact = len(model.l) == 1
        if _is_clearance(model):  # both gaps → 0: the DOF held between its stops at all times
            from ..methods.mms.held import _held_frequency

            f_zero = _held_frequency(model, [model.contacts[0].dof], 1)
            exact = True
    except (ValueError, np.linalg.LinAlgError) as err:
        log.info("no reference lines: %s", err)
        return None
    return f_lin, f_zero, exact


def resonance_label(k, j) -> str:
    """The label of the internal resonance of harmonic k with mode j (1-based), e.g.
    "5Ω≈f₂"."""
    sub = str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉")
    return f"{k}Ω≈f{str(j).translate(sub)}"


def symmetric_clearance(model) -> bool:
    """True for a symmetric clearance: two stops on one DOF, on opposite sides, with equal
    gaps. Its periodic motions have half-wave symmetry, so they carry odd harmonics only
    and only odd harmonics can meet another mode."""
    contacts = list(getattr(model, "contacts", ()) or ())
    if len(contacts) != 2:
        return False
    a, b = contacts
    return a.dof == b.dof and a.side == -b.side and np.isclose(a.gap, b.gap, rtol=1e-12, atol=0)


def odd_harmonics(branch) -> bool:
    """Whether ``branch``'s motion carries odd harmonics only (its model is a symmetric
    clearance); False when the model cannot be had."""
    if hasattr(branch, "odd_harmonics"):
        return bool(branch.odd_harmonics)
    try:
        return symmetric_clearance(branch.get_model())
    except ValueError:
        return False


def resonance_orders(harmonics: int, max_order: int, odd: bool = False) -> list[int]:
    """The orders n of the reference lines f_j/n a branch can meet: harmonics 2..H that
    its ansatz carries (all up to ``max_order`` for a method without truncation, H = 0),
    odd ones only for a motion with half-wave symmetry (``odd``)."""
    top = max_order if harmonics <= 0 else min(int(harmonics), max_order)
    return [n for n in range(2, top + 1) if not odd or n % 2]


def resonances_met(branch) -> list:
    """The branch's ``"internal_resonance"`` special points where the branch resonates:
    a stretch named at the branch's last point is left out (the run ended on its way
    toward kΩ = ω_j, at a bound or a stop, and its largest share is only where it stopped)."""
    n = len(branch)
    return [sp for sp in branch.special_points if sp[0] == "internal_resonance" and 0 <= int(sp[1]) < n - 1]


def marked_run(runs) -> dict:
    """The coordinates (method, harmonics, elements) of the run of a study that carries
    the marked points of its figures: the largest H with the most elements."""
    runs = list(runs)
    if not runs:
        raise ValueError("the study is empty")
    best = max(runs, key=lambda r: (r.get("harmonics", 0), r.get("elements", 0)))
    return {k: best[k] for k in ("method", "harmonics", "elements") if k in best}
