"""The pinned system solved from a distant start: a Newton (global) homotopy.

Newton on the pinned system G(u) = [R(u); A(u)/A* − 1] = 0 (:mod:`mmshbm.core.pinned`)
converges only from starts near a solution; on the nonsmooth MMS-HBM residual that basin
can be small. An orbit of a low-harmonic family raised to H harmonics (the new
harmonics zero) is such a distant start. The Newton homotopy

    Φ(u, s) = G(u) − (1 − s) G(u₀),        s from 0 to 1,

has the start u₀ as its solution at s = 0 and the pinned system at s = 1. Its solution
curve through (u₀, 0) is followed by pseudo-arclength continuation in (u, s) — the curve
may turn back in s on the way (Allgower & Georg, *Introduction to Numerical Continuation
Methods*, SIAM 2003, ch. 11) — until it crosses s = 1, where Newton on G finishes from
the crossing. Where Newton's iterates from u₀ wander between the contacts' kinks, the
curve keeps every intermediate point an exact solution of a nearby system. The curve can
still end elsewhere (at another solution, or leave the trust region): the result is a
solution of G, and the caller decides whether it is the orbit it sought.

Cost: a few tens of steps when the curve is short, a few hundred when it winds; each
step is one or two residual + Jacobian evaluations and a bordered solve (the pinned
solve's). On MMS-HBM's few contact unknowns that is 0.01–0.1 s.
"""

from __future__ import annotations

import logging
import math

import numpy as np
import scipy.sparse as sp

from .bordered import bordered_solve
from .pinned import PinnedFailure, StartOutside, amplitude_and_gradient, solve_at_amplitude
from .problem import as_problem

__all__ = ["pinned_homotopy"]

log = logging.getLogger(__name__)

#: corrector iterations per step before the step is halved
_CORRECTOR_ITERATIONS = 6
#: the corrector's tolerance on |Φ|∞ (the curve is followed this closely; the final Newton
#: at s = 1 meets the caller's tolerance)
_CORRECTOR_TOL = 1e-8
#: smallest cosine between consecutive tangents (larger turns halve the step)
_MIN_TURN_COSINE = 0.9
#: step lengths (scaled unknowns and s together): first, largest, smallest
_H_FIRST, _H_MAX, _H_MIN = 0.05, 0.5, 1e-6


def pinned_homotopy(problem, u0: np.ndarray, amplitude: float, *, tol: float = 1e-10, max_iter: int = 20,
                    max_steps: int = 400, admissible=None) -> tuple[np.ndarray, int, np.ndarray, np.ndarray]:
    """Solve [R(u); A(u)/A* − 1] = 0 by the Newton homotopy from ``u0``.

    Parameters
    ----------
    problem : ContinuationProblem
    u0 : ndarray, shape (n,)
        The start (scaled unknowns); it need not be near a solution.
    amplitude : float
        A* (m), > 0.
    tol, max_iter :
        Of the final Newton solve at s = 1 (:func:`~mmshbm.core.pinned.solve_at_amplitude`).
    max_steps : int
        Continuation steps at most (accepted and refused together).
    admissible : callable(u) -> bool, optional
        The trust region: the curve ends with PinnedFailure where it leaves it.

    Returns
    -------
    (u, iterations, residual history, tangent) of the final Newton solve, as
    :func:`~mmshbm.core.pinned.solve_at_amplitude` returns them.

    Raises
    ------
    PinnedFailure
        When the curve does not reach s = 1 within ``max_steps`` (its step falls below
        the smallest, it leaves the trust region, or an evaluation fails), or the final
        Newton solve fails.
    """
    if not amplitude > 0:
        raise ValueError(f"amplitude must be positive, got {amplitude!r}")
    problem = as_problem(problem)
    gradient = problem.amplitude_and_gradient or (lambda v: amplitude_and_gradient(problem, v))
    u0 = np.array(u0, dtype=float)
    n = len(u0)

    def system(u):
        R, J = problem.residual_and_jacobian(u)
        A, g = gradient(u)
        G = np.empty(n)
        G[:-1] = R
        G[-1] = A / amplitude - 1.0
        return G, J, g / amplitude

    try:
        G0, J, g = system(u0)
    except (ArithmeticError, np.linalg.LinAlgError, ValueError, RuntimeError) as err:
        raise PinnedFailure(f"the homotopy's start cannot be evaluated: {err}") from None
    if not np.isfinite(G0).all():
        raise PinnedFailure("the homotopy's start has a non-finite residual")

    def jacobian(J, g):
        """dΦ/d(u, s) without its last row: [J | R₀] (n−1, n+1); the last row apart."""
        if sp.issparse(J):
            return sp.hstack([J, sp.csr_matrix(G0[:-1, None])], format="csr"), np.append(g, G0[-1])
        return np.hstack([np.asarray(J), G0[:-1, None]]), np.append(g, G0[-1])

    def solve(Jx, gx, border, rhs):
        """[Jx; gx; border] y = rhs, the (n+1)×(n+1) bordered system."""
        if sp.issparse(Jx):
            return bordered_solve(sp.vstack([Jx, sp.csr_matrix(gx[None, :])], format="csr"), border, rhs)
        return bordered_solve(np.vstack([Jx, gx]), border, rhs)

    e_last = np.zeros(n + 1)
    e_last[-1] = 1.0
    Jx, gx = jacobian(J, g)
    t = solve(Jx, gx, e_last, e_last)  # ds = 1 along the start's tangent
    if not np.isfinite(t).all():
        raise PinnedFailure("the homotopy's start is singular")
    t /= np.linalg.norm(t)
    x = np.append(u0, 0.0)
    h = _H_FIRST
    for step in range(max_steps):
        x_pred = x + h * t
        y = x_pred.copy()
        converged, iterations = False, 0
        while iterations < _CORRECTOR_ITERATIONS:
            iterations += 1
            try:
                G, J, g = system(y[:-1])
            except (ArithmeticError, np.linalg.LinAlgError, ValueError, RuntimeError):
                break
            Phi = G - (1.0 - y[-1]) * G0
            if not np.isfinite(Phi).all():
                break
            Jx, gx = jacobian(J, g)
            if float(np.abs(Phi).max()) <= _CORRECTOR_TOL:
                converged = True
                break
            dy = solve(Jx, gx, t, np.append(Phi, t @ (y - x_pred)))
            if not np.isfinite(dy).all() or float(np.abs(dy).max()) > 10.0 * h + 1.0:
                break
            y -= dy
        if converged:
            t_new = solve(Jx, gx, t, e_last)
            converged = bool(np.isfinite(t_new).all())
        if converged:
            t_new /= np.linalg.norm(t_new)
            converged = t_new @ t >= _MIN_TURN_COSINE
        if not converged:
            h *= 0.5
            if h < _H_MIN:
                raise PinnedFailure("the homotopy's step fell below its smallest")
            continue
        if admissible is not None and not admissible(y[:-1]):
            raise PinnedFailure("the homotopy left the trust region")
        if (x[-1] - 1.0) * (y[-1] - 1.0) <= 0.0:  # crossed s = 1 between x and y
            w = (1.0 - x[-1]) / (y[-1] - x[-1]) if y[-1] != x[-1] else 1.0
            u = x[:-1] + w * (y[:-1] - x[:-1])
            log.debug("homotopy at %.4g ended after %d steps", amplitude, step + 1)
            try:
                return solve_at_amplitude(problem, u, amplitude, tol=tol, max_iter=max_iter,
                                          admissible=admissible)
            except StartOutside:
                raise PinnedFailure("the homotopy ended outside the trust region") from None
        x, t = y, t_new
        if iterations <= 3:
            h = min(2.0 * h, _H_MAX)
    raise PinnedFailure(f"the homotopy did not reach its end in {max_steps} steps "
                        f"(parameter {x[-1]:.3g} of 1)" if math.isfinite(x[-1]) else
                        f"the homotopy did not reach its end in {max_steps} steps")
