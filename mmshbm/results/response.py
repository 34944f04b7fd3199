"""FrequencyResponse: the result of a forced-response computation.

Like :class:`~mmshbm.results.branch.Branch`, a struct of arrays (one entry per converged
point of the continuation in the excitation frequency) plus the status, the special
points (folds, grazing, bifurcations from the Floquet multipliers) and the metadata to
redo the run; per-point signals come from the solver (``response.solver``), rebuilt on
demand from the model and the excitation stored in the metadata.

Files: :meth:`FrequencyResponse.save` writes one ``.npz`` archive (the arrays
bit-identical on reload, the metadata as JSON, the model's matrices when its description
cannot rebuild it); :meth:`FrequencyResponse.to_csv` the per-point table.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.special_points import special_from_json, special_to_json
from ..core.status import Status
from .branch import read_archive, versions, write_archive
from .models import _model_arrays, _model_from_arrays, rebuild_model

__all__ = ["FrequencyResponse"]

RESPONSE_FORMAT = "mmshbm.FrequencyResponse"
FORMAT_VERSION = 1
#: per-point arrays, in file order
ARRAY_FIELDS = ("frequency", "amplitude", "phase", "energy", "contact_force_max", "stable", "floquet_max",
                "newton_iterations", "step_size", "states")


@dataclass(eq=False)
class FrequencyResponse:
    """A computed frequency response (forced, damped, with impact).

    Attributes
    ----------
    frequency : ndarray, shape (n_points,)
        Excitation (= response) frequency (Hz).
    amplitude : ndarray, shape (n_points,)
        Largest |q| (m or rad) of the model's ``amplitude_dof`` over the period.
    phase : ndarray, shape (n_points,)
        Lag (rad) of that DOF's fundamental behind the excitation force, in [−π/2, 3π/2);
        π/2 at phase resonance.
    energy : ndarray, shape (n_points,)
        Period mean of kinetic + potential energy (J).
    contact_force_max : ndarray, shape (n_points,)
        Largest force (N) a stop exerts over the period.
    stable : ndarray of bool, shape (n_points,)
        All Floquet multipliers inside the unit circle (True where not computed).
    floquet_max : ndarray, shape (n_points,)
        Largest multiplier modulus (NaN where not computed).
    newton_iterations, step_size, states : ndarray
        Per point, as in :class:`Branch` (states: the solver's scaled unknowns).
    status : str
        Why the continuation stopped ("bound:frequency" is the normal end).
    method : str
        "mmshbm", "penalty" or "shooting".
    harmonics : int
        H (0 for shooting).
    special_points : list of SpecialPoint
        "start", "grazing", "fold", "branch_point", "period_doubling", "neimark_sacker",
        bound hits, "endpoint".
    metadata : dict
        Model description, excitation, frequency range, method and continuation options,
        versions, timing.
    records : dict of str to ndarray
        Further per-point quantities (e.g. ``floquet``: all multipliers, complex).
    """

    frequency: np.ndarray
    amplitude: np.ndarray
    phase: np.ndarray
    energy: np.ndarray
    contact_force_max: np.ndarray
    stable: np.ndarray
    floquet_max: np.ndarray
    newton_iterations: np.ndarray
    step_size: np.ndarray
    states: np.ndarray
    status: str
    method: str
    harmonics: int
    special_points: list = field(default_factory=list)
    metadata: dict = field(default_factory=dict)
    solver: object = field(default=None, repr=False)
    residual_histories: list = field(default_factory=list, repr=False)
    model: object = field(default=None, repr=False)
    records: dict = field(default_factory=dict, repr=False)

    def __len__(self) -> int:
        return len(self.frequency)

    @property
    def completed(self) -> bool:
        """True when the response reached a bound of its frequency range."""
        return Status.parse(self.status).kind == Status.BOUND

    @property
    def gap(self) -> float | None:
        """The model's (smallest) gap (m), when known."""
        model = self.model if self.model is not None else getattr(self.solver, "model", None)
        if model is not None:
            return float(model.gap)
        gap = dict(self.metadata.get("model", {})).get("gap")
        return None if gap is None else float(gap)

    def peak(self) -> tuple[float, float]:
        """(frequency (Hz), amplitude (m)) of the largest amplitude on the response."""
        i = int(np.argmax(self.amplitude))
        return float(self.frequency[i]), float(self.amplitude[i])

    # ------------------------------------------------------------------ model and solver
    def get_model(self):
        """The model: attached, the solver's, or rebuilt from the metadata's description."""
        if self.model is None and self.solver is not None:
            self.model = self.solver.model
        if self.model is None:
            self.model = rebuild_model(self.metadata.get("model", {}), self.metadata.get("model_gap"))
        return self.model

    def attach_solver(self):
        """Rebuild the solver that computed this response (model, excitation, method and
        options from the metadata) and attach it."""
        make = _entry_point("mmshbm.methods.frequency_response:make_forced_problem")
        meta = self.metadata
        solver = make(self.get_model(), meta["excitation"], self.method, self.harmonics,
                      dict(meta.get("method_options", {})))
        if len(self) and self.states.shape[1] != solver.n_unknowns:
            raise ValueError(f"the rebuilt {self.method} solver has {solver.n_unknowns} unknowns but the "
                             f"states have {self.states.shape[1]}: the options do not match the run")
        self.solver = solver
        return solver

    def _require_solver(self):
        if self.solver is None:
            try:
                self.attach_solver()
            except (ValueError, KeyError) as err:
                raise RuntimeError(f"this response has no solver attached and none can be rebuilt: {err}") \
                    from None
        return self.solver

    def _index(self, point: int) -> int:
        n = len(self)
        if isinstance(point, bool) or not isinstance(point, int | np.integer):
            raise TypeError(f"point must be an integer index, got {point!r}")
        if not -n <= point < n:
            raise IndexError(f"point {point} out of range for a response of {n} points")
        return int(point) % n

    def time_signals(self, point: int, dofs=None, n_samples: int = 256):
        """(t (n_samples,) s, q (n_dofs, n_samples)) over one period at ``point``."""
        return self._require_solver().time_signals(self.states[self._index(point)], dofs, n_samples)

    def contact_force(self, point: int, n_samples: int = 256):
        """(t, λ (n_contacts, n_samples) N) over one period at ``point``."""
        return self._require_solver().contact_force(self.states[self._index(point)], n_samples)

    def harmonic_content(self, point: int, dof: int | None = None) -> np.ndarray:
        """|Q̂_k|, k = 0..H, of ``dof`` (default the amplitude DOF) at ``point``."""
        return self._require_solver().harmonic_content(self.states[self._index(point)], dof)

    def floquet_multipliers(self, point: int) -> np.ndarray:
        """All Floquet multipliers at ``point`` (stored, or computed by the solver)."""
        if "floquet" in self.records:
            return np.asarray(self.records["floquet"][self._index(point)])
        return self._require_solver().floquet_multipliers(self.states[self._index(point)])

    # ------------------------------------------------------------------ files
    def save(self, path) -> Path:
        """Write the response to ``path`` (``.npz``); returns the path."""
        arrays = {name: np.asarray(getattr(self, name)) for name in ARRAY_FIELDS}
        hist = [np.asarray(h, dtype=float).ravel() for h in self.residual_histories]
        arrays["residual_histories"] = np.concatenate(hist) if hist else np.empty(0)
        arrays["residual_history_lengths"] = np.array([len(h) for h in hist], dtype=np.int64)
        for name, value in self.records.items():
            arrays[f"record__{name}"] = np.asarray(value)
        model = self.model if self.model is not None else getattr(self.solver, "model", None)
        info = {"matrices": False}
        if model is not None:
            info.update(description=dict(model.description),
                        contacts=[[int(c.dof), float(c.gap), int(c.side)] for c in model.contacts],
                        amplitude_dof=model._amplitude_dof)
            try:
                store = not rebuild_model(model.description, [c.gap for c in model.contacts]).same_as(model)
            except ValueError:
                store = True
            if store:
                arrays.update(_model_arrays(model))
                info["matrices"] = True
        meta = {"format": RESPONSE_FORMAT, "format_version": FORMAT_VERSION, "status": self.status,
                "method": self.method, "harmonics": int(self.harmonics),
                "special_points": special_to_json(self.special_points), "metadata": self.metadata,
                "model": info, "records": list(self.records), "saved_with": versions()}
        return write_archive(path, arrays, meta)

    @classmethod
    def load(cls, path) -> FrequencyResponse:
        """Read a response written by :meth:`save`.

        Raises
        ------
        ValueError
            For a missing, unreadable or foreign file.
        """
        arrays, meta = read_archive(path)
        if meta.get("format") != RESPONSE_FORMAT:
            raise ValueError(f"{str(path)!r} is not a saved mmshbm FrequencyResponse "
                             f"(format {meta.get('format')!r})")
        try:
            fields_ = {name: arrays[name] for name in ARRAY_FIELDS}
            lengths = arrays["residual_history_lengths"]
            flat = arrays["residual_histories"]
            records = {str(n): arrays[f"record__{n}"] for n in meta.get("records", [])}
            info = meta["model"]
            model = _model_from_arrays(arrays, info) if info.get("matrices") else None
            histories = list(np.split(flat, np.cumsum(lengths)[:-1])) if len(lengths) else []
            special = special_from_json(meta["special_points"])
            return cls(**fields_, status=meta["status"], method=meta["method"],
                       harmonics=int(meta["harmonics"]), special_points=special,
                       metadata=dict(meta["metadata"]), residual_histories=histories, model=model,
                       records=records)
        except (KeyError, TypeError, ValueError) as err:
            raise ValueError(f"malformed frequency response in {str(path)!r}: {err}") from None

    def to_csv(self, path) -> Path:
        """Per-point table: frequency_hz, amplitude_m, phase_rad, energy_j,
        contact_force_max_n, stable, floquet_max, newton_iterations, step_size (12
        significant digits)."""
        path = Path(path)
        names = ["frequency_hz", "amplitude_m", "phase_rad", "energy_j", "contact_force_max_n", "stable",
                 "floquet_max", "newton_iterations", "step_size"]
        cols = [self.frequency, self.amplitude, self.phase, self.energy, self.contact_force_max,
                self.stable.astype(int), self.floquet_max, self.newton_iterations, self.step_size]
        fmt = ["%.12g"] * 5 + ["%d", "%.12g", "%d", "%.6g"]
        table = np.column_stack(cols) if len(self) else np.empty((0, len(names)))
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savetxt(path, table, delimiter=",", fmt=fmt, comments="", header=",".join(names))
        return path

    def __repr__(self) -> str:
        if len(self) == 0:
            return f"FrequencyResponse(method={self.method!r}, empty, status={self.status!r})"
        f, a = self.peak()
        return (f"FrequencyResponse(method={self.method!r}, H={self.harmonics}, points={len(self)}, "
                f"frequency={self.frequency.min():.4g}..{self.frequency.max():.4g} Hz, peak {a:.3g} m at "
                f"{f:.4g} Hz, unstable points={int((~self.stable).sum())}, status={self.status!r})")


def _entry_point(spec: str):
    module, _, attr = spec.partition(":")
    return getattr(importlib.import_module(module), attr)
