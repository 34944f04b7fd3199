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

from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

import numpy as np

from .base import FORMAT_VERSION, ResultBase, SolverSlot, entry_point

__all__ = ["FrequencyResponse", "FORMAT_VERSION"]


def _rms(q: np.ndarray) -> float:
    """Root mean square of one period of uniform samples."""
    return float(np.sqrt(np.mean(q * q)))

RESPONSE_FORMAT = "mmshbm.FrequencyResponse"
#: per-point arrays, in file order
ARRAY_FIELDS = ("frequency", "amplitude", "phase", "energy", "contact_force_max", "stable", "floquet_max",
                "newton_iterations", "step_size", "states")


@dataclass(eq=False)
class FrequencyResponse(ResultBase):
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
    solver : object
        The forced-response problem that computed it (not saved): held when computed,
        else rebuilt on first access from the model and the excitation in the metadata.
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
    solver: object = SolverSlot()
    residual_histories: list = field(default_factory=list, repr=False)
    model: object = field(default=None, repr=False)
    records: dict = field(default_factory=dict, repr=False)

    FORMAT: ClassVar[str] = RESPONSE_FORMAT
    ARRAY_FIELDS: ClassVar[tuple] = ARRAY_FIELDS
    _NOUN: ClassVar[str] = "response"

    @property
    def completed(self) -> bool:
        """True when the response reached the end of its frequency range: status kind
        "bound" with the last point nearer f_end than f_start (``metadata["frequency_range"]``;
        without it, the status alone). False when it ran out of steps (``"max_steps"``) or of
        step size (``"ds_min"``), failed, or turned back at a fold and left at f_start."""
        if not super().completed:
            return False
        frange = self.metadata.get("frequency_range")
        if frange is None or not len(self):
            return True
        f, (f0, f1) = float(self.frequency[-1]), frange
        return abs(f - f1) <= abs(f - f0)

    @property
    def amplitude_error(self) -> np.ndarray:
        """Estimated relative error of each point's amplitude at its frequency, shape
        (n_points,): ``records["amplitude_error"]``, filled by a run with ``tol``
        (:mod:`mmshbm.methods.adaptive_forced`); NaN where not estimated.
        ``records["harmonics"]`` holds the H of each point."""
        return self._record_or_nan("amplitude_error")

    @property
    def frequency_error(self) -> np.ndarray:
        """Estimated relative error of each point's frequency at its amplitude, shape
        (n_points,): ``records["frequency_error"]`` (a run with ``tol``); NaN where not
        estimated. One of the two errors is measured at a point (``records["error_pinned"]``:
        0 the amplitude, 1 this one, near folds); the other follows from the slope."""
        return self._record_or_nan("frequency_error")

    def _record_or_nan(self, name: str) -> np.ndarray:
        value = self.records.get(name)
        if value is None or len(value) != len(self):
            return np.full(len(self), np.nan)
        return np.asarray(value, dtype=float)

    @property
    def findings(self) -> list:
        """The findings stored with the response (``metadata["checks"]``: the
        ``"tolerance_not_met"`` finding of a run with ``tol``); empty otherwise."""
        from .findings import Finding

        return [Finding.from_dict(d) for d in self.metadata.get("checks", [])]

    def peak(self) -> tuple[float, float]:
        """(frequency (Hz), amplitude (m)) of the largest amplitude on the response."""
        i = int(np.argmax(self.amplitude))
        return float(self.frequency[i]), float(self.amplitude[i])

    # ------------------------------------------------------------------ measures per DOF
    @property
    def angular_frequency(self) -> np.ndarray:
        """Excitation frequency Ω = 2π f (rad/s), shape (n_points,)."""
        return 2 * np.pi * np.asarray(self.frequency, dtype=float)

    def rms(self, dof: int | None = None) -> np.ndarray:
        """Root mean square over the period of DOF ``dof`` (default the amplitude DOF; m or
        rad), shape (n_points,): sqrt(c_0² + ½ Σ_k (a_k² + b_k²)) of its series (the sample
        mean of q² over more than 2H uniform samples is exact for degree H; shooting: its
        samples)."""
        return np.array([_rms(q) for q in self._signals(dof)])

    def peak_amplitude(self, dof: int | None = None) -> np.ndarray:
        """Largest |q(t)| over the period of DOF ``dof`` (default the amplitude DOF; m or
        rad), refined by a parabola through the sampled peak, shape (n_points,). For the
        amplitude DOF of a model with friction or several contacts this is ``amplitude``."""
        from ..core.measures import refined_max

        return np.array([max(refined_max(q), refined_max(-q)) for q in self._signals(dof)])

    def phase_of(self, dof: int | None = None) -> np.ndarray:
        """Lag (rad) of the fundamental harmonic of DOF ``dof`` (default the amplitude DOF)
        behind the excitation, in [−π/2, 3π/2) (π/2 at phase resonance), shape (n_points,)."""
        ref = self._excitation_reference()
        out = np.empty(len(self))
        for i, q in enumerate(self._signals(dof)):
            n = len(q)
            q1 = 2.0 / n * np.sum(q * np.exp(-2j * np.pi * np.arange(n) / n))  # a_1 − i b_1
            lag = np.angle(ref) - np.angle(q1)
            out[i] = (lag + 0.5 * np.pi) % (2 * np.pi) - 0.5 * np.pi
        return out

    def _signals(self, dof: int | None) -> list:
        """One period of DOF ``dof`` per point (samples at τ_j = 2πj/n), from the solver."""
        from ..core.measures import check_dof

        solver = self._require_solver()
        model = solver.model
        dof = check_dof(dof, model.n_dof, model.amplitude_dof)
        H = self.harmonics
        n = None if H == 0 else max(256, 2 ** int(np.ceil(np.log2(8 * (2 * H + 1)))))
        out = []
        for u in self.states:
            _, q = solver.time_signals(u, [dof]) if n is None else solver.time_signals(u, [dof], n)
            out.append(np.asarray(q[0], dtype=float))
        return out

    def _excitation_reference(self) -> complex:
        solver = self._require_solver()
        exc = getattr(solver, "excitation", None)
        if exc is not None:
            return complex(exc.reference)
        try:  # the excitation's JSON record (Excitation.to_json)
            re_, im_ = self.metadata["excitation"]["reference"]
        except (KeyError, TypeError, ValueError) as err:
            raise RuntimeError(f"this response records no excitation phase reference: {err}") from None
        return complex(float(re_), float(im_))

    # ------------------------------------------------------------------ solver
    def _build_solver(self, model, options: dict):
        make = entry_point("make_forced_problem")
        return make(model, self.metadata["excitation"], self.method, self.harmonics, options)

    def floquet_multipliers(self, point: int) -> np.ndarray:
        """All Floquet multipliers at ``point`` (stored, or computed by the solver)."""
        if "floquet" in self.records:
            return np.asarray(self.records["floquet"][self._index(point)])
        return self._require_solver().floquet_multipliers(self.states[self._index(point)])

    # ------------------------------------------------------------------ files
    def to_csv(self, path) -> Path:
        """Per-point table: frequency_hz, amplitude_m, phase_rad, energy_j,
        contact_force_max_n, stable, floquet_max, newton_iterations, step_size (12
        significant digits); a run with ``tol`` adds amplitude_error, frequency_error and
        harmonics."""
        path = Path(path)
        names = ["frequency_hz", "amplitude_m", "phase_rad", "energy_j", "contact_force_max_n", "stable",
                 "floquet_max", "newton_iterations", "step_size"]
        cols = [self.frequency, self.amplitude, self.phase, self.energy, self.contact_force_max,
                self.stable.astype(int), self.floquet_max, self.newton_iterations, self.step_size]
        fmt = ["%.12g"] * 5 + ["%d", "%.12g", "%d", "%.6g"]
        if "harmonics" in self.records and "amplitude_error" in self.records:
            names += ["amplitude_error", "frequency_error", "harmonics"]
            cols += [self.amplitude_error, self.frequency_error, np.asarray(self.records["harmonics"])]
            fmt += ["%.6g", "%.6g", "%d"]
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

