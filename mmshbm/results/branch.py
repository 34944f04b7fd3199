"""Branch: the result of a backbone computation.

A :class:`Branch` is a struct of arrays, one entry per converged point, plus the status
saying why the branch stopped, the special points, and the metadata needed to redo the
run. Per-point time signals, contact force and harmonic content come from the solver
object that computed the branch (``branch.solver``), which knows the model.

Files. :meth:`Branch.save` writes one ``.npz`` archive: every array of the branch
(bit-identical on reload) plus one JSON string, ``metadata``, holding the model's
description, method, H, N, solver and continuation options, versions, status and special
points; models that their description cannot rebuild (user matrices) also store ``M`` and
``K``. :meth:`Branch.load` reads it back and, if asked, rebuilds the model and the solver,
so that time signals work again; :meth:`Branch.rerun` redoes the run from the file alone.
"""

from __future__ import annotations

import importlib
import logging
import platform
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.special_points import special_from_json, special_to_json
from .archive import read_archive, write_archive
from .family_points import amplitude_in_m, family_front, frequency_at, solve_at, warn_outside_front
from .models import _model_arrays, _model_from_arrays, rebuild_model  # noqa: F401 - rebuild_model is public here

__all__ = ["Branch", "rebuild_model", "read_archive", "write_archive"]

log = logging.getLogger(__name__)

#: the ``format`` entry of a saved branch, and the layout version of the file
BRANCH_FORMAT = "mmshbm.Branch"
FORMAT_VERSION = 1
#: per-point arrays of a branch, in file order
ARRAY_FIELDS = ("frequency", "amplitude", "energy", "contact_force_max", "newton_iterations", "step_size",
                "states")


@dataclass(eq=False)
class Branch:
    """A computed nonlinear mode (backbone curve).

    Attributes
    ----------
    frequency : ndarray, shape (n_points,)
        Oscillation frequency (Hz).
    amplitude : ndarray, shape (n_points,)
        Largest excursion (m) of the contact DOF away from the stop over a period.
    energy : ndarray, shape (n_points,)
        Mechanical energy (J) (period average of kinetic + potential energy).
    contact_force_max : ndarray, shape (n_points,)
        Largest contact force (N) over a period.
    newton_iterations : ndarray of int, shape (n_points,)
        Corrector iterations per point.
    step_size : ndarray, shape (n_points,)
        Arclength step (scaled units) that led to each point.
    states : ndarray, shape (n_points, n_unknowns)
        The solver's scaled unknowns per point (for MMS-HBM: contact-DOF cosine
        coefficients and Ω); ``solver`` turns them into signals.
    status : str
        Why the branch stopped ("bound:amplitude" is a normal end).
    method : str
        "mmshbm", "penalty" or "shooting".
    harmonics : int
        H (0 for shooting).
    special_points : list of SpecialPoint
        Named points (:mod:`mmshbm.core.special_points`): pairs ``(kind, index)`` with a
        ``data`` dict; kinds "start", "grazing", "fold", "branch_point",
        "internal_resonance", "jump", bound hits, "endpoint".
    metadata : dict
        Model description, solver options, versions, timings.
    solver : object
        The problem object that computed the branch (not saved; :meth:`attach_solver`
        rebuilds it, and the per-point methods do so on demand).
    residual_histories : list of ndarray
        Corrector residual norms per Newton iteration, per point.
    model : Model or None
        The structure, when known without the solver (e.g. loaded from a file that stores
        its matrices); :meth:`get_model` returns it, building it if needed.
    records : dict of str to ndarray
        Further monitored quantities, one array per name with first axis n_points (e.g.
        shooting's ``floquet_max``); saved and loaded with the branch.
    """

    frequency: np.ndarray
    amplitude: np.ndarray
    energy: np.ndarray
    contact_force_max: np.ndarray
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
    def damping_ratio(self) -> np.ndarray:
        """Modal damping ratio ξ/(2Ω) per point of a damped nonlinear mode (method "epmc");
        zeros for a conservative backbone."""
        return np.asarray(self.records.get("damping_ratio", np.zeros(len(self))), dtype=float)

    @property
    def completed(self) -> bool:
        """True when the branch reached its bounds (status ``"bound:<name>"``); a run that
        ran out of steps (``"max_steps"``), of step size or failed is not completed."""
        return self.status.startswith("bound:")

    def check(self, thresholds=None, *, warn: bool = True) -> list:
        """Check what this branch is (family of its starting mode, contact admissibility,
        completeness): :func:`mmshbm.results.diagnostics.check_branch`. ``backbone``
        does it for every branch it returns; call it on loaded or older branches.

        Returns
        -------
        list of Finding
            Also stored in ``metadata["checks"]``; one :class:`~mmshbm.BranchWarning`
            each when ``warn``.
        """
        from .diagnostics import check_branch

        return check_branch(self, thresholds, warn=warn, stacklevel=3)

    @property
    def findings(self) -> list:
        """The findings of the last :meth:`check` (from ``metadata["checks"]``; empty when
        never checked)."""
        from .diagnostics import findings

        return findings(self)

    @property
    def gap(self) -> float | None:
        """The model's gap (m): of the attached model or solver, else from the metadata
        (``model_gap``, then the description's ``gap``); None when unknown."""
        model = self.model if self.model is not None else getattr(self.solver, "model", None)
        if model is not None:
            return float(model.gap)
        gap = self.metadata.get("model_gap", dict(self.metadata.get("model", {})).get("gap"))
        return None if gap is None else float(gap)

    # ------------------------------------------------------------------ per point
    def _require_solver(self):
        if self.solver is None:
            try:
                self.attach_solver()
            except ValueError as err:
                raise RuntimeError(f"this branch has no solver attached and none can be rebuilt: {err}") \
                    from None
        return self.solver

    # ------------------------------------------------------------------ model and solver
    def get_model(self):
        """The :class:`~mmshbm.model.Model` of this branch: the attached one, the solver's,
        or rebuilt from ``metadata["model"]`` (a beam's or oscillator's description) and
        cached in :attr:`model`.

        Raises
        ------
        ValueError
            If the description cannot rebuild the model and no model is attached.
        """
        if self.model is None and self.solver is not None and hasattr(self.solver, "model"):
            self.model = self.solver.model
        if self.model is None:
            self.model = rebuild_model(self.metadata.get("model", {}),
                                       self.metadata.get("model_gaps", self.metadata.get("model_gap")))
        return self.model

    def attach_solver(self, **method_options):
        """Rebuild the solver that computed this branch and attach it (:attr:`solver`).

        Uses :func:`mmshbm.methods.registry.make_problem` with the method and method options recorded in
        ``metadata`` (``method_options`` given here override them), on :meth:`get_model`.

        Returns
        -------
        object
            The solver (continuation problem), also stored in :attr:`solver`.

        Raises
        ------
        ValueError
            If the model cannot be rebuilt, or the rebuilt solver's unknowns do not match
            :attr:`states`.
        """
        make_problem = _entry_point("make_problem")
        options = {**dict(self.metadata.get("method_options", {})), **method_options}
        if self.method != "shooting":
            options.setdefault("harmonics", self.harmonics)
        solver = make_problem(self.get_model(), self.method, **options)
        n = getattr(solver, "n_unknowns", None)
        if n is not None and self.states.ndim == 2 and len(self) and self.states.shape[1] != n:
            raise ValueError(f"the rebuilt {self.method} solver has {n} unknowns but the branch's states "
                             f"have {self.states.shape[1]}: the options do not match the run")
        self.solver = solver
        return solver

    def rerun(self, **overrides) -> Branch:
        """Redo the run from the metadata alone (model, method, H, amplitudes, solver and
        continuation options); keyword arguments of :func:`mmshbm.backbone` override them.

        Returns
        -------
        Branch
            The new branch; with no overrides it repeats this one.
        """
        backbone = _entry_point("backbone")
        meta = self.metadata
        kwargs = {**dict(meta.get("continuation", {})), **dict(meta.get("method_options", {}))}
        kwargs.setdefault("harmonics", meta.get("harmonics", self.harmonics))
        for name in ("max_amplitude", "start_amplitude"):
            if name in meta:
                kwargs[name] = meta[name]
        kwargs["method"] = self.method
        kwargs.update(overrides)
        return backbone(self.get_model(), **kwargs)

    # ------------------------------------------------------------------ files
    def save(self, path) -> Path:
        """Write the branch to ``path`` (a ``.npz`` archive, written exactly there).

        The archive holds every per-point array (:data:`ARRAY_FIELDS`, bit-identical on
        reload), the residual histories, and ``metadata``: a JSON string with the format
        name and version, status, method, H, special points, the run's metadata (model
        description, method and continuation options, versions, timing), and the model's
        gap, contact DOF and stop side. When the model's description cannot rebuild it (a
        user :class:`~mmshbm.model.Model`, or a model whose matrices differ from its
        description's), ``M`` and ``K`` are stored too (CSR parts, ``model_M_data``, ...).

        Returns
        -------
        pathlib.Path
            The path written.
        """
        arrays, meta = branch_payload(self)
        meta = {"format": BRANCH_FORMAT, "format_version": FORMAT_VERSION, **meta,
                "saved_with": versions()}
        return write_archive(path, arrays, meta)

    @classmethod
    def load(cls, path, attach_solver: bool = False) -> Branch:
        """Read a branch written by :meth:`save`.

        Parameters
        ----------
        path : str or Path
            The ``.npz`` file.
        attach_solver : bool
            Also rebuild the model and solver now (otherwise the per-point methods do it
            on first use).

        Raises
        ------
        ValueError
            If the file is missing, unreadable, or not a saved branch.
        """
        arrays, meta = read_archive(path)
        if meta.get("format") != BRANCH_FORMAT:
            raise ValueError(f"{str(path)!r} is not a saved mmshbm Branch (format {meta.get('format')!r})")
        branch = branch_from_payload(arrays, meta)
        if attach_solver:
            branch.attach_solver()
        return branch

    def to_csv(self, path) -> Path:
        """Write the per-point table to ``path`` (CSV, one header line):
        ``frequency_hz, amplitude_m, energy_j, contact_force_max_n, newton_iterations,
        step_size``, then one column per one-dimensional numeric entry of :attr:`records`
        (e.g. ``mode_share``).

        Numbers are written as Python's ``repr`` of the float: the shortest text that
        reads back to the same double (``0.1``, not ``0.10000000000000001``), so the
        file round-trips exactly; integers as integers; ``nan``/``inf`` as such.

        Returns
        -------
        pathlib.Path
            The path written.
        """
        path = Path(path)
        n = len(self)
        names = ["frequency_hz", "amplitude_m", "energy_j", "contact_force_max_n", "newton_iterations",
                 "step_size"]
        cols = [self.frequency, self.amplitude, self.energy, self.contact_force_max, self.newton_iterations,
                self.step_size]
        for name, value in self.records.items():
            value = np.asarray(value)
            if value.ndim == 1 and len(value) == n and value.dtype.kind in "biuf":
                names.append(name)
                cols.append(value)
        cols = [np.asarray(c) for c in cols]
        cells = [[str(int(v)) for v in c] if c.dtype.kind in "biu" else [repr(float(v)) for v in c]
                 for c in cols]
        lines = [",".join(names)] + [",".join(row) for row in zip(*cells, strict=True)]
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("\n".join(lines) + "\n")
        return path

    def time_signals(self, point: int, dofs=None, n_samples: int = 256, *, admissible: bool = False):
        """Displacements of ``dofs`` over one period at branch point ``point``.

        Parameters
        ----------
        point : int
            Branch point index.
        dofs : sequence of int, optional
            Model DOFs (default all).
        n_samples : int
            Samples per period.
        admissible : bool
            False (default): the method's own signals (for harmonic balance the truncated
            Fourier series of every DOF, which may pass through the stop). True: the
            massless DOFs from the exact static contact problem driven by the Fourier
            motion of the DOFs with mass (no penetration; :mod:`mmshbm.contact.static`);
            the DOFs with mass are unchanged.

        Returns
        -------
        t : ndarray, shape (n_samples,)
            Time (s) over one period.
        q : ndarray, shape (len(dofs), n_samples)
            Displacements (m) / rotations (rad); all DOFs when ``dofs`` is None.
        """
        solver = self._require_solver()
        u = self.states[self._index(point)]
        if not admissible:
            return solver.time_signals(u, dofs, n_samples)
        t, q, _ = _entry_point("admissible_signals")(solver, u, n_samples)
        if dofs is not None:
            dofs = np.atleast_1d(np.asarray(dofs))
            if dofs.dtype.kind not in "iu" or np.any((dofs < -q.shape[0]) | (dofs >= q.shape[0])):
                raise ValueError(f"dofs must be integer indices in [0, {q.shape[0] - 1}], got {dofs}")
            q = q[dofs]
        return t, q

    def contact_force(self, point: int, n_samples: int = 256, *, admissible: bool = False):
        """Contact force λ(t) (N) over one period at ``point``: returns (t, λ).

        ``admissible=False``: the method's own force (for MMS-HBM the truncated series,
        which may pull); True: the exact static contact force driven by the DOFs with
        mass (λ >= 0, exactly 0 while the contact is open). λ has shape (n_samples,),
        or (n_contacts, n_samples) with several contacts when ``admissible``.
        """
        solver = self._require_solver()
        u = self.states[self._index(point)]
        if not admissible:
            return solver.contact_force(u, n_samples)
        t, _, lam = _entry_point("admissible_signals")(solver, u, n_samples)
        return t, (lam[0] if lam.shape[0] == 1 else lam)

    def harmonic_content(self, point: int, dof: int | None = None) -> np.ndarray:
        """Amplitudes √(c_k² + s_k²) of harmonics 0..H of ``dof`` (default the contact DOF)
        at ``point``; shape (H+1,)."""
        return self._require_solver().harmonic_content(self.states[self._index(point)], dof)

    def family_front(self) -> np.ndarray:
        """Indices of the points that make up the backbone of the starting mode's family:
        points on the family (``records["on_family"]``, all points when the branch has no
        such record) whose amplitude is at least every earlier family point's. Excursions
        into internal-resonance tongues, and the way back down a loop, are left out."""
        return family_front(self)

    def frequency_at(self, amplitude: float, *, unit: str = "m", interpolate: bool = False,
                     tol: float = 1e-10) -> float:
        """Frequency (Hz) of the backbone at ``amplitude`` (m, or gaps with ``unit="gap"``).

        By default the point is *solved*: Newton on the method's equations with the
        amplitude pinned (:func:`mmshbm.core.pinned.solve_at_amplitude`), started between
        the two neighbouring points of the family front (:meth:`family_front`), so the
        answer is the one a run refined onto that amplitude gives (to the Newton
        tolerance), not a secant between continuation points. NaN where the front does not
        reach the amplitude, or where the starting mode's family does not exist there
        (inside an internal-resonance tongue that the branch jumped or passed: see
        ``special_points``; :mod:`mmshbm.results.family_points`).

        Parameters
        ----------
        amplitude : float
            In m (``unit="m"``) or in multiples of the model's gap (``unit="gap"``).
        unit : {"m", "gap"}
            Unit of ``amplitude``.
        interpolate : bool
            Linear interpolation between the neighbouring front points instead (no solve;
            the 0.1 behaviour, with an error of the order of the curvature times the
            step).
        tol : float
            Newton tolerance of the solve.

        Warns
        -----
        BranchWarning
            When ``amplitude`` lies outside the amplitude range of the family front (the
            answer is then NaN): the message gives that range in m and in gaps.
        """
        a = amplitude_in_m(self, amplitude, unit)
        warn_outside_front(self, a)
        return frequency_at(self, a, interpolate=interpolate, tol=tol)

    def solve_at(self, amplitudes, *, unit: str = "m", tol: float = 1e-10) -> Branch:
        """The backbone's points at ``amplitudes`` (m, or gaps with ``unit="gap"``), solved
        on the family front (as :meth:`frequency_at`): a Branch with one point per
        amplitude and this branch's solver, so that ``time_signals``, ``contact_force`` and
        ``harmonic_content`` give the on-family orbits (the marked points of the plots).
        Where the front has no point at an amplitude, its stored point nearest in amplitude
        stands in (``records["solved"]`` is 0 there, 1 for solved points).
        """
        amps = [amplitude_in_m(self, a, unit) for a in np.atleast_1d(amplitudes)]
        return solve_at(self, amps, tol=tol)

    def _index(self, point: int) -> int:
        n = len(self)
        if isinstance(point, bool) or not isinstance(point, int | np.integer):
            raise TypeError(f"point must be an integer index, got {point!r}")
        if not -n <= point < n:
            raise IndexError(f"point {point} out of range for a branch of {n} points")
        return int(point) % n

    def __repr__(self) -> str:
        if len(self) == 0:
            return f"Branch(method={self.method!r}, empty, status={self.status!r})"
        return (f"Branch(method={self.method!r}, H={self.harmonics}, points={len(self)}, "
                f"frequency={self.frequency[0]:.4g}..{self.frequency[-1]:.4g} Hz, "
                f"amplitude up to {self.amplitude.max():.3g} m, status={self.status!r})")


#: The functions a branch calls to rebuild its solver and to redo its run. They live in
#: the methods layer above this module, which therefore never imports them statically:
#: like pickle, a branch finds them by their recorded names.
_ENTRY_POINTS = {"make_problem": "mmshbm.methods.registry:make_problem",
                 "backbone": "mmshbm.methods.backbone:backbone",
                 "admissible_signals": "mmshbm.contact.static:branch_signals"}


def _entry_point(name: str):
    module, _, attr = _ENTRY_POINTS[name].partition(":")
    return getattr(importlib.import_module(module), attr)


# ---------------------------------------------------------------------- payloads
def versions() -> dict:
    """Versions of Python and of the numerical packages (for file metadata)."""
    import numba
    import scipy

    from .. import __version__

    return {"mmshbm": __version__, "python": platform.python_version(), "numpy": np.__version__,
            "scipy": scipy.__version__, "numba": numba.__version__}


def branch_payload(branch: Branch, prefix: str = "") -> tuple[dict, dict]:
    """Split a branch into (arrays, JSON-able metadata) for an archive; array keys get
    ``prefix``."""
    arrays = {f"{prefix}{name}": np.asarray(getattr(branch, name)) for name in ARRAY_FIELDS}
    hist = [np.asarray(h, dtype=float).ravel() for h in branch.residual_histories]
    arrays[f"{prefix}residual_histories"] = np.concatenate(hist) if hist else np.empty(0)
    arrays[f"{prefix}residual_history_lengths"] = np.array([len(h) for h in hist], dtype=np.int64)
    names = []
    for name, value in dict(branch.records).items():
        if not isinstance(name, str) or not name:
            raise TypeError(f"record names must be non-empty strings, got {name!r}")
        arrays[f"{prefix}record__{name}"] = np.asarray(value)
        names.append(name)

    description = dict(branch.metadata.get("model", {}))
    model = branch.model if branch.model is not None else getattr(branch.solver, "model", None)
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
        gap = branch.metadata.get("model_gap", description.get("gap"))
        info["gap"] = None if gap is None else float(gap)
        if description.get("kind") not in ("TimoshenkoBeam", "OneDofOscillator"):
            log.warning("saving a branch whose model can neither be rebuilt from its description nor "
                        "was attached: the file cannot redo the run")
    meta = {"status": branch.status, "method": branch.method, "harmonics": int(branch.harmonics),
            "special_points": special_to_json(branch.special_points),
            "metadata": branch.metadata, "model": info, "records": names}
    return arrays, meta


def branch_from_payload(arrays: dict, meta: dict, prefix: str = "") -> Branch:
    """Inverse of :func:`branch_payload`."""
    try:
        fields_ = {name: arrays[f"{prefix}{name}"] for name in ARRAY_FIELDS}
        flat = arrays[f"{prefix}residual_histories"]
        lengths = arrays[f"{prefix}residual_history_lengths"]
        info = meta["model"]
        status, method, harmonics = meta["status"], meta["method"], int(meta["harmonics"])
        special = special_from_json(meta["special_points"])
        metadata = dict(meta["metadata"])
        records = {str(name): arrays[f"{prefix}record__{name}"] for name in meta.get("records", [])}
    except (KeyError, TypeError, ValueError) as err:
        raise ValueError(f"malformed branch record: missing or bad entry {err}") from None
    histories = np.split(flat, np.cumsum(lengths)[:-1]) if len(lengths) else []
    if info.get("gap") is not None and info["gap"] != metadata.get("model", {}).get("gap"):
        metadata["model_gap"] = info["gap"]  # Model.with_gap: the description's gap is stale
    if "contacts" in info and len(info["contacts"]) > 1:
        metadata["model_gaps"] = [float(c[1]) for c in info["contacts"]]
    model = _model_from_arrays({k[len(prefix):]: v for k, v in arrays.items() if k.startswith(prefix)},
                               info) if info.get("matrices") else None
    return Branch(**fields_, status=status, method=method, harmonics=harmonics, special_points=special,
                  metadata=metadata, residual_histories=list(histories), model=model, records=records)
