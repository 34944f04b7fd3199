"""The machinery shared by the damped results computed to a tolerance (forced responses,
damped nonlinear modes): solvers at several H, moving a point between them, and the
loop that raises H per point while its estimate exceeds the tolerance.

It is the loop of :mod:`mmshbm.methods.adaptive` (the backbone's) for problems whose
unknowns are those of :class:`~mmshbm.methods.mms.damped.DampedHBMBase`: the cosine and
sine coefficients of the massless DOFs, harmonic by harmonic (blocks of ``n_x / (2H+1)``
numbers: the mean, then cos 1, sin 1, cos 2, ...), followed by a few numbers that do not
depend on H (Ω, the damping ξ of a nonlinear mode, a tracked first harmonic). The
thresholds of the loop (:data:`~mmshbm.methods.adaptive_climb.FASTEST`,
:data:`~mmshbm.methods.adaptive_climb.ASSUMED_CONTRACTION`) are the backbone's: a point is
promoted to its 2H solution while its estimate exceeds ``tol``, contracts by
``contraction`` per doubling (``patience`` doublings without it stop the point), and
``tol`` stays within reach below ``max_harmonics``; a point promoted to the top gets its
estimate divided by its last contraction (at least ASSUMED_CONTRACTION), flagged in
``extrapolated``.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable

import numpy as np

from ..core.problem import ContinuationProblemBase
from .adaptive_climb import ASSUMED_CONTRACTION, FASTEST

__all__ = ["pad_damped", "solve_at_frequency", "raise_H", "DampedLadder", "refine_points", "Refined",
           "AmplitudePinned"]

log = logging.getLogger(__name__)

#: Newton iterations of the direct re-solve at 2H before stepping H up instead
DIRECT_ITERATIONS = 12
#: the factor on H per step where the direct re-solve failed (two steps per doubling)
STEP = 1.42


def pad_damped(s_from, u: np.ndarray, s_to) -> np.ndarray:
    """The scaled unknowns ``u`` of ``s_from`` as those of ``s_to`` (another H): the
    harmonic coefficients padded with zeros (or cut), the numbers after them kept.

    Raises
    ------
    ValueError
        When a solver's unknowns are not laid out harmonic by harmonic.
    """
    for s in (s_from, s_to):
        if s.n_x % (2 * s.H + 1):
            raise ValueError(f"{type(s).__name__}: {s.n_x} coefficients are not 2H+1 = {2 * s.H + 1} blocks")
    y = np.asarray(u, dtype=float) * s_from.colscale
    x, rest = y[:s_from.n_x], y[s_from.n_x:]
    out = np.zeros(s_to.n_x)
    n = min(s_to.n_x, s_from.n_x)
    out[:n] = x[:n]
    return np.concatenate([out, rest]) / s_to.colscale


def solve_at_frequency(problem, u0: np.ndarray, *, tol: float = 1e-10, max_iter: int = 20) -> np.ndarray:
    """Newton on R(u) = 0 with the last unknown (Ω) held at its value in ``u0``: the
    point of a forced response at that excitation frequency (bordered system
    [J; e_Ωᵀ] du = [R; 0], the continuation's linear solve). Returns the unknowns.

    Raises
    ------
    PinnedFailure
        No convergence, a singular system or a non-finite residual.
    """
    from ..core.bordered import bordered_solve
    from ..core.pinned import PinnedFailure
    from ..core.problem import as_problem

    problem = as_problem(problem)
    u = np.array(u0, dtype=float)
    e = np.zeros(len(u))
    e[-1] = 1.0
    norm = math.inf
    for it in range(max_iter + 1):
        try:
            R, J = problem.residual_and_jacobian(u)
        except (ArithmeticError, np.linalg.LinAlgError, ValueError, RuntimeError) as err:
            raise PinnedFailure(f"evaluation failed: {err}") from None
        norm = float(np.abs(R).max()) if R.size else 0.0
        if not math.isfinite(norm):
            raise PinnedFailure("non-finite residual")
        if norm <= tol:
            return u
        if it == max_iter:
            break
        du = bordered_solve(J, e, np.concatenate([R, [0.0]]))
        if not np.isfinite(du).all():
            raise PinnedFailure("singular system")
        lam = 1.0  # halve the step while the residual grows (the residual is nonsmooth)
        for _ in range(6):
            try:
                if float(np.abs(problem.residual(u - lam * du)).max()) < norm:
                    break
            except (ArithmeticError, np.linalg.LinAlgError, ValueError, RuntimeError):
                pass
            lam *= 0.5
        u = u - lam * du
    raise PinnedFailure(f"no convergence in {max_iter} iterations (residual {norm:.2e})")


class DampedLadder:
    """Solvers of one problem at several H, built once each by ``build(H)``."""

    def __init__(self, build: Callable[[int], object], first=None):
        self._build = build
        self._solvers = {} if first is None else {int(first.H): first}

    def at(self, H: int):
        """The solver at H harmonics."""
        H = int(H)
        if H not in self._solvers:
            self._solvers[H] = self._build(H)
        return self._solvers[H]


def raise_H(ladder: DampedLadder, H: int, u: np.ndarray, H2: int, pinned_solve) -> np.ndarray:
    """The point ``u`` of the solver at ``H`` solved at ``H2`` by ``pinned_solve(solver,
    start, max_iter)`` from its coefficients padded with zeros; where that fails, H is
    raised by :data:`STEP` per solve instead. Returns the unknowns at ``H2``.

    Raises
    ------
    PinnedFailure
        When a solve fails.
    """
    from ..core.pinned import PinnedFailure

    def solve(h_from, v, h_to, max_iter):
        s_to = ladder.at(h_to)
        return pinned_solve(s_to, pad_damped(ladder.at(h_from), v, s_to), max_iter)

    try:
        return solve(H, u, H2, DIRECT_ITERATIONS)
    except (PinnedFailure, ArithmeticError, ValueError):
        h, v = H, u
        while h < H2:
            nxt = min(H2, max(h + 1, math.ceil(STEP * h)))
            v, h = solve(h, v, nxt, 40), nxt
        return v


class Refined:
    """What :func:`refine_points` returns (arrays of shape (n_points,) unless said).

    Attributes
    ----------
    harmonics : ndarray of int
        The H each point keeps.
    states : list of ndarray
        Its unknowns at that H.
    error : ndarray
        Its estimate (the largest of the measures the estimator returns).
    measures : dict of str to ndarray
        Every measure of the estimator at the kept H (e.g. amplitude and frequency errors).
    extrapolated : ndarray of int8
        1 where the estimate was extrapolated from the last doubling (the top H).
    levels : int
        Estimate passes.
    """

    def __init__(self, harmonics, states, error, measures, extrapolated, levels):
        self.harmonics, self.states, self.error = harmonics, states, error
        self.measures, self.extrapolated, self.levels = measures, extrapolated, levels


def refine_points(states, start_harmonics: int, estimate, *, tol: float, max_harmonics: int, patience: int,
                  contraction: float, eligible=None) -> Refined:
    """Raise H per point until its estimate meets ``tol`` (module docstring).

    Parameters
    ----------
    states : list of ndarray
        The points' unknowns at ``start_harmonics``.
    start_harmonics : int
    estimate : callable(indices, H, states) -> list of (measures, u2, H2)
        For each point, its measures (dict name -> relative error at H, NaN where the
        re-solve failed; the estimate is their largest), its unknowns at H2 = 2H (None
        where it failed) and H2.
    tol, max_harmonics, patience, contraction
        As in :func:`mmshbm.methods.adaptive.backbone_to_tolerance`.
    eligible : ndarray of bool, optional
        The points that may be raised (default all); the others keep their first estimate.
    """
    n = len(states)
    H = np.full(n, start_harmonics, dtype=int)
    states = [np.asarray(u, dtype=float) for u in states]
    err = np.full(n, np.nan)
    measures: dict = {}
    last = np.full(n, np.inf)
    ratio = np.full(n, math.nan)
    extrapolated = np.zeros(n, dtype=np.int8)
    stalls = np.zeros(n, dtype=int)
    eligible = np.ones(n, dtype=bool) if eligible is None else np.asarray(eligible, dtype=bool)
    active = np.arange(n)
    levels = 0
    while len(active):
        levels += 1
        out = estimate(active, H[active], [states[i] for i in active])
        promote = []
        for i, (m, u2, h2) in zip(active, out, strict=True):
            for k, v in m.items():
                measures.setdefault(k, np.full(n, np.nan))[i] = v
            vals = np.array(list(m.values()), dtype=float)
            e = float(np.max(vals)) if len(vals) and np.all(np.isfinite(vals)) else math.nan
            err[i] = e
            if not math.isfinite(e) or e <= tol or u2 is None:
                continue
            ratio[i] = last[i] / e if math.isfinite(last[i]) else math.nan
            stalls[i] = 0 if e * contraction <= last[i] else stalls[i] + 1
            last[i] = e
            left = math.floor(math.log2(max_harmonics / H[i]) + 1e-9)
            if not eligible[i] or stalls[i] >= patience or left < 1 or e > tol * FASTEST ** left:
                continue
            promote.append((i, u2, int(h2)))
        nxt = []
        for i, u2, h2 in promote:
            states[i], H[i] = u2, h2
            if 2 * H[i] <= max_harmonics:
                nxt.append(i)
            else:  # the top: no solve above the cap, the estimate extrapolated
                c = ratio[i] if math.isfinite(ratio[i]) else ASSUMED_CONTRACTION
                c = min(max(c, ASSUMED_CONTRACTION), FASTEST)
                err[i] /= c
                for k in measures:
                    measures[k][i] /= c
                extrapolated[i] = 1
        active = np.array(nxt, dtype=int)
        log.info("tolerance %.3g: level %d, %d points raised", tol, levels, len(promote))
    return Refined(H, states, err, measures, extrapolated, levels)


class AmplitudePinned(ContinuationProblemBase):
    """A forced-response solver with the amplitude's gradient that
    :func:`mmshbm.core.pinned.solve_at_amplitude` needs, in closed form for the MMS-HBM
    forced problem (:class:`~mmshbm.methods.mms.forced.ForcedResponseProblem`): the
    amplitude is the largest |q(τ)| of the amplitude DOF, q = E(τ)·Q, with Q affine in the
    massless DOFs' coefficients x at fixed Ω (Q = Xc for a contact DOF, −Z_k(Ω) Q̂_c + the
    load's response for a DOF with mass), so that ∂A/∂x = sign q(τ*) E(τ*) ∂Q/∂x at the
    maximiser τ* (envelope theorem); ∂A/∂Ω by central differences (step 1e-7 of the scaled
    Ω). Other problems get the monitor's amplitude differenced in every unknown."""

    def __init__(self, solver):
        from ..core.problem import as_problem
        from .mms.forced import ForcedResponseProblem

        self.solver = as_problem(solver)
        self.n_unknowns = solver.n_unknowns
        self.residual = self.solver.residual
        self.residual_and_jacobian = self.solver.residual_and_jacobian
        self.monitor = self.solver.monitor
        self.amplitude_value = None
        self.amplitude_and_gradient = None
        if type(solver) is ForcedResponseProblem:
            model, dof = solver.model, solver.amplitude_dof
            self._c = int(np.flatnonzero(model.c == dof)[0]) if dof in model.c else None
            self._l = None if self._c is not None else int(np.flatnonzero(model.l == dof)[0])
            self.amplitude_value = self._value
            self.amplitude_and_gradient = self._value_and_gradient

    def _coefficients(self, u):
        s = self.solver
        return s.coefficients(u)[s.amplitude_dof]

    def _value(self, u) -> float:
        return float(self.solver.amplitude(self._coefficients(u)))

    def _value_and_gradient(self, u, h: float = 1e-7):
        from .mms.damped import fine_samples, synthesis_matrix

        s = self.solver
        Q = self._coefficients(u)
        value = float(s.amplitude(Q))
        n = s._n_fine
        q = fine_samples(Q, n)
        j = int(np.argmax(np.abs(q)))
        y0, ym, yp = abs(q[j]), abs(q[j - 1]), abs(q[(j + 1) % n])
        curv = ym - 2 * y0 + yp
        delta = 0.5 * (ym - yp) / curv if curv < 0 else 0.0
        tau = 2 * np.pi * (j + delta) / n
        gQ = np.sign(q[j]) * synthesis_matrix(s.H, np.array([tau]))[0]  # (2H+1,)
        n_c, H = s.n_c, s.H
        gx = np.zeros(s.n_x)
        if self._c is not None:
            gx[np.arange(2 * H + 1) * n_c + self._c] = gQ
        else:
            omega = s.angular_frequency(u)
            Z = s._condensed(omega, recover=True).Z[:, self._l, :]  # (H+1, n_c)
            gx[:n_c] = -gQ[0] * Z[0].real
            for k in range(1, H + 1):
                gc, gs, Zr, Zi = gQ[2 * k - 1], gQ[2 * k], Z[k].real, Z[k].imag
                gx[(2 * k - 1) * n_c:2 * k * n_c] = -gc * Zr + gs * Zi
                gx[2 * k * n_c:(2 * k + 1) * n_c] = -gc * Zi - gs * Zr
        grad = np.empty(self.n_unknowns)
        grad[:-1] = gx * s.xscale
        up, um = np.array(u, dtype=float), np.array(u, dtype=float)
        up[-1] += h
        um[-1] -= h
        grad[-1] = (self._value(up) - self._value(um)) / (2 * h)
        return value, grad
