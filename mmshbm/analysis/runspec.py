"""What a worker runs: one backbone of a study, described by a picklable :class:`RunSpec`.

Workers receive only run descriptions (beam data, a model file or matrices, H, method,
options) and return branches without their solver, which holds unpicklable FFT plans;
the solver is rebuilt on the parent side when a per-point method needs it.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._warnings import BranchWarning, MmshbmWarning
from ..results.branch import Branch

__all__ = ["RunSpec", "build_model", "execute", "matrix_source"]


@dataclass(frozen=True)
class RunSpec:
    """Everything a worker needs for one run; picklable, no solver or model objects.

    Attributes
    ----------
    index : int
        Position of the run in the study.
    coords : dict
        The run's grid coordinates, e.g. ``{"method": "mmshbm", "elements": 21,
        "harmonics": 5, "gap": 0.001}``.
    source : dict
        How to build the model: ``{"beam": {TimoshenkoBeam fields}, "n_elements": n,
        "grading": g}``, ``{"file": path, "gap": g or None}`` (a :meth:`Model.save_npz`
        file) or ``{"matrices": {CSR parts}, "contact_dof", "gap", "stop_side",
        "description"}``.
    harmonics : int
        H.
    method : str
        "mmshbm", "penalty" or "shooting".
    max_amplitude : float or None
        Largest amplitude, in m (``unit="m"``) or in gaps of the run's model.
    unit : {"m", "gap"}
        Unit of ``max_amplitude``.
    options : dict
        Further keyword arguments of :func:`mmshbm.backbone`.
    """

    index: int
    coords: dict
    source: dict
    harmonics: int
    method: str
    max_amplitude: float | None
    unit: str
    options: dict


def build_model(source: dict):
    """The :class:`~mmshbm.model.Model` described by a :attr:`RunSpec.source`."""
    from ..model.model import Model

    if "beam" in source:
        from ..fe.beam import TimoshenkoBeam

        return TimoshenkoBeam(**source["beam"]).model(source["n_elements"], source["grading"])
    if "file" in source:
        model = Model.from_npz(source["file"])
    elif "matrices" in source:
        import scipy.sparse as sp

        parts, mats = source["matrices"], []
        for name in ("M", "K"):
            d, i, p, shape = (parts[f"{name}_{q}"] for q in ("data", "indices", "indptr", "shape"))
            mats.append(sp.csr_matrix((d, i, p), shape=tuple(int(v) for v in shape)))
        model = Model.from_matrices(mats[0], mats[1], source["contact_dof"], source["gap"],
                                    source["stop_side"], source.get("description"))
    else:
        raise ValueError(f"unknown model source with keys {sorted(source)}")
    gap = source.get("gap")
    return model if gap is None or gap == model.gap else model.with_gap(gap)


def execute(spec: RunSpec) -> Branch:
    """Run one grid point (this is what workers execute); the branch comes back without
    its solver, which holds unpicklable FFT plans. Thread executors are safe: every
    thread has its own FFTW plans and buffers (:func:`mmshbm.harmonic.harmonics.transform`)."""
    return _execute(spec)


def _execute(spec: RunSpec) -> Branch:
    from ..methods.backbone import backbone

    model = build_model(spec.source)
    max_amplitude = spec.max_amplitude
    if max_amplitude is not None and spec.unit == "gap":
        max_amplitude *= model.gap
    with warnings.catch_warnings(record=True) as caught:
        # the checks are recorded in branch.metadata["checks"], the package's other warnings
        # (e.g. a modal condensation's left-out mode) in metadata["run_warnings"]: a worker
        # process has no terminal of its own, and the study summarises both on the parent side
        warnings.simplefilter("always", MmshbmWarning)
        warnings.simplefilter("ignore", BranchWarning)
        options = dict(spec.options)
        harmonics = spec.harmonics
        if options.get("tol") is not None:  # H chosen per point: the grid's H is where it starts
            options.setdefault("start_harmonics", harmonics)
            harmonics = None
        branch = backbone(model, harmonics=harmonics, method=spec.method, max_amplitude=max_amplitude,
                          **options)
    notes = []
    package = str(Path(__file__).resolve().parents[1]) + os.sep
    for w in caught:
        if issubclass(w.category, MmshbmWarning) or str(w.filename).startswith(package):
            notes.append(f"{w.category.__name__}: {w.message}")
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if notes:
        branch.metadata["run_warnings"] = list(dict.fromkeys(notes))
    branch.solver = None
    return branch


def matrix_source(model) -> dict:
    """The :attr:`RunSpec.source` of a user model: its CSR matrices and contact data."""
    mats = {}
    for name, A in (("M", model.M.tocsr()), ("K", model.K.tocsr())):
        mats.update({f"{name}_data": A.data, f"{name}_indices": A.indices, f"{name}_indptr": A.indptr,
                     f"{name}_shape": np.array(A.shape)})
    return {"matrices": mats, "contact_dof": int(model.contact_dof), "gap": float(model.gap),
            "stop_side": int(model.stop_side), "description": dict(model.description)}
