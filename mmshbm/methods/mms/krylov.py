"""A Newton–Krylov corrector for MMS-HBM with many contact DOFs.

The dense corrector (:mod:`mmshbm.methods.mms.corrector_kernels`) factorises the bordered
Jacobian of all contact harmonics, n = (H+1)·n_c + n_p + 1 unknowns, by LU at every Newton
iteration: O(n³), 8× per doubling of the contact DOFs. This corrector keeps the same
residual, Jacobian and convergence tests and replaces only that solve.

Structure. With P the block-diagonal (per contact DOF, (H+1) × (H+1)) projection of the
active set and 𝔻 = diag_k(D_k) the condensed dynamic stiffness (n_c × n_c per harmonic),
the contact rows of the Jacobian are (I − P) 𝔻 + r P (:mod:`mmshbm.methods.mms.contact_kernels`).
P_mk = ε_m/2 (C_|m−k| + C_m+k), C the active set's cosine spectrum, so its diagonal is
the time-averaged active set (C_0) plus C_2k, and the coupling between harmonics lives in
the off-diagonal entries. The preconditioner keeps the diagonal blocks: per harmonic k
the square block of J on the unknowns of harmonic k (a_k and the pole unknowns η_jk of
that harmonic, :meth:`MMSHBMProblem.harmonic_columns`), (I − diag P_kk) D_k + r diag P_kk,
one LU of n_c (+ poles) per harmonic — (H+1) n_c³/3 flops instead of ((H+1) n_c)³/3.
The bordering row (arclength) and column (∂R/∂Ω) are added to the preconditioner exactly
by block elimination onto the fundamental harmonic's block (whose own block is singular
on the linear mode, :meth:`KrylovCorrector._preconditioner`).

Right-preconditioned GMRES (:func:`_right_gmres`, whose residual is the true one: a
left-preconditioned GMRES stalls on the preconditioned residual above the round-off floor)
then solves the bordered system with the Jacobian applied as a dense product (O(n²) per
application) to a relative residual of ``rtol`` (default 1e-10), or to a backward error
of 1e-13 √n ‖[J; tᵀ]‖∞ ‖x‖∞ where that is larger (the round-off floor: near convergence
the right-hand side is small). The next Newton residual then carries at most ~rtol times
the current one from the inexact solve, far below the Newton tolerance, so the converged
points are those of the dense path to that tolerance. A solve that GMRES does not finish
within ``max_krylov`` iterations falls back to the dense LU of the bordered matrix (logged
at DEBUG, counted in :attr:`KrylovCorrector.fallbacks`): it costs an LU, not the step.

The preconditioner is built at the corrector's first iterate and kept for the later
solves of the call and for the tangent (it needs to be near J, not equal: GMRES's
stopping test is on the true residual). The tangent at the converged point is solved
the same way and handed to the continuation (the problem's ``solved_tangent``). The
sign of det [J; tᵀ] (branch-point detection) is not computed on this path: it is reported
as 0, "unknown", as for the sparse Jacobians of :mod:`mmshbm.core.bordered`.
"""

from __future__ import annotations

import logging
import math

import numpy as np
import scipy.linalg as la

__all__ = ["KrylovCorrector", "LINEAR_SOLVERS", "KRYLOV_MIN_UNKNOWNS", "check_linear_solver",
           "resolve_linear_solver"]

log = logging.getLogger(__name__)

#: the corrector's linear solvers: "dense" (LU of the whole bordered Jacobian), "krylov"
#: (this module), "auto" (krylov from KRYLOV_MIN_UNKNOWNS unknowns on)
LINEAR_SOLVERS = ("auto", "dense", "krylov")
#: the size of the bordered system, (H+1)·n_c + n_p + 1 (n_p the pole unknowns), from which
#: ``linear_solver="auto"`` takes the Krylov corrector. The dense corrector's cost is set
#: by that size, not by n_c alone: the contact string carries ~4 pole unknowns per contact
#: at H = 5 (245 unknowns at 24 contacts, 326 at 32), the 16×1×1 solid beam one for its 27
#: massless DOFs (164). Measured on the string at H = 5 (docs/scale.md): dense 1.9 against
#: Krylov 4.1 ms a corrector call at 245 unknowns, 11 against 6 at 326.
KRYLOV_MIN_UNKNOWNS = 300
#: the largest system a solve that GMRES does not finish assembles for the dense LU when its
#: Jacobian is an operator (8000² numbers: 512 MB); a larger one returns NaN (the step fails)
DENSE_FALLBACK_MAX = 8000
#: GMRES's absolute tolerance relative to ‖[J; tᵀ]‖∞ ‖x‖∞ (a backward error of ~450 ε,
#: below which the residual of the bordered system is round-off)
_FLOOR = 1e-13
#: the quadratic-convergence skip needs a tolerance above the scaled residual's round-off
#: floor (the same rule as the dense corrector's)
_SKIP_MIN_TOL = 1e-11


def check_linear_solver(linear_solver: str) -> str:
    """``linear_solver`` itself; raises ValueError naming a value not in LINEAR_SOLVERS."""
    if not isinstance(linear_solver, str) or linear_solver not in LINEAR_SOLVERS:
        raise ValueError(f"linear_solver must be one of {LINEAR_SOLVERS}, got {linear_solver!r}")
    return linear_solver


def resolve_linear_solver(linear_solver: str, n_unknowns: int) -> str:
    """"dense" or "krylov" for the option ``linear_solver`` and a bordered system of
    ``n_unknowns`` unknowns; raises ValueError naming a bad value."""
    if check_linear_solver(linear_solver) == "auto":
        return "krylov" if n_unknowns >= KRYLOV_MIN_UNKNOWNS else "dense"
    return linear_solver


class KrylovCorrector:
    """Newton on [R(u); t·(u − u_pred)] = 0 for an
    :class:`~mmshbm.methods.mms.conservative.MMSHBMProblem`, each linear solve by
    preconditioned GMRES (module docstring).

    Parameters
    ----------
    problem : MMSHBMProblem
        The problem whose scaled residual and Jacobian (``_evaluate``) are solved.
    rtol : float
        GMRES's relative residual tolerance of each solve.
    max_krylov : int
        Most GMRES iterations of one solve before the dense fallback.

    Attributes
    ----------
    krylov_iterations, solves, fallbacks : int
        GMRES iterations and linear solves so far, and solves that fell back to the
        dense LU.
    """

    def __init__(self, problem, rtol: float = 1e-10, max_krylov: int = 200):
        self.problem = problem
        self.rtol = float(rtol)
        self.max_krylov = int(max_krylov)
        n_a = (problem.H + 1) * problem.n_c + problem.n_poles
        self._blocks = [np.asarray(problem.harmonic_columns(k), dtype=np.intp) for k in range(problem.H + 1)]
        covered = np.sort(np.concatenate(self._blocks))
        if not np.array_equal(covered, np.arange(n_a)):
            raise ValueError("the harmonics' unknowns do not partition the residual's unknowns")
        self.krylov_iterations = 0
        self.solves = 0
        self.fallbacks = 0

    # ------------------------------------------------------------------ the linear algebra
    def _preconditioner(self, J: np.ndarray, t: np.ndarray):
        """The bordered preconditioner of [J; tᵀ] (a callable on (n,) vectors), or None
        when a block is exactly singular.

        M = [[B, b], [cᵀ, d]], B = diag_k(B_k) the harmonics' blocks of J, b = ∂R/∂Ω,
        (cᵀ, d) = tᵀ, is solved exactly by eliminating every harmonic but the fundamental
        (x_k = B_k⁻¹(v_k − b_k ξ)), leaving the fundamental's block bordered by the Ω
        column and the reduced arclength row,

            E_1 = [[B_1, b_1], [c_1ᵀ, d − Σ_{k≠1} c_kᵀ B_k⁻¹ b_k]],

        which stays regular where B_1 itself is singular: on the linear mode (Ω = ω_1 and
        every contact open) B_1 has the mode as its null vector, and only the bordering
        makes the branch's system regular."""
        n = J.shape[1]
        if isinstance(J, np.ndarray):
            b = J[:, -1]

            def block(k):
                return J[np.ix_(self._blocks[k], self._blocks[k])]
        else:  # an operator that forms its harmonics' blocks (forced_operator.ForcedJacobian)
            b, block = J.column, J.harmonic_block
        c, d = t[:-1], float(t[-1])
        factors = []
        coupling = 0.0
        for k, idx in enumerate(self._blocks):
            if k == 1:
                continue
            lu = la.lu_factor(block(k), check_finite=False)
            if not np.all(np.isfinite(lu[0])) or np.any(np.diag(lu[0]) == 0.0):
                return None
            z = la.lu_solve(lu, b[idx], check_finite=False)
            coupling += float(c[idx] @ z)
            factors.append((idx, lu, z))
        idx1 = self._blocks[1]
        m = len(idx1)
        E = np.empty((m + 1, m + 1))
        E[:m, :m] = block(1)
        E[:m, m] = b[idx1]
        E[m, :m] = c[idx1]
        E[m, m] = d - coupling
        lu1 = la.lu_factor(E, check_finite=False)
        if not np.all(np.isfinite(lu1[0])) or np.any(np.diag(lu1[0]) == 0.0):
            return None

        def apply(v):
            out = np.empty(n)
            arc = float(v[-1])
            ws = []
            for idx, lu, _z in factors:
                w = la.lu_solve(lu, v[idx], check_finite=False)
                arc -= float(c[idx] @ w)
                ws.append(w)
            rhs1 = np.empty(m + 1)
            rhs1[:m] = v[idx1]
            rhs1[m] = arc
            y = la.lu_solve(lu1, rhs1, check_finite=False)
            xi = y[m]
            out[idx1] = y[:m]
            out[-1] = xi
            for (idx, _, z), w in zip(factors, ws, strict=True):
                out[idx] = w - z * xi
            return out

        return apply

    def solve(self, J: np.ndarray, t: np.ndarray, rhs: np.ndarray, pre=None) -> np.ndarray:
        """x with [J; tᵀ] x = rhs: preconditioned GMRES, else the dense LU (module docstring).
        ``pre``: a preconditioner of this (J, t) from :meth:`_preconditioner`."""
        n = J.shape[1]
        self.solves += 1
        if pre is None:
            pre = self._preconditioner(J, t)
        if pre is not None:
            x, its, converged = _right_gmres(J, t, rhs, pre, self.rtol, self.max_krylov)
            self.krylov_iterations += its
            if converged:
                return x
        self.fallbacks += 1
        log.debug("GMRES did not converge on a %d-unknown bordered system; dense LU instead", n)
        if not isinstance(J, np.ndarray):
            if n > DENSE_FALLBACK_MAX:
                return np.full(n, np.nan)
            J = J.toarray()
        A = np.empty((n, n))
        A[:-1] = J
        A[-1] = t
        try:
            return la.solve(A, rhs, check_finite=False)
        except la.LinAlgError:
            return np.full(n, np.nan)

    # ------------------------------------------------------------------ Newton
    def newton(self, u0, u_pred, t, tol: float, max_iter: int, step_tol: float):
        """The dense corrector's loop (:func:`mmshbm.methods.mms.corrector_kernels._newton_modal`:
        the same convergence tests and quadratic-convergence skip) with Krylov solves.

        Returns (u, iterations, residual history, Jacobian at the last evaluated iterate)
        and sets the problem's solved tangent; raises ArithmeticError with the reason."""
        problem = self.problem
        u = np.array(u0, dtype=float)
        t = np.ascontiguousarray(t, dtype=float)
        u_pred = np.ascontiguousarray(u_pred, dtype=float)
        n = u.shape[0]
        hist = []
        du_norm = math.inf
        problem._solved_tangent = None
        pre = None  # the first iterate's preconditioner, kept for the later solves of the call
        for it in range(max_iter + 1):
            R, J = problem._evaluate(u, True)
            arc = float(t @ (u - u_pred))
            norm = max(float(np.abs(R).max()) if R.size else 0.0, abs(arc))
            if not math.isfinite(norm):
                raise ArithmeticError("non-finite residual")
            hist.append(norm)
            if norm <= tol or (du_norm <= step_tol and norm <= math.sqrt(tol)):
                self._tangent(J, t, pre)
                return u, it, np.array(hist), J
            if it == max_iter:
                break
            rhs = np.empty(n)
            rhs[:-1] = R
            rhs[-1] = arc
            if pre is None:
                pre = self._preconditioner(J, t)
            du = self.solve(J, t, rhs, pre)
            du_norm = float(np.abs(du).max())
            if not math.isfinite(du_norm):
                raise ArithmeticError("singular Jacobian")
            u = u - du
            if it >= 1 and tol >= _SKIP_MIN_TOL:
                r_prev = hist[-2]
                if r_prev > 0.0 and norm <= math.sqrt(tol) and norm <= 0.1 * r_prev:
                    predicted = norm * (norm / r_prev) ** 2
                    if predicted <= 0.1 * tol:
                        hist.append(predicted)
                        self._tangent(J, t, pre)
                        return u, it + 1, np.array(hist), J
        raise ArithmeticError(f"no convergence in {max_iter} iterations (residual {hist[-1]:.2e})")

    def _tangent(self, J, t, pre=None):
        """[J; tᵀ] x = e_n at the returned Jacobian, kept for the continuation's tangent
        (sign 0: not computed)."""
        e = np.zeros(J.shape[1])
        e[-1] = 1.0
        x = self.solve(J, t, e, pre)
        if np.all(np.isfinite(x)):
            self.problem._solved_tangent = (J, t, x, 0.0)


def _right_gmres(J, t, rhs, pre, rtol: float, max_iter: int):
    """GMRES on [J; tᵀ] x = rhs (J an array or an operator with ``@`` and
    ``inf_norm_bound()``), right-preconditioned by ``pre`` (x = x0 + M⁻¹ V y), from
    x0 = pre(rhs), without restarts (Arnoldi by modified Gram–Schmidt, the least-squares
    residual updated by Givens rotations, so the residual it tracks is the true one's in
    exact arithmetic, not a preconditioned one).

    Stops when that residual is <= max(rtol ‖rhs‖₂, _FLOOR ‖[J; tᵀ]‖∞ ‖x0‖∞ √n); then
    checks the true residual against the same bound. Returns (x, iterations, converged)."""
    n = rhs.shape[0]

    def apply(v):
        out = np.empty(n)
        out[:-1] = J @ v
        out[-1] = t @ v
        return out

    norm = float(np.abs(J).sum(axis=1).max()) if isinstance(J, np.ndarray) else J.inf_norm_bound()
    scale = max(norm, float(np.abs(t).sum()))
    return gmres_operator(apply, rhs, pre, rtol, max_iter, scale)


def gmres_operator(apply, rhs: np.ndarray, pre, rtol: float, max_iter: int, scale: float):
    """:func:`_right_gmres` on any operator: ``apply`` a callable (n,) -> (n,), ``scale``
    its ∞-norm (the round-off floor's scale). Returns (x, iterations, converged)."""
    n = rhs.shape[0]
    x0 = pre(rhs)
    if not np.all(np.isfinite(x0)):
        return x0, 0, False
    bound = max(rtol * float(np.linalg.norm(rhs)), _FLOOR * scale * float(np.abs(x0).max()) * math.sqrt(n))
    r0 = rhs - apply(x0)
    beta = float(np.linalg.norm(r0))
    if beta <= bound:
        return x0, 0, True
    m = min(max_iter, n)
    V = np.zeros((m + 1, n))
    Z = np.zeros((m, n))
    Hh = np.zeros((m + 1, m))
    cs, sn = np.zeros(m), np.zeros(m)
    g = np.zeros(m + 1)
    g[0] = beta
    V[0] = r0 / beta
    k = 0
    for k in range(m):
        Z[k] = pre(V[k])
        w = apply(Z[k])
        for i in range(k + 1):
            h = float(w @ V[i])
            Hh[i, k] = h
            w -= h * V[i]
        h_next = float(np.linalg.norm(w))
        Hh[k + 1, k] = h_next
        for i in range(k):  # the earlier rotations on the new column
            a, b = Hh[i, k], Hh[i + 1, k]
            Hh[i, k], Hh[i + 1, k] = cs[i] * a + sn[i] * b, -sn[i] * a + cs[i] * b
        a, b = Hh[k, k], Hh[k + 1, k]
        rho = math.hypot(a, b)
        if rho == 0.0 or not math.isfinite(rho):
            return x0, k + 1, False
        cs[k], sn[k] = a / rho, b / rho
        Hh[k, k], Hh[k + 1, k] = rho, 0.0
        g[k + 1] = -sn[k] * g[k]
        g[k] = cs[k] * g[k]
        if abs(g[k + 1]) <= bound or h_next == 0.0:
            break
        V[k + 1] = w / h_next
    y = la.solve_triangular(Hh[: k + 1, : k + 1], g[: k + 1], check_finite=False)
    x = x0 + Z[: k + 1].T @ y
    ok = bool(np.all(np.isfinite(x))) and float(np.linalg.norm(rhs - apply(x))) <= 2.0 * bound
    return x, k + 1, ok
