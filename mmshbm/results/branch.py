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

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from .._method_info import is_harmonic_balance
from .archive import read_archive, write_archive
from .base import FORMAT_VERSION, ResultBase, SolverSlot, entry_point, result_from_payload, result_payload
from .family_points import amplitude_in_m, family_front, frequency_at, solve_at, warn_outside_front
from .models import rebuild_model

if TYPE_CHECKING:
    from .orbits import OrbitsAt

__all__ = ["Branch", "rebuild_model", "read_archive", "write_archive", "FORMAT_VERSION"]

log = logging.getLogger(__name__)

#: the ``format`` entry of a saved branch
BRANCH_FORMAT = "mmshbm.Branch"
#: per-point arrays of a branch, in file order
ARRAY_FIELDS = ("frequency", "amplitude", "energy", "contact_force_max", "newton_iterations", "step_size",
                "states")


@dataclass(eq=False)
class Branch(ResultBase):
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
        The problem object that computed the branch (not saved): held when the branch
        was computed, else rebuilt on first access from the model and the options in the
        metadata (:meth:`attach_solver`; None when it cannot be).
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
    solver: object = SolverSlot()
    residual_histories: list = field(default_factory=list, repr=False)
    model: object = field(default=None, repr=False)
    records: dict = field(default_factory=dict, repr=False)

    FORMAT: ClassVar[str] = BRANCH_FORMAT
    ARRAY_FIELDS: ClassVar[tuple] = ARRAY_FIELDS
    _NOUN: ClassVar[str] = "branch"
    #: relative amplitude change below which a branch has not left its start: converged
    #: points of one orbit agree to the corrector's step tolerance (``step_tol``, 1e-8
    #: relative on the unknowns, which the amplitude follows), 100 times below this
    START_RTOL: ClassVar[float] = 1e-6

    @property
    def completed(self) -> bool:
        """True when the backbone reached one of its bounds (status ``"bound:<name>"``,
        amplitude or frequency) at a point of larger amplitude than its start.

        A backbone grows from its small start amplitude to its bound; one that reached a
        bound while coming back to its start (the amplitude's lower bound, 0) or that never
        left its start (last amplitude within :attr:`START_RTOL` of the first) did not
        cover its range, and is not completed; nor is one that ran out of steps
        (``"max_steps"``), of step size, or failed.
        """
        if not super().completed or len(self) < 2:
            return False
        first, last = float(self.amplitude[0]), float(self.amplitude[-1])
        return last - first > self.START_RTOL * max(abs(first), abs(last))

    @property
    def damping_ratio(self) -> np.ndarray:
        """Modal damping ratio ξ/(2Ω) per point of a damped nonlinear mode (method "epmc");
        zeros for a conservative backbone."""
        return np.asarray(self.records.get("damping_ratio", np.zeros(len(self))), dtype=float)

    @property
    def frequency_error(self) -> np.ndarray:
        """Estimated relative error of each point's frequency at its amplitude, shape
        (n_points,): ``records["frequency_error"]``, which a run with ``tol`` and
        :meth:`estimate_frequency_error` fill (:mod:`mmshbm.results.point_errors`); NaN
        where not estimated. ``records["harmonics"]`` holds the H of each point."""
        value = self.records.get("frequency_error")
        if value is None or len(value) != len(self):
            return np.full(len(self), np.nan)
        return np.asarray(value, dtype=float)

    def estimate_frequency_error(self) -> np.ndarray:
        """Estimate the truncation error of every point (one pinned re-solve at 2H per
        point, :mod:`mmshbm.results.point_errors`) and store it in
        ``records["frequency_error"]`` (and H in ``records["harmonics"]``).

        Returns
        -------
        ndarray, shape (n_points,)
            :attr:`frequency_error`.

        Raises
        ------
        ValueError
            For a method without harmonics.
        """
        from .point_errors import SolverLadder, estimate_point_errors

        if not is_harmonic_balance(self.method) or self.harmonics < 1:
            raise ValueError(f"a {self.method} branch has no harmonics to truncate")
        harmonics = np.asarray(self.records.get("harmonics", np.full(len(self), self.harmonics)), dtype=int)
        if np.any(harmonics != self.harmonics):
            raise ValueError("the points of this branch have their own H (a run with tol): its "
                             "frequency_error is already the estimate of each point at its H")
        self._require_solver()
        pe = estimate_point_errors(SolverLadder(self), harmonics, self.states, self.amplitude, self.frequency)
        self.records["frequency_error"] = pe.error
        self.records["harmonics"] = harmonics.astype(np.int64)
        return self.frequency_error

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

    def attach_solver(self, **method_options):
        """Rebuild the solver that computed this branch and attach it (:attr:`solver`):
        :func:`mmshbm.methods.registry.make_problem` with the method and method options
        recorded in ``metadata`` (``method_options`` given here override them), on
        :meth:`get_model`.

        Raises
        ------
        ValueError
            If the model cannot be rebuilt, or the rebuilt solver's unknowns do not match
            :attr:`states`.
        """
        return super().attach_solver(**method_options)

    def _build_solver(self, model, options: dict):
        if is_harmonic_balance(self.method):
            options.setdefault("harmonics", self.harmonics)
        return entry_point("make_problem")(model, self.method, **options)

    def rerun(self, **overrides) -> Branch:
        """Redo the run from the metadata alone (model, method, H, amplitudes, solver and
        continuation options); keyword arguments of :func:`mmshbm.backbone` override them.

        Returns
        -------
        Branch
            The new branch; with no overrides it repeats this one.
        """
        backbone = entry_point("backbone")
        meta = self.metadata
        kwargs = {**dict(meta.get("continuation", {})), **dict(meta.get("method_options", {}))}
        kwargs.setdefault("harmonics", meta.get("harmonics", self.harmonics))
        for name in ("max_amplitude", "start_amplitude"):
            if name in meta:
                kwargs[name] = meta[name]
        kwargs["method"] = self.method
        tolerance = meta.get("tolerance")
        if isinstance(tolerance, dict) and "harmonics" not in overrides:  # a run with tol: H chosen again
            kwargs.pop("harmonics", None)
            kwargs.update({k: tolerance[k] for k in ("tol", "start_harmonics", "max_harmonics", "patience",
                                                     "contraction") if k in tolerance})
        kwargs.update(overrides)
        return backbone(self.get_model(), **kwargs)

    # ------------------------------------------------------------------ files
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
        if not admissible:
            return super().time_signals(point, dofs, n_samples)
        solver = self._require_solver()
        t, q, _ = entry_point("admissible_signals")(solver, self.states[self._index(point)], n_samples)
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
        if not admissible:
            return super().contact_force(point, n_samples)
        solver = self._require_solver()
        t, _, lam = entry_point("admissible_signals")(solver, self.states[self._index(point)], n_samples)
        return t, (lam[0] if lam.shape[0] == 1 else lam)

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

        Notes
        -----
        Where several orbits of the starting mode's family coexist at the amplitude (past
        an internal resonance: a tongue's or a loop's beside the backbone, or one the
        continuation never visited), this is the backbone's, the one on the family front
        the continuation followed; :meth:`orbits_at` lists them all, the backbone's first.

        The answer is the branch's, at its H: how far the truncated Fourier series leaves
        it from the limit in H is estimated on demand by :meth:`truncation_error` (two
        re-solves of that amplitude at larger H).
        """
        a = amplitude_in_m(self, amplitude, unit)
        warn_outside_front(self, a)
        return frequency_at(self, a, interpolate=interpolate, tol=tol)

    def orbits_at(self, amplitude: float, unit: str = "m", *, search: bool = False,
                  tol: float = 1e-10) -> OrbitsAt:
        """Every orbit of the starting mode's family found at ``amplitude`` (m, or gaps
        with ``unit="gap"``), the backbone's first: :func:`mmshbm.results.orbits.orbits_at`.

        The backbone's orbit (the one :meth:`frequency_at` returns), then the other
        segments of this branch's path that cross the amplitude (tongues and loops,
        :mod:`mmshbm.results.coexisting`), solved there exactly; with ``search`` also the
        orbits a deflated Newton search at the pinned amplitude finds (starts: those
        orbits moved in frequency, the linear and closed-contact first modes scaled to the
        amplitude). An orbit other than the backbone's is listed when its fundamental
        holds at least half the kinetic energy (``orbits.FAMILY_SHARE``).

        Parameters
        ----------
        amplitude : float
            In m (``unit="m"``) or in multiples of the model's gap (``unit="gap"``).
        unit : {"m", "gap"}
            Unit of ``amplitude``.
        search : bool
            Also search for orbits the branch did not visit (harmonic balance only; a few
            dozen pinned Newton solves).
        tol : float
            Newton tolerance of the solves.

        Returns
        -------
        OrbitsAt
            A sequence of :class:`~mmshbm.results.orbits.Orbit` (``.frequency`` Hz,
            ``.fundamental_share``, ``.state``, ``.amplitude`` m, ``.source``); empty with
            a ``reason`` (and a BranchWarning) where the amplitude lies outside the
            branch's points.
        """
        from .orbits import orbits_at

        return orbits_at(self, amplitude_in_m(self, amplitude, unit), search=search, tol=tol)

    def solve_at(self, amplitudes, *, unit: str = "m", tol: float = 1e-10, stand_in: bool = False) -> Branch:
        """The backbone's points at ``amplitudes`` (m, or gaps with ``unit="gap"``), solved
        on the family front (as :meth:`frequency_at`): a Branch with one point per
        amplitude and this branch's solver, so that ``time_signals``, ``contact_force`` and
        ``harmonic_content`` give the on-family orbits (the marked points of the plots).

        Parameters
        ----------
        amplitudes : float or sequence of float
            In m (``unit="m"``) or in multiples of the model's gap (``unit="gap"``).
        unit : {"m", "gap"}
            Unit of ``amplitudes``.
        tol : float
            Newton tolerance of the solves.
        stand_in : bool
            False (default): where the front has no point at an amplitude (beyond its
            ends, where :meth:`frequency_at` is NaN, or inside a tongue the branch jumped),
            the entry is NaN, as :meth:`frequency_at` answers there. True: the front's
            stored point nearest in amplitude stands in (what a plot marks), without a
            warning.

        Returns
        -------
        Branch
            ``records["requested_amplitude"]`` (m) the amplitudes asked for,
            ``records["solved"]`` 1 for solved points and 0 for NaN entries or stand-ins.

        Warns
        -----
        BranchWarning
            Without ``stand_in``, once when some amplitude has no backbone point: the
            message names them and the front's range in m and in gaps.
        """
        amps = [amplitude_in_m(self, a, unit) for a in np.atleast_1d(amplitudes)]
        return solve_at(self, amps, tol=tol, stand_in=stand_in)

    def truncation_error(self, amplitude: float, *, unit: str = "m", factors=(2, 4), rate: float = 1.0,
                         tol: float = 1e-10):
        """Estimated relative error of :meth:`frequency_at` at ``amplitude`` (m, or gaps with
        ``unit="gap"``) from the truncation of the Fourier series: the same amplitude
        re-solved at 2H and 4H and extrapolated with the measured algebraic rate
        (:func:`mmshbm.results.truncation.truncation_error`, which states the method and its
        assumptions). On demand only: two pinned solves at larger H.

        Returns
        -------
        TruncationEstimate
            ``.error`` (relative), ``.frequency`` at each H, ``.rate``, ``.limit`` (Hz),
            ``.asymptotic``, ``.note``; ``float(estimate)`` is ``.error``.
        """
        from .truncation import truncation_error

        a = amplitude_in_m(self, amplitude, unit)
        return truncation_error(self, a, factors=factors, rate=rate, tol=tol)

    def __repr__(self) -> str:
        if len(self) == 0:
            return f"Branch(method={self.method!r}, empty, status={self.status!r})"
        return (f"Branch(method={self.method!r}, H={self.harmonics}, points={len(self)}, "
                f"frequency={self.frequency[0]:.4g}..{self.frequency[-1]:.4g} Hz, "
                f"amplitude up to {self.amplitude.max():.3g} m, status={self.status!r})")


# ---------------------------------------------------------------------- payloads
def branch_payload(branch: Branch, prefix: str = "") -> tuple[dict, dict]:
    """Split a branch into (arrays, JSON-able metadata) for an archive (a study's file holds
    several); array keys get ``prefix``."""
    return result_payload(branch, prefix)


def branch_from_payload(arrays: dict, meta: dict, prefix: str = "") -> Branch:
    """Inverse of :func:`branch_payload`."""
    return result_from_payload(Branch, arrays, meta, prefix)
