"""Points pinned by a constraint: the solution of the continuation problem at a given
amplitude.

The continuation problem has n−1 equations in n unknowns; fixing a scalar function of the
unknowns, here the amplitude A(u) = A*, closes it:

    [R(u); A(u) − A*] = 0,        Jacobian [J; ∇A(u)ᵀ].

Newton on this system gives the point of the branch at exactly that amplitude (what
``Branch.frequency_at`` reports, and where a jump over an internal-resonance tongue lands).
The amplitude is the largest excursion of a DOF over the period; problems that know its
gradient provide ``amplitude_and_gradient(u) -> (A, ∇A)`` (MMS-HBM: envelope theorem);
otherwise it is differenced from ``monitor(u)["amplitude"]``.

A solve runs to its iteration limit unless it converges: no stagnation test stops it
earlier. On the nonsmooth MMS-HBM residual a solve can creep for 20–28 iterations without
lowering its best residual (steps cut to λ = 1/32 throughout) and then converge
quadratically within the limit, once a step crosses a contact's kink. Over the solves of
the beam's convergence study and of random corpus models, no test on the residual history
or the step lengths separated such solves from those that fail.
"""

from __future__ import annotations

import math

import numpy as np

from .bordered import bordered_solve
from .problem import as_problem

__all__ = ["amplitude_and_gradient", "solve_at_amplitude", "PinnedFailure", "StartOutside"]


class PinnedFailure(ArithmeticError):
    """Newton on the pinned system did not converge (the message says why)."""


class StartOutside(PinnedFailure):
    """The start of a pinned solve lies outside its trust region (nothing was solved)."""


def amplitude_and_gradient(problem, u: np.ndarray, h: float = 1e-7) -> tuple[float, np.ndarray]:
    """(A(u), ∇A(u)) from the problem, or by central differences of its monitor."""
    problem = as_problem(problem)
    if problem.amplitude_and_gradient is not None:
        return problem.amplitude_and_gradient(u)
    value = float(problem.monitor(u)["amplitude"])
    grad = np.empty(len(u))
    for i in range(len(u)):
        e = np.zeros(len(u))
        e[i] = h
        grad[i] = (problem.monitor(u + e)["amplitude"] - problem.monitor(u - e)["amplitude"]) / (2 * h)
    return value, grad


def solve_at_amplitude(problem, u0: np.ndarray, amplitude: float, *, tol: float = 1e-10, max_iter: int = 20,
                       step_tol: float = 1e-8, solve=None,
                       admissible=None) -> tuple[np.ndarray, int, np.ndarray, np.ndarray]:
    """Newton on [R(u); A(u)/A* − 1] = 0 from ``u0``.

    Parameters
    ----------
    problem : ContinuationProblem
    u0 : ndarray, shape (n,)
        Start (scaled unknowns), e.g. interpolated between neighbouring branch points.
    amplitude : float
        A* (m), > 0.
    tol : float
        Infinity norm of the scaled residual (the amplitude row relative).
    max_iter : int
    step_tol : float
        Also converged when the full Newton update's infinity norm is below this while the
        residual is below √tol (a round-off floor near a pole of the condensed stiffness,
        as in :func:`mmshbm.core.continuation.newton`).
    solve : callable(J_bordered_rows, rhs), optional
        Solver of the bordered system ``[J; g] x = rhs`` (default: the continuation's).
    admissible : callable(u) -> bool, optional
        The trust region: every iterate must satisfy it (e.g. a frequency window around
        the branch being solved). A Newton step that leaves it is halved until it does
        not (at most 6 times); an iterate that still leaves it ends the solve with
        PinnedFailure, so no iterate is ever evaluated far from the branch (a harmonic of
        a runaway frequency beyond the modes the condensation kept).

    Returns
    -------
    u, iterations, residual history, unit tangent of the branch at u (oriented to
    increasing amplitude)

    Raises
    ------
    PinnedFailure
        No convergence, a singular system or a non-finite residual.
    """
    if not amplitude > 0:
        raise ValueError(f"amplitude must be positive, got {amplitude!r}")
    problem = as_problem(problem)
    solve = solve or bordered_solve
    u = np.array(u0, dtype=float)
    if admissible is not None and not admissible(u):
        raise StartOutside("the start lies outside the trust region")
    history = []
    du_norm = math.inf
    gradient = problem.amplitude_and_gradient or (lambda v: amplitude_and_gradient(problem, v))
    carried = None  # (R, J, A, g) at u, evaluated by the line search's full step
    for it in range(max_iter + 1):
        if carried is not None:
            R, J, A, g = carried
            carried = None
        else:
            try:
                R, J = problem.residual_and_jacobian(u)
                A, g = gradient(u)
            except (ArithmeticError, np.linalg.LinAlgError, ValueError, RuntimeError) as err:
                raise PinnedFailure(f"evaluation failed: {err}") from None
        c = A / amplitude - 1.0
        norm = max(float(np.abs(R).max()) if R.size else 0.0, abs(c))
        history.append(norm)
        if not math.isfinite(norm):
            raise PinnedFailure("non-finite residual")
        if norm <= tol or (du_norm <= step_tol and norm <= math.sqrt(tol)):
            rhs = np.zeros(len(u))
            rhs[-1] = 1.0
            t = solve(J, g / amplitude, rhs)
            if not np.all(np.isfinite(t)):
                raise PinnedFailure("singular system at the solution")
            t /= np.linalg.norm(t)
            return u, it, np.array(history), t
        if it == max_iter:
            break
        rhs = np.empty(len(u))
        rhs[:-1] = R
        rhs[-1] = c
        du = solve(J, g / amplitude, rhs)
        if not np.isfinite(du).all():
            raise PinnedFailure("singular system")
        du_norm = float(np.abs(du).max())
        # backtracking: halve the step while the residual grows (nonsmooth, and far from
        # the solution a full step can land on another branch); the last halving
        # (λ = 1/32) is taken whatever its residual, so it is not evaluated. The full step
        # is tried with the Jacobian and the amplitude's gradient (most full steps are
        # taken, and the next iteration needs both there); shorter ones with the residual.
        lam = 1.0
        for _ in range(7):
            trial = u - lam * du
            if admissible is not None and not admissible(trial):
                if lam < 0.05:
                    raise PinnedFailure(f"Newton left the trust region (iteration {it + 1})")
                lam *= 0.5
                continue
            if lam < 0.05:
                break
            if lam == 1.0:
                carried = _full_step(problem, gradient, trial, amplitude, norm)
                if carried is not None:
                    break
            elif _decreases(problem, trial, amplitude, norm):
                break
            lam *= 0.5
        u = u - lam * du
    raise PinnedFailure(f"no convergence in {max_iter} iterations (residual {history[-1]:.2e})")


def _full_step(problem, gradient, u: np.ndarray, amplitude: float, norm: float):
    """(R, J, A, ∇A) at ``u`` when the scaled residual's norm there is below ``norm``, else
    None (a failed evaluation: None). The evaluation the next Newton iteration starts from
    where the full step is taken; the residual rows come first, as in :func:`_decreases`."""
    try:
        R, J = problem.residual_and_jacobian(u)
        if not (float(np.abs(R).max()) if R.size else 0.0) < norm:
            return None
        A, g = gradient(u)
        if not abs(A / amplitude - 1.0) < norm:
            return None
        return R, J, A, g
    except (ArithmeticError, np.linalg.LinAlgError, ValueError, RuntimeError):
        return None


def _decreases(problem, u: np.ndarray, amplitude: float, norm: float) -> bool:
    """Whether the scaled residual's norm at ``u`` is below ``norm`` (a failed evaluation:
    no). The residual rows come first: when they alone reach ``norm`` (most rejected
    trials) the amplitude is not evaluated, and the answer is that of the full norm."""
    try:
        r = float(np.abs(problem.residual(u)).max())
        if not r < norm:
            return False
        A = (problem.amplitude_value(u) if problem.amplitude_value is not None
             else amplitude_and_gradient(problem, u)[0])
        return max(r, abs(A / amplitude - 1.0)) < norm
    except (ArithmeticError, np.linalg.LinAlgError, ValueError, RuntimeError):
        return False
