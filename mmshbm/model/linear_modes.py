"""Linear modes of a model with its contacts open: the massless DOFs statically condensed,
dense eigen-solves on small models and shift-invert Lanczos on large ones, the
positive-definiteness checks of the model's blocks, and the model's modes and frequencies
kept with it (:class:`ModesMixin`, a mixin of :class:`~mmshbm.model.Model`)."""

from __future__ import annotations

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .. import _validate as check
from .contact import Contact

# Dense eigen-solves below this many linear DOFs (faster and exact), Lanczos above.
_DENSE_EIG_LIMIT = 600


def open_contact_modes(model, n: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """The ``n`` lowest modes of ``model`` (a :class:`~mmshbm.model.Model`) with the contact open.

    Returns
    -------
    frequencies : ndarray, shape (n,)
        Natural frequencies in Hz, ascending.
    modes : ndarray, shape (n_dof, n)
        Mode shapes on all DOFs (massless DOFs follow statically), mass-normalised:
        ``modes.T @ M @ modes = I``.
    """
    n = check.integer("n", n, minimum=1)
    b = model.blocks
    n_l = len(model.l)
    if n > n_l:
        raise ValueError(f"n must be <= the number of DOFs with mass ({n_l}), got {n}")
    if n_l <= _DENSE_EIG_LIMIT or n > n_l // 2:
        lam, phi = _lowest_eigenpairs_dense(model.reduced_stiffness.toarray(), b["M_ll"].toarray(), n)
    else:
        # a fixed start vector makes ARPACK (and so every branch started from its mode) reproducible;
        # shift-invert with a minimum-degree LU (symmetric, diagonal pivots): on 3-D meshes its
        # solves are ~4x cheaper than with scipy's default column ordering
        K_red = model.reduced_stiffness
        lu = spla.splu(sp.csc_matrix(K_red), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})
        op = spla.LinearOperator(K_red.shape, matvec=lu.solve, dtype=float)
        lam, phi = spla.eigsh(K_red, k=n, M=b["M_ll"], sigma=0.0, which="LM", v0=np.ones(n_l), OPinv=op)
        order = np.argsort(lam)
        lam, phi = lam[order], phi[:, order]
    modes = np.zeros((model.n_dof, n))
    modes[model.l] = phi
    if len(model.c):
        modes[model.c] = -la.solve(b["K_cc"], b["K_lc"].T @ phi)
    # fix the sign: the (first) contact DOF of each mode moves toward its stop first
    # (without one: the first friction DOF, or else the first DOF, moves to +)
    first = model.contacts[0] if model.contacts else Contact(
        model.friction[0].dof if model.friction else 0, 0.0, 1)
    sign = np.where(modes[first.dof] * first.side < 0, -1.0, 1.0)
    modes *= sign
    return np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi), modes


def _lowest_eigenpairs_dense(K: np.ndarray, M: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``n`` smallest eigenpairs of ``K φ = λ M φ`` (K, M dense, symmetric positive definite).

    Solved in the inverted form ``M φ = μ K φ`` for the ``n`` largest ``μ = 1/λ``: the direct
    form loses relative accuracy of order eps·λ_max/λ_min in the lowest λ, which on a fine
    beam mesh reaches 1e-5 in the first frequency. Returns ``λ`` ascending, shape (n,), and
    mass-normalised ``φ`` (``φᵀ M φ = I``), shape (N, n).
    """
    N = K.shape[0]
    mu, phi = la.eigh(M, K, subset_by_index=(N - n, N - 1))
    mu, phi = mu[::-1], phi[:, ::-1]
    return 1.0 / mu, phi / np.sqrt(mu)  # eigh gives φᵀ K φ = I, so φᵀ M φ = diag(μ)


def _require_positive_definite(A, what: str) -> None:
    """Raise ValueError unless the symmetric matrix ``A`` is positive definite.

    Uses LU with diagonal pivots after a symmetric fill-reducing permutation P (minimum
    degree on AᵀA + A; = LDLᵀ of P A Pᵀ for a symmetric matrix): by Sylvester's criterion
    all pivots are positive exactly when A is positive definite. The ordering keeps 3-D
    models cheap (the natural order of a 15 000-DOF solid took 411 s and 4.4 GiB, the
    minimum-degree order 0.1 s); if SuperLU had to leave the diagonal (a zero pivot) the
    matrix is not positive definite.
    """
    if sp.issparse(A):
        n = A.shape[0]
        if n == 0:
            return
        try:
            lu = spla.splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                           options={"SymmetricMode": True})
            pivots = lu.U.diagonal()
        except RuntimeError:
            raise ValueError(f"{what} is singular (is the structure fixed?)") from None
        if not np.array_equal(lu.perm_r, lu.perm_c):
            raise ValueError(f"{what} is singular or indefinite (a zero pivot): is the structure fixed, and "
                             "are M and K positive (semi)definite?")
    else:
        A = np.asarray(A)
        if A.size == 0:
            return
        try:
            la.cholesky(A)
            return
        except la.LinAlgError:
            pivots = np.linalg.eigvalsh(A)
    scale = np.max(np.abs(pivots))
    worst = np.min(pivots)
    if not worst > 1e-13 * scale:
        kind = "singular" if abs(worst) <= 1e-13 * scale else "indefinite"
        raise ValueError(f"{what} is {kind} (smallest pivot {worst:.3e}, largest {scale:.3e}): "
                         "is the structure fixed, and are M and K positive (semi)definite?")


class ModesMixin:
    """Linear modes and frequencies of a model with its contacts open, kept with the model
    (needs the attributes of :class:`~mmshbm.model.Model`)."""

    def linear_modes(self, n: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """The ``n`` lowest modes with the contact open (see :meth:`_linear_modes`); the
        result for each ``n`` is kept with the model (immutable), so a repeated call costs a
        copy. (Not sliced from a larger solve: the same call gives the same bits whatever was
        asked before.)"""
        n = check.integer("n", n, minimum=1)
        memo = self.__dict__.setdefault("_memo_modes", {})
        if n not in memo:
            memo[n] = self._linear_modes(n)
        freqs, modes = memo[n]
        return freqs.copy(), modes.copy()

    def _linear_modes(self, n: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """The ``n`` lowest modes with the contact open
        (:func:`~mmshbm.model.linear_modes.open_contact_modes`)."""
        return open_contact_modes(self, n)

    def linear_frequencies(self, n: int = 1) -> np.ndarray:
        """The ``n`` lowest natural frequencies (Hz) with the contact open."""
        return self.linear_modes(n)[0]

    def zero_gap_frequency(self) -> float:
        """Frequency (Hz) of the first mode's bilinear limit (gap → 0 or amplitude → ∞):
        half a period open, half a period with the contact DOF held at the stop,
        f = 2 / (1/f_open + 1/f_closed). Exact for one DOF; on a structure whose open and
        held first modes differ in shape an estimate (a chain's first-mode orbit above a
        2:1 tongue lies up to 31 % above it at 10 gaps, docs/resonances.md). Kept with the
        model after the first call."""
        memo = self.__dict__.get("_memo_zero_gap")
        if memo is None:
            memo = self._zero_gap_frequency()
            self.__dict__["_memo_zero_gap"] = memo
        return memo

    def _zero_gap_frequency(self) -> float:
        contact = self._single("zero-gap limit")
        f_open = self.linear_frequencies(1)[0]
        closed = np.setdiff1d(np.arange(self.n_dof), [contact.dof])
        sub = type(self)(self.M[closed][:, closed], self.K[closed][:, closed], (Contact(0, 0.0, 1),))
        f_closed = sub.linear_frequencies(1)[0]  # sparse eigen-solve on large models
        return 2.0 / (1.0 / f_open + 1.0 / f_closed)



def amplitude_mode(model, mode: int = 1) -> tuple[float, np.ndarray]:
    """Linear mode ``mode`` (1-based) of ``model`` scaled to a unit motion of its amplitude DOF.

    Returns
    -------
    frequency : float
        The mode's frequency, Hz.
    shape : ndarray, shape (n_dof,)
        The mode shape divided by the magnitude of its entry at ``model.amplitude_dof``.

    Raises
    ------
    ValueError
        If the mode does not move the amplitude DOF (its entry below 1e-12 of the largest).
    """
    freqs, modes = model.linear_modes(mode)
    phi = modes[:, -1]
    ref = phi[int(model.amplitude_dof)]
    if abs(ref) < 1e-12 * np.max(np.abs(phi)):
        raise ValueError(f"linear mode {mode} does not move the amplitude DOF {int(model.amplitude_dof)}")
    return float(freqs[-1]), phi / abs(ref)
