"""The continuation problem protocol: what the path follower asks of a problem.

The driver (:func:`mmshbm.core.continuation.continue_branch`) follows the solution curve
of n−1 equations in n unknowns. It needs only the small required protocol
:class:`ContinuationProblem`; everything else a problem can offer is a named
*capability*, declared on :class:`ContinuationProblemBase` with a default that means "not
offered" (``None``, or the plain rule), so that the driver, the family events and the
runners call them directly and never probe a problem for attributes.

**Required** (:class:`ContinuationProblem`):

``n_unknowns : int``
    n, the number of scaled unknowns u (the last one is usually the frequency).
``residual(u) -> R``
    The scaled residual R(u), shape (n−1,).
``residual_and_jacobian(u) -> (R, J)``
    The same R(u) and its Jacobian J = ∂R/∂u, shape (n−1, n), a dense ndarray or a
    scipy.sparse matrix. Numerical failures in either raise ArithmeticError, ValueError,
    RuntimeError or LinAlgError (the step then fails and is retried smaller; never the
    run).
``monitor(u) -> dict``
    The recorded quantities of a converged point (name -> float or array): what bounds
    act on and what the branch stores.

**Capabilities** (declared on :class:`ContinuationProblemBase`):

:class:`StepControl`
    ``step_control`` (``"effort"`` or ``"residual"``: the step rule that
    ``ContinuationOptions(step_control="auto")`` picks); ``fast_newton(u0, u_pred,
    tangent, tol, max_iter, step_tol)``, a compiled corrector returning (u, iterations,
    history, J) or None to let the Python loop run; ``solved_tangent(J, t)``, the raw
    tangent x of [J; tᵀ] x = e_n and the sign of that determinant when that corrector
    already solved it for the J it returned (None otherwise); ``measure``, the record
    whose relative change caps the arclength step (None: only ``ds_max``);
    ``progress_records``, the records a progress bar shows; ``corner_parameter``, True for
    a nonsmooth branch whose corners are crossed at fixed parameter (the last unknown),
    e.g. stick arcs of friction that vanish between two frequencies.
:class:`PinnedSolves`
    ``amplitude_and_gradient(u) -> (A, ∇A)`` and ``amplitude_value(u) -> A`` for Newton
    with the amplitude pinned (:mod:`mmshbm.core.pinned`); None: the amplitude is
    differenced from ``monitor(u)["amplitude"]``.
:class:`FamilyEvents`
    What the search for the family beyond a frontier uses (:mod:`mmshbm.family`):
    ``frequency_of(u)`` (Hz, no evaluation), ``family_frequency_limit()`` (Hz, where the
    starting mode's backbone tends far above the gaps),
    ``family_frequency_ceiling()`` (Hz, the first mode with every contact held: the top
    of the family's frequency band; the limit when not offered),
    ``scaled_state(u, factor)``, ``family_predictor(u_from, A_from, A_to, A_max)``,
    ``family_landing(u_from, rec_from, excursion, A_max, A_min, family_share=)``,
    ``harmonic_landing(A, A_max, tol=, max_iter=, admissible=, fundamental=) -> (u, share_ref)``
    (None where ``fundamental=True`` names no ladder of its own),
    ``homotopy_landing(A, A_max, tol=, max_iter=, admissible=) -> (u, f_start)`` (the orbit
    reached by a homotopy from another family's orbit of frequency f_start, Hz:
    :mod:`mmshbm.core.homotopy`), ``leads_fundamental(u) -> bool`` (the starting mode
    holds the largest share of the fundamental harmonic's kinetic energy among the
    tracked modes), and ``family_starts()``, the object that supplies the starts of the
    deflated search (:class:`mmshbm.family.deflation.FamilyStarts`; MMS-HBM's adds the
    filtered passage, the predictor and the scaled orbit). Each is None when not offered.
:class:`AmplitudeStart` (backbones, :class:`BackboneProblemBase`)
    ``linear_mode_point(amplitude)`` (the linear mode at that amplitude, m),
    ``initial_tangent()``, ``open_amplitude()`` (the amplitude at which the linear mode
    first reaches a stop; None when not offered).
:class:`FrequencyStart` (forced responses, :class:`ForcedProblemBase`)
    ``linear_response_point(frequency)`` (the linear response at that frequency, Hz),
    ``start_point(frequency)`` (a converged first point; default the linear response),
    ``initial_tangent()``.
:class:`BranchRecords`
    ``branch_records(states) -> dict`` (records computed once for a whole branch; None
    when not offered), ``tracked_frequencies`` (Hz of the modes whose energy shares are
    recorded; None), ``H`` and ``N`` (harmonics and samples; 0 where they do not apply),
    ``setting_names`` and ``solver_settings()`` (the attributes, and their numbers, that
    fix the discretisation, for checkpoints), ``state_convention()`` (how the states are to
    be read, e.g. the scaling of extra unknowns; empty by default).

A problem that only has the required protocol (a test problem, a user's) goes through
:func:`as_problem`, which wraps it in a :class:`ContinuationProblemBase` with every
capability at its default; capabilities are offered by subclassing the base.

``evaluate(u, jacobian=True)``, the one method that was both (R alone, or the pair
(R, J) with ``jacobian``), stays on the base as a thin wrapper of the two. A problem that
defines only ``evaluate`` (:class:`EvaluateProblem`, the earlier protocol) still works:
the base's ``residual`` and ``residual_and_jacobian`` then call it, and
:func:`as_problem` wraps a plain object that has only ``evaluate``.

``linear_point`` is the name both starts had before they were told apart: it stays as a
thin alias, of ``linear_mode_point`` on backbone problems and of
``linear_response_point`` on forced ones.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol, runtime_checkable

import numpy as np

__all__ = ["AmplitudeStart", "BackboneProblemBase", "BranchRecords", "ContinuationProblem",
           "ContinuationProblemBase", "EvaluateProblem", "FamilyEvents", "ForcedProblemBase",
           "FrequencyStart", "OneEvaluation", "PinnedSolves", "StepControl", "as_problem"]


@runtime_checkable
class ContinuationProblem(Protocol):
    """What the driver needs from every problem (all vectors in scaled units)."""

    n_unknowns: int

    def residual(self, u: np.ndarray) -> np.ndarray:
        """The scaled residual R(u), shape (n−1,)."""

    def residual_and_jacobian(self, u: np.ndarray) -> tuple[np.ndarray, Any]:
        """(R, J): R(u) (n−1,) and J = ∂R/∂u (n−1, n), a dense ndarray or scipy.sparse."""

    def monitor(self, u: np.ndarray) -> dict:
        """Scalar quantities recorded per point (e.g. frequency, amplitude, energy)."""


@runtime_checkable
class EvaluateProblem(Protocol):
    """The earlier required protocol: one ``evaluate`` for R and (R, J).
    :func:`as_problem` still takes a problem that has only this."""

    n_unknowns: int

    def evaluate(self, u: np.ndarray, jacobian: bool = True):
        """R(u) (n−1,), or with ``jacobian`` the pair (R, J), J (n−1, n)."""

    def monitor(self, u: np.ndarray) -> dict:
        """Scalar quantities recorded per point."""


@runtime_checkable
class StepControl(Protocol):
    """The step rule and corrector a problem asks for."""

    step_control: str
    fast_newton: Callable[..., tuple | None] | None
    solved_tangent: Callable[[Any, np.ndarray], tuple[np.ndarray, float] | None] | None
    measure: str | None
    progress_records: tuple[str, ...]
    corner_parameter: bool


@runtime_checkable
class PinnedSolves(Protocol):
    """The amplitude A(u) and its gradient, for solves with the amplitude pinned."""

    amplitude_and_gradient: Callable[[np.ndarray], tuple[float, np.ndarray]] | None
    amplitude_value: Callable[[np.ndarray], float] | None


@runtime_checkable
class FamilyEvents(Protocol):
    """The starts and the frequency band of the search for the family beyond a frontier."""

    frequency_of: Callable[[np.ndarray], float] | None
    family_frequency_limit: Callable[[], float] | None
    family_frequency_ceiling: Callable[[], float] | None
    scaled_state: Callable[[np.ndarray, float], np.ndarray] | None
    family_predictor: Callable[[np.ndarray, float, float, float], np.ndarray] | None
    family_landing: Callable[..., tuple[np.ndarray, float]] | None
    harmonic_landing: Callable[..., tuple[np.ndarray, float] | None] | None
    homotopy_landing: Callable[..., tuple[np.ndarray, float]] | None
    leads_fundamental: Callable[[np.ndarray], bool] | None
    family_starts: Callable[[], Any] | None


@runtime_checkable
class AmplitudeStart(Protocol):
    """A backbone's start: the linear mode at a given amplitude."""

    open_amplitude: Callable[[], float] | None

    def linear_mode_point(self, amplitude: float) -> np.ndarray: ...

    def initial_tangent(self) -> np.ndarray: ...


@runtime_checkable
class FrequencyStart(Protocol):
    """A forced response's start: a point at a given excitation frequency."""

    def linear_response_point(self, frequency: float) -> np.ndarray: ...

    def start_point(self, frequency: float) -> np.ndarray: ...

    def initial_tangent(self) -> np.ndarray: ...


@runtime_checkable
class BranchRecords(Protocol):
    """What the runners read after the continuation."""

    branch_records: Callable[[np.ndarray], dict] | None
    tracked_frequencies: Any
    H: int
    N: int
    setting_names: tuple[str, ...]

    def solver_settings(self) -> dict: ...

    def state_convention(self) -> dict: ...



class OneEvaluation:
    """Mixin of a problem whose residual and Jacobian come from one routine,
    ``_evaluate(u, jacobian) -> R | (R, J)``, that shares its intermediate results (the
    condensed stiffness, the projection) between the two: :meth:`residual` and
    :meth:`residual_and_jacobian` call it. Put it first among the bases."""

    def residual(self, u: np.ndarray) -> np.ndarray:
        """The scaled residual R(u), shape (n_unknowns − 1,) (see ``_evaluate``)."""
        return self._evaluate(u, False)

    def residual_and_jacobian(self, u: np.ndarray):
        """(R, J): the scaled residual and J = ∂R/∂u, shape (n_unknowns − 1, n_unknowns)
        (see ``_evaluate``)."""
        return self._evaluate(u, True)


class ContinuationProblemBase:
    """Defaults of every capability (see the module docstring): a subclass implements
    ``n_unknowns``, ``residual``, ``residual_and_jacobian`` and ``monitor`` (or, as
    before, ``evaluate`` in place of the two) and overrides what it offers."""

    n_unknowns: int

    # StepControl
    step_control: str = "effort"
    fast_newton: Callable[..., tuple | None] | None = None
    solved_tangent: Callable[[Any, np.ndarray], tuple[np.ndarray, float] | None] | None = None
    measure: str | None = "amplitude"
    progress_records: tuple[str, ...] = ("frequency", "amplitude")
    #: True for a nonsmooth branch whose corners (a tangent turning past 90° within one
    #: step) are crossed at fixed parameter (``core.steps._advance``)
    corner_parameter: bool = False
    # PinnedSolves
    amplitude_and_gradient: Callable[[np.ndarray], tuple[float, np.ndarray]] | None = None
    amplitude_value: Callable[[np.ndarray], float] | None = None
    # FamilyEvents
    frequency_of: Callable[[np.ndarray], float] | None = None
    family_frequency_limit: Callable[[], float] | None = None
    family_frequency_ceiling: Callable[[], float] | None = None
    scaled_state: Callable[[np.ndarray, float], np.ndarray] | None = None
    family_predictor: Callable[[np.ndarray, float, float, float], np.ndarray] | None = None
    family_landing: Callable[..., tuple[np.ndarray, float]] | None = None
    harmonic_landing: Callable[..., tuple[np.ndarray, float] | None] | None = None
    homotopy_landing: Callable[..., tuple[np.ndarray, float]] | None = None
    leads_fundamental: Callable[[np.ndarray], bool] | None = None
    family_starts: Callable[[], Any] | None = None
    # AmplitudeStart
    open_amplitude: Callable[[], float] | None = None
    # BranchRecords
    branch_records: Callable[[np.ndarray], dict] | None = None
    tracked_frequencies: Any = None
    H: int = 0
    N: int = 0
    #: the attributes whose numbers fix the discretisation (:meth:`solver_settings`)
    setting_names: tuple[str, ...] = ()

    def residual(self, u: np.ndarray) -> np.ndarray:
        """The scaled residual R(u), shape (n−1,).

        The default calls ``evaluate(u, jacobian=False)`` of a subclass that overrides
        only ``evaluate``."""
        if type(self).evaluate is ContinuationProblemBase.evaluate:
            raise NotImplementedError(f"{type(self).__name__} defines neither residual nor evaluate")
        return self.evaluate(u, jacobian=False)

    def residual_and_jacobian(self, u: np.ndarray) -> tuple[np.ndarray, Any]:
        """(R, J): the scaled residual R(u) (n−1,) and J = ∂R/∂u (n−1, n), a dense
        ndarray or a scipy.sparse matrix.

        The default calls ``evaluate(u, jacobian=True)`` of a subclass that overrides
        only ``evaluate``."""
        if type(self).evaluate is ContinuationProblemBase.evaluate:
            raise NotImplementedError(f"{type(self).__name__} defines neither residual_and_jacobian "
                                      f"nor evaluate")
        return self.evaluate(u, jacobian=True)

    def evaluate(self, u: np.ndarray, jacobian: bool = True):
        """The earlier protocol, kept for old code: :meth:`residual_and_jacobian`
        with ``jacobian``, else :meth:`residual`."""
        return self.residual_and_jacobian(u) if jacobian else self.residual(u)

    def initial_tangent(self) -> np.ndarray:
        """Unit tangent at the start of the branch."""
        raise NotImplementedError(f"{type(self).__name__} has no initial tangent")

    def solver_settings(self) -> dict:
        """The scalar numbers among the attributes the class names in ``setting_names``
        (a checkpoint's ``solver`` entry: a resumed run must match); a named attribute that
        this instance does not set, or that holds no single number (None, an array), is
        left out."""
        out = {}
        for name in self.setting_names:
            value = getattr(self, name, None)
            if isinstance(value, int | float | np.number) and not isinstance(value, bool):
                out[name] = value.item() if isinstance(value, np.generic) else value
        return out

    def state_convention(self) -> dict:
        """How this problem's states are to be read, beyond its settings (recorded with a
        result and a checkpoint header, so that a loaded or resumed run reads them alike):
        name -> str. Empty by default."""
        return {}


class BackboneProblemBase(ContinuationProblemBase):
    """A problem continued from the linear mode at a small amplitude (:class:`AmplitudeStart`)."""

    def linear_mode_point(self, amplitude: float) -> np.ndarray:
        """Scaled unknowns of the linear mode whose amplitude DOF swings ``amplitude`` (m)."""
        raise NotImplementedError(f"{type(self).__name__} has no linear mode start")

    def linear_point(self, amplitude: float) -> np.ndarray:
        """Alias of :meth:`linear_mode_point` (the name of mmshbm 0.2)."""
        return self.linear_mode_point(amplitude)


class ForcedProblemBase(ContinuationProblemBase):
    """A problem continued in the excitation frequency (:class:`FrequencyStart`)."""

    def linear_response_point(self, frequency: float) -> np.ndarray:
        """Scaled unknowns of the linear response at ``frequency`` (Hz)."""
        raise NotImplementedError(f"{type(self).__name__} has no linear response start")

    def start_point(self, frequency: float) -> np.ndarray:
        """Scaled unknowns of the first point at ``frequency`` (Hz): the linear response
        unless the problem converges a better one."""
        return self.linear_response_point(frequency)

    def linear_point(self, frequency: float) -> np.ndarray:
        """Alias of :meth:`linear_response_point` (the name of mmshbm 0.2)."""
        return self.linear_response_point(frequency)


class _Plain(ContinuationProblemBase):
    """A problem with only the required protocol, every capability at its default."""

    def __init__(self, problem):
        self.problem = problem
        self.n_unknowns = problem.n_unknowns

    def residual(self, u):
        return self.problem.residual(u)

    def residual_and_jacobian(self, u):
        return self.problem.residual_and_jacobian(u)

    def monitor(self, u) -> dict:
        return self.problem.monitor(u)


class _PlainEvaluate(_Plain):
    """A problem with only the earlier protocol (:class:`EvaluateProblem`)."""

    def residual(self, u):
        return self.problem.evaluate(u, jacobian=False)

    def residual_and_jacobian(self, u):
        return self.problem.evaluate(u, jacobian=True)


def as_problem(problem) -> ContinuationProblemBase:
    """``problem`` itself when it derives from :class:`ContinuationProblemBase`, else
    wrapped in one (every capability at its default).

    Raises
    ------
    TypeError
        When ``problem`` lacks ``n_unknowns``, ``monitor`` or both ``residual`` and
        ``residual_and_jacobian`` (and ``evaluate``).
    """
    if isinstance(problem, ContinuationProblemBase):
        return problem
    if isinstance(problem, ContinuationProblem):
        return _Plain(problem)
    if isinstance(problem, EvaluateProblem):
        return _PlainEvaluate(problem)
    raise TypeError(f"a continuation problem needs n_unknowns, residual(u), residual_and_jacobian(u) "
                    f"(or evaluate(u, jacobian)) and monitor(u); got {type(problem).__name__}")
