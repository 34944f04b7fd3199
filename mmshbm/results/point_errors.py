"""The truncation error of every point of a harmonic balance branch, from one re-solve at 2H.

A harmonic balance point at H harmonics (amplitude A, frequency f(H)) is solved again at
H' = 2H with its amplitude pinned (:func:`mmshbm.core.pinned.solve_at_amplitude`),
starting from its own coefficients padded with zeros. Under the algebraic model of the
truncation, f(H) = f_∞ + C·H^−p,

    f(H) − f_∞ = (f(H) − f(2H)) · 2^p / (2^p − 1),

and the estimate of the relative error of the point is

    e = |f(2H) − f(H)| / f(2H) · 2^p / (2^p − 1),       with p = ``rate`` (default 2).

The factor is 4/3 at p = 2, 2 at p = 1 and tends to 1 for fast rates, so the rate matters
little once the point is in its asymptotic regime: measured against the exact orbits of
random chains with stiff contacts and of clearance oscillators (H = 8, 16, 32; ``python -m
validation accuracy N --estimator``, docs/accuracy.md) the ratio estimate / true error had
a median of 1.9 with p = 1 and 1.2 with p = 2, hence the default. Where the convergence
in H oscillates, a point at which the error happens to be small is overestimated (the
difference is then the 2H point's error), and one between two crossings can be
underestimated; before the asymptotic regime (a stiff contact whose contact time the
series does not resolve yet, a larger H that resolves another orbit) the estimate is a
measure of how much the point still moves with H, not a bound.

Why this estimator. It costs one pinned solve per point (a few Newton iterations at 2H;
the 2H solver is built once per branch), and it measures the frequency itself, so no
constant relates it to the error. Cheaper proxies read at H alone (the decay of the
harmonic amplitudes, the residual of the admissible signals) cost nothing but relate to
the frequency's error through a constant that depends on the model and the orbit (the
contact stiffness, how many contacts per period). The two-re-solve estimate
(:func:`mmshbm.results.truncation.truncation_error`, 2H and 4H, measured rate) stays the
one to call on demand where a point's rate matters.

The second solve is the branch refined: :func:`raise_point` returns it, and the tolerance
driver (:mod:`mmshbm.methods.adaptive`) promotes a point to it where the estimate at H
exceeds the tolerance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["PointErrors", "SolverLadder", "raise_point", "estimate_point_errors", "error_factor"]


def error_factor(rate: float, ratio: float = 2.0) -> float:
    """``ratio^p / (ratio^p − 1)``: the error of f(H) over |f(ratio·H) − f(H)| at rate p."""
    q = ratio ** float(rate)
    return q / (q - 1.0)


class SolverLadder:
    """The solvers of one branch's method at several H, built once each.

    Parameters
    ----------
    branch : Branch
        A harmonic balance branch (its model, method and method options rebuild the
        solvers; ``n_samples`` is left to each H's default).
    """

    def __init__(self, branch):
        self.branch = branch
        self.model = branch.get_model()
        self.options = {k: v for k, v in dict(branch.metadata.get("method_options", {})).items()
                        if k not in ("n_samples", "harmonics")}
        self._solvers = {}
        #: the (H, H2) pairs whose direct re-solve failed on this branch (:func:`raise_point`)
        self.stepped: set[tuple[int, int]] = set()
        solver = branch.attached_solver
        if solver is not None and getattr(solver, "H", None) is not None:
            self._solvers[int(solver.H)] = solver

    def at(self, H: int):
        """The solver at H harmonics."""
        H = int(H)
        solver = self._solvers.get(H)
        if solver is None:
            options = {**self.options, "harmonics": H}
            solver = self._solvers[H] = self.branch._build_solver(self.model, options)
        return solver


def pad(solver_from, u: np.ndarray, solver_to) -> np.ndarray:
    """The unknowns ``u`` of ``solver_from`` as unknowns of ``solver_to`` (another H): the
    cosine coefficients padded with zeros (or cut), Ω kept."""
    coef, omega = solver_from.unpack(u)[:2]
    out = np.zeros((solver_to.H + 1, coef.shape[1]))
    n = min(out.shape[0], coef.shape[0])
    out[:n] = coef[:n]
    return solver_to.pack(out, omega)


def raise_point(ladder: SolverLadder, H: int, u: np.ndarray, amplitude: float, H2: int,
                tol: float = 1e-10) -> np.ndarray:
    """The point ``u`` of the solver at ``H`` re-solved at ``H2`` with its amplitude
    (m) pinned, from its coefficients padded with zeros; where Newton fails from there, H
    is raised by ``STEP`` (~√2) per pinned solve instead (the direct solve gets
    ``DIRECT_ITERATIONS``, each step 40). Returns the unknowns at ``H2``.

    A pair (H, H2) whose direct solve failed once on the ladder's branch goes by the
    steps from then on (``ladder.stepped``): the points of a branch are solved in its
    order, and where the zero-padded start is too poor for one point (a stiff contact
    whose harmonics above H are not small) it is for the next, deeper one too; a failed
    direct solve costs its ``DIRECT_ITERATIONS`` at H2 for nothing.

    Raises
    ------
    PinnedFailure
        When a solve fails.
    """
    from ..core.pinned import PinnedFailure, solve_at_amplitude

    def solve(h_from, v, h_to, max_iter):
        s_from, s_to = ladder.at(h_from), ladder.at(h_to)
        return solve_at_amplitude(s_to, pad(s_from, v, s_to), amplitude, tol=tol, max_iter=max_iter)[0]

    pair = (int(H), int(H2))
    if pair not in ladder.stepped or STEP * H >= H2:
        try:  # from a good start Newton converges in a few iterations: a long struggle is a bad start
            return solve(H, u, H2, DIRECT_ITERATIONS)
        except (PinnedFailure, ArithmeticError, ValueError):
            ladder.stepped.add(pair)
    h, v = H, u
    while h < H2:
        nxt = min(H2, max(h + 1, math.ceil(STEP * h)))
        v, h = solve(h, v, nxt, 40), nxt
    return v


#: Newton iterations of the direct re-solve at H2 before the steps take over
DIRECT_ITERATIONS = 12
#: the factor on H per step where the direct re-solve failed (two steps per doubling)
STEP = 1.42


@dataclass(frozen=True)
class PointErrors:
    """The per-point estimates of a branch (arrays of shape (n_points,)).

    Attributes
    ----------
    error : ndarray
        Estimated relative error of each point's frequency (NaN where the re-solve failed).
    frequency_raised : ndarray
        The frequency (Hz) of the point re-solved at ``harmonics_raised`` (NaN where it failed).
    harmonics_raised : ndarray of int
        The H of the re-solve.
    states_raised : list of ndarray or None
        The re-solved unknowns (None where the solve failed).
    """

    error: np.ndarray
    frequency_raised: np.ndarray
    harmonics_raised: np.ndarray
    states_raised: list


def estimate_point_errors(ladder: SolverLadder, harmonics, states, amplitudes, frequencies, *,
                          rate: float = 2.0, tol: float = 1e-10) -> PointErrors:
    """The estimate of the module docstring for each point: point i (unknowns
    ``states[i]`` of the solver at ``harmonics[i]``, amplitude ``amplitudes[i]`` m,
    frequency ``frequencies[i]`` Hz) re-solved at ``2·harmonics[i]``."""
    from ..core.pinned import PinnedFailure

    n = len(states)
    err = np.full(n, np.nan)
    f2 = np.full(n, np.nan)
    H2 = np.asarray(harmonics, dtype=int) * 2
    raised: list = [None] * n
    factor = error_factor(rate)
    for i in range(n):
        a = float(amplitudes[i])
        if not (a > 0 and math.isfinite(a) and math.isfinite(frequencies[i])):
            continue
        try:
            u2 = raise_point(ladder, int(harmonics[i]), states[i], a, int(H2[i]), tol)
        except (PinnedFailure, ArithmeticError, ValueError, np.linalg.LinAlgError):
            continue
        f = float(ladder.at(int(H2[i])).unpack(u2)[1]) / (2 * math.pi)  # Ω (rad/s): the monitor's frequency
        raised[i], f2[i] = u2, f
        err[i] = factor * abs(f - float(frequencies[i])) / abs(f)
    return PointErrors(err, f2, H2, raised)
