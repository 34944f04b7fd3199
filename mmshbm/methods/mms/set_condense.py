"""The linear structure condensed per harmonic onto a chosen set of DOFs (with or without mass).

MMS-HBM condenses the structure onto its massless DOFs (:mod:`mmshbm.harmonic.condense`). A
smooth element needs no massless DOF: its DOFs may carry mass, and the structure is
condensed exactly onto the set ``s`` of the element DOFs (and the contact and amplitude
DOFs), every other DOF ``o`` eliminated per harmonic k from the dynamic stiffness

    S_k(Ω) = K − (kΩ)² M + i kΩ (C − ξ M)        (n, n), symmetric,
    X_k = S_oo⁻¹ S_os,   D_k = S_ss − S_so X_k = T_kᵀ S_k T_k,   T_k = [I; −X_k],
    ∂D_k/∂Ω = T_kᵀ (∂S_k/∂Ω) T_k,        ∂S_k/∂Ω = −2k²Ω M + i k (C − ξ M),

and likewise ∂D_k/∂ξ = T_kᵀ (−ikΩ M) T_k (ξ: the negative mass-proportional damping of
the extended periodic motion concept, 0 elsewhere).

A load F on the DOFs (harmonic k) condenses to P_k = T_kᵀ F = F_s − X_kᵀ F_o with
Y_k = S_oo⁻¹ F_o, ∂P_k/∂Ω = −T_kᵀ (∂S_k/∂Ω) [0; Y_k]; the eliminated DOFs follow as
q_o,k = Y_k − X_k q_s,k. The formulas use S_k = S_kᵀ (K, M, C symmetric).

D_k has poles where kΩ is an eigenfrequency of the structure with the set held: there
S_oo is singular and :class:`~mmshbm.harmonic._errors.SingularDynamicStiffness` (an
ArithmeticError: the continuation retries a smaller step) is raised. Through a pole det D_k
changes sign through infinity (det S_k = det S_oo det D_k); the undamped condensation
returns sgn det S_oo,k with D_k (:attr:`SetCondensation.pole_signs`), so that a residual can
keep the sign of its Jacobian's determinant where only a pole is crossed. Small models are
solved dense, larger ones with a sparse LU per harmonic.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...harmonic._errors import SingularDynamicStiffness

__all__ = ["SetCondensation"]

#: dense solves up to this many eliminated DOFs, sparse LU above
_DENSE_LIMIT = 400
#: a pivot below this fraction of the largest one makes S_oo singular
_PIVOT_RTOL = 1e-13


class SetCondensation:
    """The dynamic stiffness of ``model`` condensed onto the DOFs ``dofs``.

    Parameters
    ----------
    model : Model
        The linear structure (M, K, damping).
    dofs : sequence of int
        The kept DOFs s (sorted, distinct); every other DOF is eliminated.
    """

    def __init__(self, model, dofs):
        s = np.asarray(sorted(set(int(d) for d in dofs)), dtype=int)
        n = model.n_dof
        o = np.setdiff1d(np.arange(n), s)
        self.s, self.o = s, o
        self.n_s, self.n_o = len(s), len(o)
        self.damped = model.damping is not None
        mats = {"K": model.K, "M": model.M}
        if self.damped:
            mats["C"] = model.damping
        self.dense = self.n_o <= _DENSE_LIMIT
        self._blocks = {}
        for name, A in mats.items():
            A = sp.csr_matrix(A)
            ss = A[s][:, s].toarray()
            so = A[s][:, o].toarray()
            oo = A[o][:, o]
            self._blocks[name] = (ss, so, oo.toarray() if self.dense else oo.tocsc())
        #: Ω -> per-harmonic (X_k (n_o, n_s), solver of S_oo) of the last evaluation, and its ξ
        self._last = (None, None, None)
        self._last_xi = 0.0
        self.dD_dxi = None

    # ------------------------------------------------------------------ matrices
    def _parts(self, k: int, omega: float, damped: bool, xi: float = 0.0):
        """(S_ss, S_so, S_oo), their Ω-derivatives and their ξ-derivatives at harmonic k."""
        w = k * omega
        Kss, Kso, Koo = self._blocks["K"]
        Mss, Mso, Moo = self._blocks["M"]
        S = [Kss - w * w * Mss, Kso - w * w * Mso, Koo - w * w * Moo]
        dS = [-2.0 * k * w * Mss, -2.0 * k * w * Mso, -2.0 * k * w * Moo]
        dS_xi = [-1j * w * Mss, -1j * w * Mso, -1j * w * Moo]
        if damped and self.damped:
            Css, Cso, Coo = self._blocks["C"]
            S = [S[0] + 1j * w * (Css - xi * Mss), S[1] + 1j * w * (Cso - xi * Mso),
                 S[2] + 1j * w * (Coo - xi * Moo)]
            dS = [dS[0] + 1j * k * (Css - xi * Mss), dS[1] + 1j * k * (Cso - xi * Mso),
                  dS[2] + 1j * k * (Coo - xi * Moo)]
        return S, dS, dS_xi

    def _factor(self, S_oo, k: int, omega: float):
        """(a solver of S_oo x = b, sgn det S_oo (1.0 for a complex S_oo));
        SingularDynamicStiffness where S_oo is singular."""
        real = not np.iscomplexobj(S_oo)
        if self.dense:
            lu, piv = la.lu_factor(S_oo, check_finite=False)
            diagonal = np.diag(lu)
            pivots = np.abs(diagonal)
            if not np.all(np.isfinite(pivots)) or pivots.min() <= _PIVOT_RTOL * max(pivots.max(), 1e-300):
                raise SingularDynamicStiffness(self._singular_message(k, omega))
            sign = 1.0
            if real:  # the row swaps' parity times the pivots' signs
                swaps = int(np.count_nonzero(piv != np.arange(len(piv))))
                sign = (-1.0) ** swaps * float(np.prod(np.sign(diagonal)))
            return (lambda b: la.lu_solve((lu, piv), b, check_finite=False)), sign
        try:
            lu = spla.splu(sp.csc_matrix(S_oo))
        except RuntimeError:  # "Factor is exactly singular"
            raise SingularDynamicStiffness(self._singular_message(k, omega)) from None
        sign = 1.0
        if real:  # det = det(P_r) det(L) det(U) det(P_c), L unit lower triangular
            sign = _parity(lu.perm_r) * _parity(lu.perm_c) * float(np.prod(np.sign(lu.U.diagonal())))
        return lu.solve, sign

    @staticmethod
    def _singular_message(k: int, omega: float) -> str:
        return (f"the structure with the condensed DOFs held is singular at harmonic {k} of "
                f"Ω = {omega:.9g} rad/s: kΩ sits on one of its eigenfrequencies")

    # ------------------------------------------------------------------ condensation
    def dynamic_stiffness(self, omega: float, harmonics: int, derivative: bool = True, damped: bool = False,
                          xi: float = 0.0):
        """(D, dD): D_k and ∂D_k/∂Ω for k = 0..H, shape (H+1, n_s, n_s); real undamped
        (``damped=False``, the damping left out), complex with ``damped`` on a damped
        model (with the negative damping ``xi`` (1/s), 1/s: C − ξM); dD None unless
        ``derivative``, which also sets :attr:`dD_dxi` (∂D_k/∂ξ; damped only). Keeps X_k
        for :meth:`recover` and :meth:`condensed_load`."""
        cplx = damped and self.damped
        dtype = complex if cplx else float
        H1 = harmonics + 1
        D = np.empty((H1, self.n_s, self.n_s), dtype=dtype)
        dD = np.empty_like(D) if derivative else None
        dD_xi = np.empty((H1, self.n_s, self.n_s), dtype=complex) if derivative and cplx else None
        X_all, solvers = [], []
        signs = np.ones(H1)
        for k in range(H1):
            S, dS, dS_xi = self._parts(k, omega, damped, xi)
            if self.n_o:
                solve, signs[k] = self._factor(S[2], k, omega)
                X = solve(np.asarray(S[1].T, dtype=dtype))
                X = X.reshape(self.n_o, self.n_s)
                D[k] = S[0] - S[1] @ X
                if derivative:
                    dD[k] = _congruence(dS, X)
                    if dD_xi is not None:
                        dD_xi[k] = _congruence(dS_xi, X)
            else:
                solve, X = None, np.zeros((0, self.n_s), dtype=dtype)
                D[k] = S[0]
                if derivative:
                    dD[k] = dS[0]
                    if dD_xi is not None:
                        dD_xi[k] = dS_xi[0]
            X_all.append(X)
            solvers.append(solve)
        #: ∂D_k/∂ξ (H+1, n_s, n_s) of the last damped call with ``derivative`` (else None)
        self.dD_dxi = dD_xi
        self._last = (float(omega), (cplx, X_all), solvers)
        self._last_xi = float(xi)
        #: sgn det S_oo,k (H+1,) of the last call (1 where complex or nothing is eliminated)
        self.pole_signs = signs
        return D, dD

    def _kept(self, omega: float, harmonics: int, damped: bool, xi: float = 0.0):
        last, kept, solvers = self._last
        cplx = damped and self.damped
        if (last != float(omega) or kept is None or kept[0] != cplx or len(kept[1]) < harmonics + 1
                or self._last_xi != xi):
            self.dynamic_stiffness(omega, harmonics, derivative=False, damped=damped, xi=xi)
            last, kept, solvers = self._last
        return kept[1], solvers

    def recover(self, omega: float, harmonics: int, damped: bool = False,
                xi: float = 0.0) -> list[np.ndarray]:
        """[X_k (n_o, n_s)] for k = 0..H: the eliminated DOFs of a free harmonic follow as
        q_o,k = −X_k q_s,k."""
        return self._kept(omega, harmonics, damped, xi)[0][: harmonics + 1]

    def condensed_load(self, omega: float, k: int, load: np.ndarray, harmonics: int, damped: bool = True):
        """(P_k (n_s,), ∂P_k/∂Ω (n_s,), Y_k (n_o,)) of the load ``load`` (n_dof,) at harmonic
        k (module docstring)."""
        X_all, solvers = self._kept(omega, harmonics, damped)
        load = np.asarray(load)
        F_s, F_o = load[self.s], load[self.o]
        if not self.n_o:
            return F_s.astype(complex), np.zeros(self.n_s, dtype=complex), np.zeros(0, dtype=complex)
        X = X_all[k]
        solve = solvers[k]
        if damped and self.damped:
            Y = np.asarray(solve(np.asarray(F_o, dtype=complex))).reshape(self.n_o)
        else:  # a real factorisation: real and imaginary parts apart
            F_o = np.asarray(F_o, dtype=complex)
            Y = (np.asarray(solve(np.ascontiguousarray(F_o.real))).reshape(self.n_o)
                 + 1j * np.asarray(solve(np.ascontiguousarray(F_o.imag))).reshape(self.n_o))
        dS = self._parts(k, omega, damped)[1]
        P = F_s - X.T @ F_o
        dP = -(dS[1] @ Y - X.T @ (dS[2] @ Y))
        return P, dP, Y


def _congruence(dS, X: np.ndarray) -> np.ndarray:
    """T_kᵀ dS T_k = dS_ss − dS_so X − Xᵀ dS_os + Xᵀ dS_oo X (dS = [dS_ss, dS_so, dS_oo],
    symmetric)."""
    return dS[0] - dS[1] @ X - X.T @ dS[1].T + X.T @ (dS[2] @ X)


def _parity(perm: np.ndarray) -> float:
    """The sign (±1.0) of the permutation ``perm`` (by its cycles)."""
    perm = np.asarray(perm)
    seen = np.zeros(len(perm), dtype=bool)
    sign = 1.0
    for start in range(len(perm)):
        if seen[start]:
            continue
        length, j = 0, start
        while not seen[j]:
            seen[j] = True
            j = perm[j]
            length += 1
        if length % 2 == 0:
            sign = -sign
    return sign
