"""The Jacobian of the forced response with friction as an operator, never assembled.

On the massless DOFs the friction forced problem
(:class:`~mmshbm.methods.mms.friction_forced.FrictionForcedProblem`) solves R(x) = 0 with
F = 𝔻 x − P the force the structure needs (𝔻 = diag_k(D_k), the condensed dynamic stiffness,
a dense n_c × n_c complex block per harmonic k = 0..H) and, per friction DOF t, the play
law R_t = F_t − g_t(x_t − F_t/ρ_t) (other massless DOFs: R_i = F_i). The law is per node:
its derivatives are (2H+1) × (2H+1) blocks of node t alone (:mod:`mmshbm.methods.mms._law_blocks`),
so

    ∂R/∂x v = A (𝔻 v) + B v,   A_t = I + J_g,t/ρ_t,  B_t = −J_g,t,

with A, B block-diagonal per node. :class:`CondensedLawOperator` keeps the D_k and the
J_g,t (n_c² (H+1) complex and n_f (2H+1)² real numbers, against n_x² = (n_c (2H+1))² for the
assembled Jacobian: 11× fewer at H = 5, and no n_x² product A·𝔻 per Newton iteration) and
applies the product in O((H+1) n_c²): a batched matrix–vector product per harmonic, then the
node blocks. The J_g,t are the exact derivatives of the play projection (the law has memory
within the period, so in the time domain its derivative is not diagonal per sample; its
harmonic blocks are small and exact, and cheaper to apply than a transform to samples and
back).

The preconditioner of :mod:`mmshbm.methods.mms.forced_krylov` needs, per harmonic k, the
square block of the Jacobian on the unknowns of harmonic k: A_kk 𝔻_k + B_kk, A_kk and B_kk
the entries of the node blocks on harmonic k (diagonal per DOF), formed here in O(n_c²)
(:meth:`CondensedLawOperator.block`).

:class:`ForcedJacobian` is the continuation's scaled Jacobian (n_rows, n_unknowns): the
x block above between the problem's row and column scales, the Ω column ∂R/∂Ω = A (∂𝔻/∂Ω x
− ∂P/∂Ω) (a vector) and, where the amplitude DOF carries mass, the two rows of its tracked
harmonic (dense, 2 × n_unknowns). It solves its own bordered systems
(:meth:`ForcedJacobian.bordered_solve`, the protocol :func:`mmshbm.core.bordered.bordered_solve`
dispatches to) with the problem's GMRES solver.

Scope: friction contacts with constant slip forces in the play form (the compiled rows) and
no unilateral contacts (:func:`supports_matrix_free`); elsewhere the Krylov path multiplies
by the assembled Jacobian.
"""

from __future__ import annotations

import numpy as np

from .forced_krylov import forced_harmonic_columns

__all__ = ["CondensedLawOperator", "ForcedJacobian", "condensed_product", "real_blocks",
           "supports_matrix_free", "evaluate_matrix_free", "square_operator"]


def supports_matrix_free(problem) -> bool:
    """True when ``problem`` (a friction forced problem) has the structure this module
    applies: the play form with constant slip forces (compiled rows) and no unilateral
    contacts."""
    return bool(problem._compiled_rows) and not problem.model.contacts


def condensed_product(D: np.ndarray, x: np.ndarray) -> np.ndarray:
    """𝔻 x (n_x,) for complex D (H+1, n_c, n_c) and NLvib-ordered real x (n_x,) (coefficient
    m of DOF i at m n_c + i): harmonic k of x is X̂_k = x_c − i x_s, (𝔻x)_c = Re(D_k X̂_k),
    (𝔻x)_s = −Im(D_k X̂_k) (the convention of
    :meth:`~mmshbm.methods.mms.damped.DampedHBMBase.real_blocks`)."""
    n_c = D.shape[1]
    X = x.reshape(-1, n_c)
    out = np.empty_like(X)
    out[0] = D[0].real @ X[0]  # D_0 is real (no damping at k = 0)
    if D.shape[0] > 1:
        Z = X[1::2] - 1j * X[2::2]  # (H, n_c)
        W = np.matmul(D[1:], Z[:, :, None])[:, :, 0]
        out[1::2] = W.real
        out[2::2] = -W.imag
    return out.ravel()


def real_blocks(D: np.ndarray) -> np.ndarray:
    """The real (n_x, n_x) matrix 𝔻 of the complex D_k (H+1, n_c, n_c), the convention of
    :func:`condensed_product`."""
    H, n_c = D.shape[0] - 1, D.shape[1]
    n = 2 * H + 1
    A = np.zeros((n * n_c, n * n_c))
    A4 = A.reshape(n, n_c, n, n_c)
    A4[0, :, 0, :] = D[0].real
    for k in range(1, H + 1):
        c, s = 2 * k - 1, 2 * k
        A4[c, :, c, :] = D[k].real
        A4[c, :, s, :] = D[k].imag
        A4[s, :, c, :] = -D[k].imag
        A4[s, :, s, :] = D[k].real
    return A


class CondensedLawOperator:
    """∂R/∂x = A 𝔻 + B (n_x × n_x, physical units: N/m) of the forced problem's massless DOFs
    (module docstring), applied without forming it.

    Parameters
    ----------
    D : ndarray, complex (H+1, n_c, n_c)
        The condensed dynamic stiffness per harmonic (N/m).
    rows : ndarray of int (n_f,)
        The friction DOFs among the massless DOFs.
    rho : ndarray (n_f,)
        Their stiffnesses ρ (N/m).
    Jg : ndarray (n_f, 2H+1, 2H+1)
        ∂g/∂y of each friction DOF's play projection (N/m).
    """

    def __init__(self, D: np.ndarray, rows: np.ndarray, rho: np.ndarray, Jg: np.ndarray):
        self.D = np.ascontiguousarray(D)
        self.H = D.shape[0] - 1
        self.n_c = D.shape[1]
        self.n_coef = 2 * self.H + 1
        self.n_x = self.n_c * self.n_coef
        self.rows = np.asarray(rows, dtype=np.intp)
        self.rho = np.asarray(rho, dtype=float)
        self.Jg = Jg
        self._Jg_rho = Jg / self.rho[:, None, None]

    def matvec(self, v: np.ndarray) -> np.ndarray:
        """(A 𝔻 + B) v for v (n_x,)."""
        w = condensed_product(self.D, v)
        if len(self.rows):
            W = w.reshape(self.n_coef, self.n_c)
            V = v.reshape(self.n_coef, self.n_c)
            Wt, Vt = W[:, self.rows].T, V[:, self.rows].T  # (n_f, 2H+1)
            W[:, self.rows] += (np.einsum("tab,tb->at", self._Jg_rho, Wt)
                                - np.einsum("tab,tb->at", self.Jg, Vt))
        return w

    def law_product(self, w: np.ndarray) -> np.ndarray:
        """A w (n_x,): the law's ∂R/∂F on a force direction w (n_x,), e.g. ∂F/∂Ω."""
        out = np.array(w, dtype=float)
        if len(self.rows):
            W = out.reshape(self.n_coef, self.n_c)
            W[:, self.rows] += np.einsum("tab,tb->at", self._Jg_rho, W[:, self.rows].T)
        return out

    def _node_entries(self, a: int, b: int) -> tuple[np.ndarray, np.ndarray]:
        """(A[a, b], B[a, b]) per DOF (n_c,): entry (a, b) of every DOF's law block."""
        A = np.full(self.n_c, 1.0 if a == b else 0.0)
        B = np.zeros(self.n_c)
        A[self.rows] += self._Jg_rho[:, a, b]
        B[self.rows] = -self.Jg[:, a, b]
        return A, B

    def block(self, k: int) -> np.ndarray:
        """The square block of ∂R/∂x on harmonic k's unknowns (n_c × n_c for k = 0, else
        2 n_c × 2 n_c on [cosine DOFs, sine DOFs]): A_kk 𝔻_k + B_kk."""
        n_c = self.n_c
        if k == 0:
            A, B = self._node_entries(0, 0)
            out = A[:, None] * self.D[0].real
            out[np.diag_indices(n_c)] += B
            return out
        c, s = 2 * k - 1, 2 * k
        Dr, Di = self.D[k].real, self.D[k].imag
        top = np.hstack([Dr, Di])    # 𝔻_k's cosine rows
        bot = np.hstack([-Di, Dr])   # its sine rows
        out = np.empty((2 * n_c, 2 * n_c))
        diag = np.arange(n_c)
        for r0, a in ((0, c), (n_c, s)):
            Ac, Bc = self._node_entries(a, c)
            As, Bs = self._node_entries(a, s)
            out[r0:r0 + n_c] = Ac[:, None] * top + As[:, None] * bot
            out[r0 + diag, diag] += Bc
            out[r0 + diag, n_c + diag] += Bs
        return out

    def abs_row_bound(self, colscale: np.ndarray) -> np.ndarray:
        """Upper bound (n_x,) of the row sums of |∂R/∂x| diag(colscale) (the triangle
        inequality through A, |𝔻| and B): the scale of GMRES's round-off floor."""
        n_c, n = self.n_c, self.n_coef
        cs = colscale.reshape(n, n_c)
        d = np.empty((n, n_c))
        d[0] = np.abs(self.D[0].real) @ cs[0]
        for k in range(1, self.H + 1):
            absk = np.abs(self.D[k].real) + np.abs(self.D[k].imag)
            d[2 * k - 1] = absk @ np.maximum(cs[2 * k - 1], cs[2 * k])
            d[2 * k] = d[2 * k - 1]
        out = d.copy()
        if len(self.rows):
            dt = d[:, self.rows].T  # (n_f, n)
            cst = cs[:, self.rows].T
            out[:, self.rows] += (np.einsum("tab,tb->at", np.abs(self._Jg_rho), dt)
                                  + np.einsum("tab,tb->at", np.abs(self.Jg), cst))
        return out.ravel()

    def toarray(self) -> np.ndarray:
        """The assembled n_x × n_x matrix (the dense fallback of a solve GMRES does not
        finish, and checks): 𝔻 in real blocks, then the node blocks on the friction rows."""
        n_c, n = self.n_c, self.n_coef
        out = real_blocks(self.D)
        if len(self.rows):
            D4 = out.reshape(n, n_c, self.n_x)
            Drows = D4[:, self.rows, :]  # (n, n_f, n_x)
            D4[:, self.rows, :] += np.einsum("tab,btj->atj", self._Jg_rho, Drows)
            for t, i in enumerate(self.rows):
                own = np.arange(n) * n_c + i  # node t's coefficients
                out[np.ix_(own, own)] -= self.Jg[t]
        return out


class ForcedJacobian:
    """The friction forced problem's scaled Jacobian (n_rows, n_unknowns) as an operator
    (module docstring): ``J @ v``, the harmonics' square blocks, its Ω column, and
    :meth:`bordered_solve`.

    Parameters
    ----------
    law : CondensedLawOperator
        ∂R/∂x in physical units.
    rowscale, xscale : ndarray (n_x,)
        The problem's row and x-column scales (J_scaled = diag(1/rowscale) J diag(xscale)).
    column : ndarray (n_rows,)
        The scaled last column (∂R/∂Ω times ω_ref over the row scales).
    tracked : ndarray (n_rows − n_x, n_unknowns) or None
        The scaled rows of the tracked harmonic (None without).
    solver : ForcedKrylovSolver
        The problem's GMRES solver (its preconditioner is reused across calls).
    """

    def __init__(self, law: CondensedLawOperator, rowscale, xscale, column, tracked, solver):
        self.law = law
        self.rowscale = rowscale
        self.xscale = xscale
        self.column = column
        self.tracked = tracked
        self.solver = solver
        n_x = law.n_x
        n_rows = n_x + (0 if tracked is None else tracked.shape[0])
        self.shape = (n_rows, n_rows + 1)
        self._blocks = forced_harmonic_columns(law.n_c, law.H, n_rows)

    @property
    def dtype(self):
        return np.dtype(float)

    def matvec(self, v: np.ndarray) -> np.ndarray:
        """J v (n_rows,) for v (n_unknowns,)."""
        n_x = self.law.n_x
        out = self.column * v[-1]
        out[:n_x] += self.law.matvec(v[:n_x] * self.xscale) / self.rowscale
        if self.tracked is not None:
            out[n_x:] += self.tracked @ v
        return out

    def __matmul__(self, v):
        v = np.asarray(v, dtype=float)
        if v.ndim == 2:
            return np.column_stack([self.matvec(c) for c in v.T])
        return self.matvec(v)

    def harmonic_block(self, k: int) -> np.ndarray:
        """J[idx, idx] for harmonic k's unknowns idx (:func:`forced_harmonic_columns`: on
        harmonic 1 with the tracked unknowns)."""
        law, n_x = self.law, self.law.n_x
        idx = self._blocks[k]
        ix = idx[idx < n_x]
        B = law.block(k) * (self.xscale[ix][None, :] / self.rowscale[ix][:, None])
        if len(ix) == len(idx):
            return B
        out = np.zeros((len(idx), len(idx)))
        m = len(ix)
        out[:m, :m] = B
        out[m:] = self.tracked[:, idx]
        return out

    def inf_norm_bound(self) -> float:
        """An upper bound of ‖J‖∞ (the round-off floor's scale)."""
        n_x = self.law.n_x
        rows = self.law.abs_row_bound(self.xscale) / self.rowscale + np.abs(self.column[:n_x])
        best = float(rows.max())
        if self.tracked is not None:
            tracked = np.abs(self.tracked).sum(axis=1) + np.abs(self.column[n_x:])
            best = max(best, float(tracked.max()))
        return best

    def bordered_solve(self, t: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        """x with [J; tᵀ] x = rhs (GMRES, the problem's solver)."""
        return self.solver.bordered_solve(self, t, rhs)

    def toarray(self) -> np.ndarray:
        """The assembled scaled Jacobian (for checks on small problems)."""
        return np.column_stack([self.matvec(e) for e in np.eye(self.shape[1])])


def _law(problem, x: np.ndarray, omega: float, jacobian: bool):
    """(R (n_x,) unscaled, ∂R/∂x operator or None, ∂F/∂Ω (n_x,) or None) at (x, Ω), σ = 1."""
    from ._law_blocks import _law_blocks

    ch = problem._condensed(omega, 0.0, jacobian)
    s, ds = problem.excitation.scale(omega)
    R = condensed_product(ch.D, x) - problem.first_harmonic_vector(s * ch.P[:, 0])
    n_f = len(problem.friction_rows)
    Jg = np.zeros((n_f, problem.n_coef, problem.n_coef))
    tau, cos_t, sin_t = problem._play_tables
    _law_blocks(np.ascontiguousarray(x, dtype=float), problem._friction_rows64, problem.n_c,
                problem.slip_force, problem.rho, tau, cos_t, sin_t, jacobian, R, Jg, np.empty(n_f))
    if not jacobian:
        return R, None, None
    op = CondensedLawOperator(ch.D, problem.friction_rows, problem.rho, Jg)
    dF = (condensed_product(ch.dD_domega, x)
          - problem.first_harmonic_vector(s * ch.dP_domega[:, 0] + ds * ch.P[:, 0]))
    return R, op, dF


def square_operator(problem, x: np.ndarray, omega: float):
    """(R (n_x,), ∂R/∂x as a :class:`CondensedLawOperator`) at fixed Ω, physical units (the
    fixed-frequency Newton of ``solve_at``)."""
    R, op, _ = _law(problem, x, omega, True)
    return R, op


def evaluate_matrix_free(problem, u: np.ndarray, jacobian: bool):
    """The problem's scaled residual and, if asked, its Jacobian as a :class:`ForcedJacobian`
    (what ``FrictionForcedProblem._evaluate`` returns assembled)."""
    x, omega = problem.unpack(u)
    R_x, op, dF = _law(problem, x, omega, jacobian)
    n_x = problem.n_x
    tracked = problem._track is not None
    R = np.empty(n_x + (2 if tracked else 0))
    np.divide(R_x, problem.rowscale, out=R[:n_x])
    if tracked:
        ab = np.asarray(u[n_x:n_x + 2], dtype=float) * problem.length
        rec, drec, dw = problem._tracked(x, omega, jacobian)
        R[n_x:] = (ab - rec) / problem.length
    if not jacobian:
        return R
    column = np.zeros(R.shape[0])
    column[:n_x] = op.law_product(dF) * problem.omega_ref / problem.rowscale
    T = None
    if tracked:
        T = np.zeros((2, problem.n_unknowns))
        T[:, :n_x] = -drec * problem.xscale[None, :] / problem.length
        T[:, n_x:n_x + 2] = np.eye(2)
        column[n_x:] = -dw * problem.omega_ref / problem.length
    return R, ForcedJacobian(op, problem.rowscale, problem.xscale, column, T, problem._krylov)
