"""Krylov solves for the forced response with friction and many contact DOFs.

The forced problem's unknowns are the massless DOFs' coefficients x (n_c per cosine or
sine coefficient, ordered coefficient-major: x[j n_c + i] is coefficient j of DOF i), with
a friction forced problem's two tracked harmonic-1 unknowns and Ω after them. Its Jacobian
is A 𝔻 + B: 𝔻 = diag_k(D_k) the condensed dynamic stiffness (dense n_c × n_c per harmonic,
as real 2 n_c × 2 n_c blocks), A and B block-diagonal per contact DOF ((2H+1) × (2H+1): the
friction law's or the contact law's derivatives, which couple the harmonics of one DOF).
The dense LU of the whole Jacobian costs (n_c (2H+1))³ · 2/3 flops.

The preconditioner keeps, per harmonic k, the square block of the Jacobian on the unknowns
of harmonic k (the cosine and sine coefficients of every DOF, and on harmonic 1 the two
tracked unknowns): J_kk = A_kk 𝔻_k + B_kk, the law's time-averaged derivatives on that
harmonic times the exact coupling of the DOFs, one LU of 2 n_c (n_c for harmonic 0) each,
(H+1) blocks: (2H+1)³/(1 + 8H) times fewer flops than the whole LU (~20× at H = 5). The
bordered system of the continuation ([J; tᵀ], the Ω column and the arclength row) is
preconditioned by the block elimination of
:meth:`mmshbm.methods.mms.krylov.KrylovCorrector._preconditioner`; the square system of a
fixed-frequency solve by the blocks alone. Right-preconditioned GMRES
(:func:`mmshbm.methods.mms.krylov._right_gmres`) solves to a relative residual ``rtol``
(1e-10) or its round-off floor, with the Jacobian applied as a dense product, or, where
the problem hands an operator (:class:`~mmshbm.methods.mms.forced_operator.ForcedJacobian`,
never assembled), by its product and its harmonics' blocks; a solve it does not finish in
``max_krylov`` iterations falls back to the dense LU (counted in ``fallbacks``; an operator
is assembled for it up to :data:`~mmshbm.methods.mms.krylov.DENSE_FALLBACK_MAX` unknowns).
The Newton iterates therefore differ from the dense path's by at most ~rtol times the step,
and the converged points agree with it to the Newton tolerance.

Switch: ``linear_solver`` of the friction forced problem, "dense", "krylov" or "auto"
(Krylov from :data:`FORCED_KRYLOV_MIN_UNKNOWNS` unknowns on, from
:data:`FORCED_MATRIX_FREE_MIN_UNKNOWNS` where the Jacobian is an operator).
"""

from __future__ import annotations

import logging

import numpy as np
import scipy.linalg as la

from .krylov import DENSE_FALLBACK_MAX, KrylovCorrector, _right_gmres, check_linear_solver, gmres_operator

__all__ = ["ForcedKrylovSolver", "forced_harmonic_columns", "FORCED_KRYLOV_MIN_UNKNOWNS",
           "FORCED_MATRIX_FREE_MIN_UNKNOWNS", "resolve_forced_solver"]

log = logging.getLogger(__name__)

#: unknowns of the forced problem from which ``linear_solver="auto"`` takes Krylov: on the
#: lap joint with 100 pairs at H = 5 (2203 unknowns) one dense LU and one preconditioned
#: GMRES solve cost about the same (1.4 and 2.0 s on the loaded 2-core machine,
#: docs/interfaces.md); the LU grows as n³, GMRES with the dense product as n²
FORCED_KRYLOV_MIN_UNKNOWNS = 4000
#: the same where the Krylov path applies the Jacobian as an operator (constant slip forces,
#: no unilateral contacts): measured on the lap joint at H = 5, processor time of the whole
#: forced response, dense against Krylov: 29.8 against 33.8 s at 32 pairs (707 unknowns),
#: 208 against 75 s at 100 pairs (2203 unknowns) (docs/interfaces.md)
FORCED_MATRIX_FREE_MIN_UNKNOWNS = 1000
#: GMRES iterations a reused preconditioner gets before a new one is built
_REUSE_ITERATIONS = 40
#: extra GMRES iterations of a reused preconditioner, over its first solve's, from which it
#: is rebuilt: about what a rebuild costs (the (H+1) blocks and their LUs) in iterations (one
#: operator product and (H+1) triangular solves each), measured ~9 on the 100-pair lap joint
#: at H = 5 (docs/interfaces.md)
_REBUILD_MARGIN = 8


def resolve_forced_solver(linear_solver: str, n_unknowns: int, matrix_free: bool = False) -> str:
    """"dense" or "krylov" for the option and a problem of ``n_unknowns`` unknowns
    (ValueError naming a bad value); ``matrix_free``: the Krylov path would apply the
    Jacobian as an operator (:mod:`~mmshbm.methods.mms.forced_operator`), which moves the
    crossover down to :data:`FORCED_MATRIX_FREE_MIN_UNKNOWNS`."""
    if check_linear_solver(linear_solver) == "auto":
        least = FORCED_MATRIX_FREE_MIN_UNKNOWNS if matrix_free else FORCED_KRYLOV_MIN_UNKNOWNS
        return "krylov" if n_unknowns >= least else "dense"
    return linear_solver


def forced_harmonic_columns(n_c: int, H: int, n_rows: int) -> list[np.ndarray]:
    """The unknowns of each harmonic k = 0..H among the first ``n_rows`` (the rows of the
    residual: n_c (2H+1), plus 2 tracked harmonic-1 unknowns when n_rows exceeds that)."""
    n_x = n_c * (2 * H + 1)
    cols = [np.arange(n_c)]
    for k in range(1, H + 1):
        cols.append(np.arange((2 * k - 1) * n_c, (2 * k + 1) * n_c))
    if n_rows > n_x:
        cols[1] = np.concatenate([cols[1], np.arange(n_x, n_rows)])
    return cols


class ForcedKrylovSolver(KrylovCorrector):
    """Preconditioned GMRES for the forced problem's bordered and square systems (module
    docstring).

    Parameters
    ----------
    n_c, H : int
        Massless DOFs and harmonics of the problem.
    rtol : float
        GMRES's relative residual tolerance.
    max_krylov : int
        Most GMRES iterations of one solve before the dense fallback.
    rebuild_margin : int
        A reused preconditioner whose solve takes more GMRES iterations than the fresh
        one's first solve plus this many is rebuilt at the next solve.
    """

    def __init__(self, n_c: int, H: int, rtol: float = 1e-10, max_krylov: int = 200,
                 rebuild_margin: int = _REBUILD_MARGIN):
        self.n_c, self.H = int(n_c), int(H)
        self.rtol = float(rtol)
        self.max_krylov = int(max_krylov)
        self._blocks = None
        self._rows = None
        self.krylov_iterations = 0
        self.solves = 0
        self.fallbacks = 0
        self.rebuilds = 0
        self._pre = None
        self._pre_size = None
        self.rebuild_margin = int(rebuild_margin)
        self._fresh_iterations = 0
        self._square = None  # (n, preconditioner, its first solve's iterations) of square_solve

    def _set_rows(self, n_rows: int) -> None:
        if self._rows != n_rows:
            cols = forced_harmonic_columns(self.n_c, self.H, n_rows)
            self._blocks = [np.asarray(c, dtype=np.intp) for c in cols]
            self._rows = n_rows

    def bordered_solve(self, J: np.ndarray, t: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        """x with [J; tᵀ] x = rhs (J (n−1, n), its last column ∂R/∂Ω): the corrector's solve.

        The last preconditioner is tried first (the active set changes little from one
        iterate or point to the next) for at most :data:`_REUSE_ITERATIONS` GMRES
        iterations; then a new one is built at this J."""
        if not hasattr(J, "harmonic_block"):
            J = np.asarray(J, dtype=float)
        t = np.asarray(t, dtype=float)
        rhs = np.asarray(rhs, dtype=float)
        self._set_rows(J.shape[0])
        if self._pre is not None and self._pre_size == J.shape[1]:
            x, its, ok = _right_gmres(J, t, rhs, self._pre, self.rtol, _REUSE_ITERATIONS)
            self.krylov_iterations += its
            if ok:
                self.solves += 1
                if its > self._fresh_iterations + self.rebuild_margin:
                    self._pre = None  # stale: the next solve builds a new one
                return x
        self._pre = self._preconditioner(J, t)
        self._pre_size = J.shape[1]
        self.rebuilds += 1
        before = self.krylov_iterations
        x = self.solve(J, t, rhs, self._pre)
        self._fresh_iterations = self.krylov_iterations - before
        return x

    def tangent(self, J: np.ndarray, t_prev: np.ndarray):
        """(x, 0) with [J; t_prevᵀ] x = e_n (the continuation's ``solved_tangent``; the sign
        of the determinant is not computed: 0)."""
        e = np.zeros(J.shape[1])
        e[-1] = 1.0
        x = self.bordered_solve(J, t_prev, e)
        return (x, 0.0) if np.all(np.isfinite(x)) else None

    def square_solve(self, J, rhs: np.ndarray) -> np.ndarray:
        """x with J x = rhs (J square, Ω fixed: an array, or a
        :class:`~mmshbm.methods.mms.forced_operator.CondensedLawOperator`): GMRES
        preconditioned by the harmonics' blocks, the dense LU when it does not converge.

        As :meth:`bordered_solve`, the last square system's blocks are tried first (Newton's
        iterates at one frequency change the law's derivatives little) for at most
        :data:`_REUSE_ITERATIONS` iterations, and rebuilt at this J when they fail or take
        ``rebuild_margin`` more iterations than their first solve."""
        operator = hasattr(J, "block")
        if not operator:
            J = np.asarray(J, dtype=float)
        n = J.n_x if operator else J.shape[0]
        self._set_rows(n)
        self.solves += 1
        rhs = np.asarray(rhs, dtype=float)
        if operator:
            scale, apply = float(J.abs_row_bound(np.ones(n)).max()), J.matvec
        else:
            scale, apply = float(np.abs(J).sum(axis=1).max()), J.__matmul__
        reused = self._square
        if reused is not None and reused[0] == n:
            x, its, ok = gmres_operator(apply, rhs, reused[1], self.rtol, _REUSE_ITERATIONS, scale)
            self.krylov_iterations += its
            if ok:
                if its > reused[2] + self.rebuild_margin:
                    self._square = None
                return x
        self._square = None
        factors = []
        for k, idx in enumerate(self._blocks):
            lu = la.lu_factor(J.block(k) if operator else J[np.ix_(idx, idx)], check_finite=False)
            if not np.all(np.isfinite(lu[0])) or np.any(np.diag(lu[0]) == 0.0):
                factors = None
                break
            factors.append((idx, lu))
        if factors is not None:
            def pre(v):
                out = np.empty(n)
                for idx, lu in factors:
                    out[idx] = la.lu_solve(lu, v[idx], check_finite=False)
                return out

            self.rebuilds += 1
            x, its, ok = gmres_operator(apply, rhs, pre, self.rtol, self.max_krylov, scale)
            self.krylov_iterations += its
            if ok:
                self._square = (n, pre, its)
                return x
        self.fallbacks += 1
        log.debug("GMRES did not converge on a %d-unknown forced system; dense LU instead", n)
        if operator:
            if n > DENSE_FALLBACK_MAX:
                return np.full(n, np.nan)
            J = J.toarray()
        try:
            return la.solve(J, rhs, check_finite=False)
        except la.LinAlgError:
            return np.full(n, np.nan)
