"""What every result of a continuation holds, and its file.

A result (:class:`~mmshbm.results.branch.Branch`, a backbone;
:class:`~mmshbm.results.response.FrequencyResponse`, a forced response) is a struct of
arrays, one entry per converged point (``ARRAY_FIELDS`` of its class, ``states`` the
solver's scaled unknowns), plus the status, the special points, further per-point
``records``, the residual histories and the metadata that redoes the run.
:class:`ResultBase` gives them their common behaviour:

- the model (attached, or rebuilt from the description in the metadata) and the solver:
  ``result.solver`` is the problem that computed the result when one is held, else it is
  rebuilt on first access from the model and the options stored in the metadata (None
  when it cannot be); :attr:`ResultBase.attached_solver` never builds;
- per-point signals, contact force and harmonic content from the solver;
- files: :meth:`ResultBase.save` / :meth:`ResultBase.load`, one ``.npz`` archive
  (:mod:`mmshbm.results.archive`) with every array bit-identical on reload and one JSON
  record (format name and version, status, method, H, special points, metadata, the model's
  gap, contacts and, where its description cannot rebuild it, its matrices).

The solver is rebuilt by functions of the methods layer, above this one: the methods
register them when they are imported (:func:`register_entry_point`,
:mod:`mmshbm.methods.entry_points`; looked up through :mod:`mmshbm._entry_points`), so
that results never import the methods.
"""

from __future__ import annotations

import logging
import platform
from collections.abc import Callable
from pathlib import Path
from typing import ClassVar

import numpy as np

from .. import _entry_points
from ..core.special_points import special_from_json, special_to_json
from ..core.status import Status
from .archive import read_archive, write_archive
from .models import _model_arrays, _model_from_arrays, rebuild_model

__all__ = ["ResultBase", "SolverSlot", "register_entry_point", "entry_point", "result_payload",
           "result_from_payload", "versions", "FORMAT_VERSION"]

log = logging.getLogger(__name__)

#: the layout version of result files (``format_version``), the same for every kind
FORMAT_VERSION = 1


def register_entry_point(name: str, function: Callable) -> None:
    """Make ``function`` the entry point ``name`` of the results: "make_problem",
    "backbone", "admissible_signals", "make_forced_problem" (the methods layer registers
    them when it is imported, :mod:`mmshbm.methods.entry_points`)."""
    _entry_points.register(name, function)


def entry_point(name: str) -> Callable:
    """The function registered as ``name`` (:func:`register_entry_point`); the methods
    package is imported first if it is missing (:mod:`mmshbm._entry_points`).

    Raises
    ------
    LookupError
        When nothing registers it.
    """
    return _entry_points.lookup(name)


def versions() -> dict:
    """Versions of Python and of the numerical packages (for file metadata)."""
    import numba
    import scipy

    from .. import __version__

    return {"mmshbm": __version__, "python": platform.python_version(), "numpy": np.__version__,
            "scipy": scipy.__version__, "numba": numba.__version__}


class SolverSlot:
    """The ``solver`` attribute of a result: the problem object it holds, or, when it
    holds none, the one :meth:`ResultBase.attach_solver` rebuilds (kept); None when the
    result cannot rebuild one. Assigning None drops the held solver."""

    def __set_name__(self, owner, name: str) -> None:
        self.attr = f"_{name}"

    def __get__(self, obj, cls=None):
        if obj is None:
            return None  # the dataclass default
        solver = obj.__dict__.get(self.attr)
        if solver is None:
            try:
                solver = obj.attach_solver()
            except (ValueError, KeyError) as err:
                log.debug("no solver can be rebuilt for this %s: %s", obj._NOUN, err)
                return None
        return solver

    def __set__(self, obj, value) -> None:
        obj.__dict__[self.attr] = value


class ResultBase:
    """Behaviour shared by :class:`~mmshbm.results.branch.Branch` and
    :class:`~mmshbm.results.response.FrequencyResponse` (dataclasses that declare the
    fields: ``frequency``, ``amplitude``, ..., ``states``, ``status``, ``method``,
    ``harmonics``, ``special_points``, ``metadata``, ``solver`` (a :class:`SolverSlot`),
    ``residual_histories``, ``model``, ``records``)."""

    #: the ``format`` entry of the class's files
    FORMAT: ClassVar[str] = ""
    #: per-point arrays, in file order
    ARRAY_FIELDS: ClassVar[tuple] = ()
    #: what the class is called in messages
    _NOUN: ClassVar[str] = "result"

    def __len__(self) -> int:
        return len(self.frequency)

    @property
    def completed(self) -> bool:
        """True when the run reached one of its bounds (status ``"bound:<name>"``); a run
        that ran out of steps (``"max_steps"``), of step size or failed is not completed."""
        return Status.parse(self.status).kind == Status.BOUND

    @property
    def attached_solver(self):
        """The solver held by this result (None when none is: :attr:`solver` then rebuilds it)."""
        return self.__dict__.get("_solver")

    @property
    def gap(self) -> float | None:
        """The model's (smallest) gap (m): of the attached model or solver, else from the
        metadata (``model_gap``, then the description's ``gap``); None when unknown."""
        model = self.model if self.model is not None else getattr(self.attached_solver, "model", None)
        if model is not None:
            return float(model.gap)
        gap = self.metadata.get("model_gap", dict(self.metadata.get("model", {})).get("gap"))
        return None if gap is None else float(gap)

    # ------------------------------------------------------------------ model and solver
    def get_model(self):
        """The :class:`~mmshbm.model.Model` of this result: the attached one, the held
        solver's, or rebuilt from ``metadata["model"]`` (with the gaps the metadata records)
        and cached in :attr:`model`.

        Raises
        ------
        ValueError
            If the description cannot rebuild the model and no model is attached.
        """
        solver = self.attached_solver
        if self.model is None and solver is not None and hasattr(solver, "model"):
            self.model = solver.model
        if self.model is None:
            self.model = rebuild_model(self.metadata.get("model", {}),
                                       self.metadata.get("model_gaps", self.metadata.get("model_gap")))
        return self.model

    def _build_solver(self, model, options: dict):
        """The solver of this result's method on ``model`` with method ``options``."""
        raise NotImplementedError

    def attach_solver(self, **method_options):
        """Rebuild the solver that computed this result from what it stores (the model, by
        :meth:`get_model`; method and method options from ``metadata``, those given here
        overriding them) and attach it (:attr:`solver`).

        Returns
        -------
        object
            The solver (continuation problem).

        Raises
        ------
        ValueError
            If the model cannot be rebuilt, or the rebuilt solver's unknowns do not match
            :attr:`states`.
        """
        options = {**dict(self.metadata.get("method_options", {})), **method_options}
        solver = self._build_solver(self.get_model(), options)
        n = getattr(solver, "n_unknowns", None)
        if n is not None and self.states.ndim == 2 and len(self) and self.states.shape[1] != n:
            raise ValueError(f"the rebuilt {self.method} solver has {n} unknowns but the {self._NOUN}'s "
                             f"states have {self.states.shape[1]}: the options do not match the run")
        convert = getattr(solver, "states_from_force_scaling", None)  # any solver, a plain object too
        if convert is not None and "pole_scaling" not in self.metadata:  # saved before it was recorded
            converted = convert(self.states)
            try:  # in place: arrays taken from the result before keep their meaning
                self.states[...] = converted
            except ValueError:  # read-only
                self.states = converted
            self.metadata["pole_scaling"] = solver.pole_scaling
        self.solver = solver
        return solver

    def _require_solver(self):
        solver = self.attached_solver
        if solver is None:
            try:
                solver = self.attach_solver()
            except (ValueError, KeyError) as err:
                raise RuntimeError(f"this {self._NOUN} has no solver attached and none can be rebuilt: "
                                   f"{err}") from None
        return solver

    def _index(self, point: int) -> int:
        n = len(self)
        if isinstance(point, bool) or not isinstance(point, int | np.integer):
            raise TypeError(f"point must be an integer index, got {point!r}")
        if not -n <= point < n:
            raise IndexError(f"point {point} out of range for a {self._NOUN} of {n} points")
        return int(point) % n

    # ------------------------------------------------------------------ per point
    def time_signals(self, point: int, dofs=None, n_samples: int = 256):
        """(t (n_samples,) s, q (n_dofs, n_samples)) over one period at ``point``: the
        method's own signals of ``dofs`` (default all DOFs)."""
        return self._require_solver().time_signals(self.states[self._index(point)], dofs, n_samples)

    def contact_force(self, point: int, n_samples: int = 256):
        """(t, λ) over one period at ``point``: the method's own contact force (N)."""
        return self._require_solver().contact_force(self.states[self._index(point)], n_samples)

    def harmonic_content(self, point: int, dof: int | None = None) -> np.ndarray:
        """Amplitudes √(c_k² + s_k²) of harmonics 0..H of ``dof`` (default the contact DOF
        of a backbone, the amplitude DOF of a forced response) at ``point``; shape (H+1,)."""
        return self._require_solver().harmonic_content(self.states[self._index(point)], dof)

    # ------------------------------------------------------------------ files
    def save(self, path) -> Path:
        """Write this result to ``path`` (a ``.npz`` archive, written exactly there).

        The archive holds every per-point array (``ARRAY_FIELDS``, bit-identical on
        reload), the records and the residual histories, and ``metadata``: a JSON string
        with the format name and version, status, method, H, special points, the run's
        metadata (model description, method and continuation options, versions, timing),
        and the model's gap, contacts and amplitude DOF. When the model's description
        cannot rebuild it (a user :class:`~mmshbm.model.Model`, or a model whose matrices
        differ from its description's), its matrices are stored too (CSR parts,
        ``model_M_data``, ...).

        Returns
        -------
        pathlib.Path
            The path written.
        """
        arrays, meta = result_payload(self)
        meta = {"format": self.FORMAT, "format_version": FORMAT_VERSION, **meta, "saved_with": versions()}
        return write_archive(path, arrays, meta)

    @classmethod
    def load(cls, path, attach_solver: bool = False):
        """Read a result written by :meth:`save` (by this version or an earlier one).

        Parameters
        ----------
        path : str or Path
            The ``.npz`` file.
        attach_solver : bool
            Also rebuild the model and solver now (otherwise :attr:`solver` and the
            per-point methods do it on first use).

        Raises
        ------
        ValueError
            If the file is missing, unreadable, or not a saved result of this class.
        """
        arrays, meta = read_archive(path)
        if meta.get("format") != cls.FORMAT:
            raise ValueError(f"{str(path)!r} is not a saved mmshbm {cls.__name__} "
                             f"(format {meta.get('format')!r})")
        result = result_from_payload(cls, arrays, meta)
        if attach_solver:
            result.attach_solver()
        return result


# ---------------------------------------------------------------------- payloads
def result_payload(result: ResultBase, prefix: str = "") -> tuple[dict, dict]:
    """Split a result into (arrays, JSON-able metadata) for an archive; array keys get
    ``prefix``."""
    arrays = {f"{prefix}{name}": np.asarray(getattr(result, name)) for name in type(result).ARRAY_FIELDS}
    hist = [np.asarray(h, dtype=float).ravel() for h in result.residual_histories]
    arrays[f"{prefix}residual_histories"] = np.concatenate(hist) if hist else np.empty(0)
    arrays[f"{prefix}residual_history_lengths"] = np.array([len(h) for h in hist], dtype=np.int64)
    names = []
    for name, value in dict(result.records).items():
        if not isinstance(name, str) or not name:
            raise TypeError(f"record names must be non-empty strings, got {name!r}")
        arrays[f"{prefix}record__{name}"] = np.asarray(value)
        names.append(name)

    description = dict(result.metadata.get("model", {}))
    model = result.model if result.model is not None else getattr(result.attached_solver, "model", None)
    info = {"description": description, "matrices": False}
    if model is not None:
        info.update(gap=float(model.gap), description=dict(model.description),
                    contacts=[[int(c.dof), float(c.gap), int(c.side)] for c in model.contacts],
                    amplitude_dof=model._amplitude_dof)
        if model.n_contacts == 1:  # the keys of format 1, still read by older versions
            info.update(contact_dof=int(model.contact_dof), stop_side=int(model.stop_side))
        try:
            rebuilt = rebuild_model(model.description, [c.gap for c in model.contacts])
            store = not rebuilt.same_as(model)
        except ValueError:
            store = True
        if store:
            arrays.update({f"{prefix}{k}": v for k, v in _model_arrays(model).items()})
            info["matrices"] = True
    else:
        gap = result.metadata.get("model_gap", description.get("gap"))
        info["gap"] = None if gap is None else float(gap)
        if description.get("kind") not in ("TimoshenkoBeam", "OneDofOscillator"):
            log.warning("saving a %s whose model can neither be rebuilt from its description nor was "
                        "attached: the file cannot redo the run", result._NOUN)
    meta = {"status": result.status, "method": result.method, "harmonics": int(result.harmonics),
            "special_points": special_to_json(result.special_points),
            "metadata": result.metadata, "model": info, "records": names}
    return arrays, meta


def result_from_payload(cls, arrays: dict, meta: dict, prefix: str = ""):
    """Inverse of :func:`result_payload`: an instance of ``cls``."""
    try:
        fields_ = {name: arrays[f"{prefix}{name}"] for name in cls.ARRAY_FIELDS}
        flat = arrays[f"{prefix}residual_histories"]
        lengths = arrays[f"{prefix}residual_history_lengths"]
        info = meta["model"]
        status, method, harmonics = meta["status"], meta["method"], int(meta["harmonics"])
        special = special_from_json(meta["special_points"])
        metadata = dict(meta["metadata"])
        records = {str(name): arrays[f"{prefix}record__{name}"] for name in meta.get("records", [])}
    except (KeyError, TypeError, ValueError) as err:
        raise ValueError(f"malformed {cls._NOUN} record: missing or bad entry {err}") from None
    histories = np.split(flat, np.cumsum(lengths)[:-1]) if len(lengths) else []
    if info.get("gap") is not None and info["gap"] != metadata.get("model", {}).get("gap"):
        metadata["model_gap"] = info["gap"]  # Model.with_gap: the description's gap is stale
    if "contacts" in info and len(info["contacts"]) > 1:
        metadata["model_gaps"] = [float(c[1]) for c in info["contacts"]]
    try:
        model = _model_from_arrays({k[len(prefix):]: v for k, v in arrays.items() if k.startswith(prefix)},
                                   info) if info.get("matrices") else None
    except (KeyError, TypeError, ValueError) as err:
        raise ValueError(f"malformed {cls._NOUN} record: bad model matrices {err}") from None
    return cls(**fields_, status=status, method=method, harmonics=harmonics, special_points=special,
               metadata=metadata, residual_histories=list(histories), model=model, records=records)
