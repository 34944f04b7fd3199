"""The continuation driver's protocol, options and results (:mod:`mmshbm.core.continuation`)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from .. import _validate as check
from .problem import ContinuationProblem
from .status import Status

__all__ = ["ContinuationOptions", "ContinuationProblem", "ContinuationResult", "ContinuationState"]


@dataclass(frozen=True)
class ContinuationOptions:
    """Options of the path follower (scaled arclength units). Validated on creation.

    Attributes
    ----------
    ds, ds_min, ds_max : float
        Initial, smallest and largest arclength step.
    max_steps : int
        Largest number of continuation steps (points after the first).
    newton_tol : float
        Convergence: infinity norm of the scaled residual.
    step_tol : float
        Convergence also when the scaled Newton update's infinity norm falls below
        this while the residual is below √newton_tol: where the residual has a
        round-off floor (near a pole of the condensed stiffness, kΩ close to an
        eigenfrequency of the clamped-contact structure) the iterate is then known to
        ``step_tol``.
    max_newton : int
        Newton iterations per corrector before the step counts as failed.
    step_control : {"auto", "residual", "effort"}
        ``"auto"`` (default): the problem's ``step_control`` attribute if it has one (MMS-HBM:
        ``"residual"``), else ``"effort"``. ``"residual"``: a second-order predictor
        (tangent plus the curvature of
        the last step) and the next step from the residual r₀ at the predictor, which
        measures the predictor's error: ds ← ds·(target_residual/r₀)^(1/3), within
        [ds/2, 1.5 ds]; Newton then typically needs two iterations. ``"effort"``: the tangent
        predictor and ds *= 1 + growth·((max_newton − nit)/max_newton)² (mmshbm 0.1; the
        same branches point for point; the right rule for stiff residuals such as
        penalty-HBM's, whose size at the predictor says little about the step).
    target_residual : float
        r₀ aimed at by ``step_control="residual"`` (scaled residual at the predictor).
    growth : float
        ``a`` in ds *= 1 + a·((max_newton − nit)/max_newton)².
    max_angle : float
        Largest angle (rad) between consecutive tangents; more means the step jumped.
    corner_ds : float
        Below this step the angle test is waived: the sampled (AFT) contact residual is
        piecewise smooth, so where a sample point changes its active set the branch
        has a genuine corner that no step size removes.
    branch_point_ds : float or None
        Longest step on which the sign of det [J; t] may change. The sign changes where
        the step crosses a branch point, and also where a step longer than a fold's
        radius of curvature jumps across the fold onto the piece beyond it (a thin Z of
        two close folds): that piece runs the other way, so the tangent, oriented along
        the old one, turns the branch back at the fold and retraces the points already
        found. A step that changes the sign and is longer than this is retried at half
        length, down to this length; there a branch point is accepted. None (the
        default): every change is accepted on the step that finds it.
        ``mmshbm.frequency_response`` sets it (a forced response has no symmetry that
        makes branch points generic).
    bounds : Mapping[str, tuple[float, float]]
        Stop when a monitored quantity leaves [lo, hi]; the last point is refined onto
        the bound. E.g. ``{"amplitude": (0, 1e-2), "frequency": (0, 80)}``.
    follow : {"family", "path"}
        ``"family"`` (default): stay on the starting mode's family, jumping over
        internal-resonance tongues the path follower cannot come back from; ``"path"``:
        plain path following (to study a tongue). The driver itself only ever follows
        the path: the family following is an event plug-in that the methods' runs pass
        to it (:func:`mmshbm.family.follower.default_events`; it acts on problems that
        record the fundamental harmonic's share).
    family_share, max_excursion, jump_step, max_jumps
        The family following's options, read by the plug-in
        (:meth:`mmshbm.family.options.FamilyOptions.of`); checked here as plain numbers.
    """

    ds: float = 0.1
    ds_min: float = 1e-7
    ds_max: float = 2.0
    max_steps: int = 1000
    newton_tol: float = 1e-10
    step_tol: float = 1e-8
    max_newton: int = 10
    growth: float = 0.5
    step_control: str = "auto"
    target_residual: float = 1e-3
    max_angle: float = math.radians(30.0)
    corner_ds: float = 1e-4
    branch_point_ds: float | None = None
    bounds: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    follow: str = "family"
    family_share: float = 0.5
    max_excursion: int = 60
    jump_step: float = 0.02
    max_jumps: int = 50

    def __post_init__(self):
        ds_min = check.positive("ds_min", self.ds_min)
        ds = check.positive("ds", self.ds)
        ds_max = check.positive("ds_max", self.ds_max)
        if not ds_min <= ds <= ds_max:
            raise ValueError(f"need ds_min <= ds <= ds_max, got {ds_min} <= {ds} <= {ds_max}")
        check.integer("max_steps", self.max_steps, minimum=1)
        check.positive("newton_tol", self.newton_tol)
        check.positive("step_tol", self.step_tol)
        check.integer("max_newton", self.max_newton, minimum=1)
        check.positive("corner_ds", self.corner_ds)
        if self.branch_point_ds is not None:
            check.positive("branch_point_ds", self.branch_point_ds)
        check.non_negative("growth", self.growth)
        if self.step_control not in ("auto", "residual", "effort"):
            raise ValueError(f"step_control must be 'auto', 'residual' or 'effort', "
                             f"got {self.step_control!r}")
        check.positive("target_residual", self.target_residual)
        if self.follow not in ("family", "path"):
            raise ValueError(f"follow must be 'family' or 'path', got {self.follow!r}")
        share = check.real_number("family_share", self.family_share)
        if not 0.0 < share < 1.0:
            raise ValueError(f"family_share must be in (0, 1), got {self.family_share!r}")
        check.integer("max_excursion", self.max_excursion, minimum=1)
        check.positive("jump_step", self.jump_step)
        check.integer("max_jumps", self.max_jumps, minimum=0)
        angle = check.positive("max_angle", self.max_angle)
        if angle > math.pi:
            raise ValueError(f"max_angle must be <= pi, got {angle}")
        for name, bound in dict(self.bounds).items():
            try:
                lo, hi = (float(b) for b in bound)
            except (TypeError, ValueError):
                raise ValueError(f"bounds[{name!r}] must be a pair (lo, hi), got {bound!r}") from None
            if not lo < hi:
                raise ValueError(f"bounds[{name!r}] must satisfy lo < hi, got {bound!r}")


@dataclass
class ContinuationResult:
    """The converged points of a branch and why it stopped.

    Attributes
    ----------
    u : ndarray, shape (n_points, n)
        Scaled unknowns per point.
    records : dict[str, ndarray]
        Monitored quantities per point (each shape (n_points,) or (n_points, ...)).
    newton_iterations : ndarray of int, shape (n_points,)
    step_size : ndarray, shape (n_points,)
        Arclength step that led to each point (0 for the first).
    residual_histories : list of ndarray
        Corrector residual norms per Newton iteration, per point.
    special_points : list of (str, int)
        ("start", 0), ("fold", i), bound hits, and ("endpoint", last).
    status : Status
        Why the branch stopped (:class:`~mmshbm.core.status.Status`, a str):
        "max_steps", "bound:<name>", "ds_min: ...", "jump failed: ...", "family ended: ...",
        "interrupted", "start failed: ...", "start outside bounds".
    tangent : ndarray, shape (n,) or None
        Unit tangent at the last point (None if no point converged).
    next_ds : float
        The step the driver would have tried next.
    steps : int
        Continuation steps taken (points after the first).
    """

    u: np.ndarray
    records: dict
    newton_iterations: np.ndarray
    step_size: np.ndarray
    residual_histories: list
    special_points: list
    status: Status
    tangent: np.ndarray | None = None
    next_ds: float = math.nan
    steps: int = 0


@dataclass
class ContinuationState:
    """Everything the driver needs to go on from its last accepted point, as if it had
    never stopped (what a checkpoint file stores; see :mod:`mmshbm.core.checkpoint`).

    Attributes
    ----------
    u : list of ndarray, each shape (n,)
        Scaled unknowns of the points so far.
    records : list of dict
        Monitored quantities per point.
    newton_iterations : list of int
    step_size : list of float
    residual_histories : list of ndarray
    special_points : list of (str, int)
        Special points so far (no "endpoint").
    tangent : ndarray, shape (n,)
        Unit tangent at the last point.
    previous_tangent : ndarray, shape (n,), optional
        Unit tangent at the point before (the second-order predictor's curvature).
    ds : float
        The step to try next.
    steps : int
        Continuation steps taken so far.
    """

    u: list
    records: list
    newton_iterations: list
    step_size: list
    residual_histories: list
    special_points: list
    tangent: np.ndarray
    ds: float
    steps: int
    previous_tangent: np.ndarray | None = None
