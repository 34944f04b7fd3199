"""The one-time reduction behind the modal condensation: fixed-interface modes and static parts.

With the massless DOFs ``c`` clamped, the DOFs with mass ``l`` have the normal modes

    K_ll φ_j = ω_j² M_ll φ_j,        φ_iᵀ M_ll φ_j = δ_ij,        b_j = K_cl φ_j  (n_c,).

A :class:`ModalReduction` holds the k lowest of them (or all, for small models) and what
the modes left out contribute, in closed form (no more eigenvectors needed):

    D_0  = K_cc − K_cl K_ll⁻¹ K_lc                                   (exact static part)
    Ṽ_i  = Σ_{j>k} φ_j b_jᵀ / ω_j^{2i+2},   i = 0..q                  (n_l × n_c)
    R(p) = Σ_{j>k} b_j b_jᵀ / ω_j^{2p} = Ṽ_aᵀ M_ll Ṽ_b,  a + b = p − 2,  p = 2..2q+2

The Ṽ_i are a block Krylov sequence of K_ll⁻¹ M_ll started from Z_0 = K_ll⁻¹ K_lc,
M-orthogonally deflated against the computed modes: Ṽ_0 = P⊥ Z_0,
Ṽ_i = P⊥ K_ll⁻¹ M_ll Ṽ_{i−1}, P⊥ = I − Φ Φᵀ M_ll (the complement of an invariant subspace
is invariant under K⁻¹M; the projection is reapplied against round-off). Deflating
first, instead of subtracting the kept modes' share from the full moments, avoids a
cancellation that would destroy R(p) for p >= 3 (the first mode dominates the full
moments by (ω_{k+1}/ω_1)^{2p}). Keeping fewer modes m < k only *adds* positive terms:
R(p; m) = R(p; k) + Σ_{m<j<=k} b_j b_jᵀ/ω_j^{2p}.

How the modes are found
    ``n_l <= dense_limit``: every mode by a dense symmetric eigen-solve of the inverted
    pencil ``M φ = μ K φ`` (μ = 1/ω²: the lowest modes, which dominate the condensation,
    keep full relative accuracy); then Ṽ = 0 and R = 0. Larger models: the lowest ``k``
    modes by ARPACK in shift-invert mode about σ = 0 with one sparse LU of K_ll
    (SuperLU, minimum-degree ordering on AᵀA+A, diagonal pivots: K_ll is symmetric
    positive definite), ``k`` doubled until the caller's selection rule is satisfied;
    the same factor gives D_0 and the Krylov blocks (n_c (q+1) solves).

Caching (why it is keyed this way)
    The reduction depends on M and K only, not on the contacts, the gap, the damping or
    the amplitude DOF. Its key is therefore :meth:`Model.fingerprint` of the *bare
    structure* (the model with one dummy contact and no damping or amplitude DOF), so a
    study over gaps, or ``with_amplitude_dof``, reuses one reduction. Two levels:
    in memory per model object (a weak dictionary: it goes with the model), and on disk
    when the caller names a file or a directory (``cache=``): ``modal-<key>.npz``, a
    plain ``.npz`` that is checked against the key on load and extended (then
    rewritten) when it holds too few modes. Nothing is written unless asked.
"""

from __future__ import annotations

import dataclasses
import logging
import time
import weakref
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..model.contact import Contact
from ..model.model import Model

__all__ = ["ModalReduction", "reduce_model", "structure_key", "REDUCTION_FORMAT"]

log = logging.getLogger(__name__)

#: format tag of saved reductions
REDUCTION_FORMAT = "mmshbm-modal-reduction-1"
#: default largest number of DOFs with mass solved by the dense eigen-solver (all modes)
DENSE_LIMIT = 200

_MEMORY: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_KEYS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_ARRAYS = ("omega", "phi", "B", "D0", "V", "R")
#: Krylov blocks Ṽ_0..Ṽ_q kept (q = KRYLOV_BLOCKS − 1): residual moments R(2)..R(2q+2)
KRYLOV_BLOCKS = 3


@dataclass(frozen=True, eq=False)
class ModalReduction:
    """Fixed-interface modes and static parts of a model (see the module docstring).

    Attributes
    ----------
    key : str
        :func:`structure_key` of the model it was computed for.
    omega : ndarray, shape (k,)
        Computed fixed-interface eigenfrequencies ω_j (rad/s), ascending.
    phi : ndarray, shape (n_l, k)
        Their M_ll-orthonormal mode shapes on the DOFs with mass (``model.l`` order).
    B : ndarray, shape (k, n_c)
        b_jᵀ = (K_cl φ_j)ᵀ (N/m per unit modal coordinate), ``model.c`` order.
    D0 : ndarray, shape (n_c, n_c)
        Static condensation K_cc − K_cl K_ll⁻¹ K_lc (N/m).
    V : ndarray, shape (q+1, n_l, n_c)
        Ṽ_i = Σ_{j>k} φ_j b_jᵀ/ω_j^{2i+2} (s^{2i+2}·...): the left-out modes' share of the
        recovery (zero when complete).
    R : ndarray, shape (2q+1, n_c, n_c)
        R[p−2] = R(p) = Σ_{j>k} b_j b_jᵀ/ω_j^{2p}, p = 2..2q+2 (zero when complete).
    complete : bool
        True when ``omega`` holds every mode (k = n_l).
    solver : str
        ``"dense"`` or ``"arpack"``.
    seconds : float
        Wall time of the computation (s).
    """

    key: str
    omega: np.ndarray
    phi: np.ndarray
    B: np.ndarray
    D0: np.ndarray
    V: np.ndarray
    R: np.ndarray
    complete: bool
    solver: str
    seconds: float = 0.0

    @property
    def n_l(self) -> int:
        return self.phi.shape[0]

    @property
    def n_c(self) -> int:
        return self.D0.shape[0]

    @property
    def n_modes(self) -> int:
        """Number of computed modes k."""
        return len(self.omega)

    def save(self, path) -> Path:
        """Write the reduction to ``path`` (``.npz``); returns the path written."""
        path = Path(path)
        meta = np.array([REDUCTION_FORMAT, self.key, self.solver, str(self.complete), repr(self.seconds)])
        tmp = path.with_name(path.name + ".tmp.npz")
        np.savez(tmp, meta=meta, **{name: getattr(self, name) for name in _ARRAYS})
        tmp.replace(path)
        return path

    @classmethod
    def load(cls, path, model: Model | None = None) -> ModalReduction:
        """Read a reduction written by :meth:`save`.

        Raises
        ------
        ValueError
            If the file is not a reduction, or (``model`` given) it was computed for
            another structure.
        """
        path = Path(path)
        try:
            with np.load(path, allow_pickle=False) as f:
                meta = [str(x) for x in f["meta"]]
                arrays = {name: np.array(f[name]) for name in _ARRAYS}
        except (OSError, KeyError, ValueError) as err:
            raise ValueError(f"{str(path)!r} is not a modal reduction file: {err}") from None
        if len(meta) != 5 or meta[0] != REDUCTION_FORMAT:
            raise ValueError(f"{str(path)!r} is not a modal reduction file (format {meta[:1]})")
        red = cls(key=meta[1], solver=meta[2], complete=meta[3] == "True", seconds=float(meta[4]), **arrays)
        if model is not None and red.key != structure_key(model):
            raise ValueError(f"the modal reduction in {str(path)!r} belongs to another structure "
                             f"(key {red.key[:12]}..., the model's {structure_key(model)[:12]}...)")
        return red


def structure_key(model: Model) -> str:
    """:meth:`Model.fingerprint` of the bare structure (M and K; contacts, damping and
    amplitude DOF stripped): the key of its modal reduction (kept per model object: hashing
    the matrices of a large model costs milliseconds)."""
    key = _KEYS.get(model)
    if key is None:
        bare = dataclasses.replace(model, contacts=(Contact(0, 0.0, 1),), damping=None, _amplitude_dof=None)
        key = _KEYS[model] = bare.fingerprint()
    return key


def reduce_model(model: Model, enough, *, cache=None, dense_limit: int = DENSE_LIMIT,
                 n_start: int = 16, max_modes: int = 400, eigen_tol: float = 0.0,
                 maxiter: int | None = None, complete: bool = False) -> ModalReduction:
    """The model's reduction with enough modes for ``enough(reduction) -> bool``.

    Looks in memory, then in ``cache`` (a directory or a ``.npz`` path), and computes (or
    extends) the reduction only if neither holds enough modes; a computed reduction is
    kept in memory and, with ``cache``, written there.

    Parameters
    ----------
    model : Model
    enough : callable(ModalReduction) -> bool
        The caller's selection rule (a complete reduction is always enough).
    cache : str or Path, optional
        Directory (file ``modal-<key[:24]>.npz`` inside) or ``.npz`` file.
    dense_limit : int
        Use the dense eigen-solver (all modes) up to this many DOFs with mass.
    n_start, max_modes : int
        ARPACK: first number of modes asked for, and the most it may be asked for.
    eigen_tol : float
        ARPACK's relative accuracy (0: machine precision).
    maxiter : int, optional
        ARPACK's iteration limit (default ``n_l * 10``).
    complete : bool
        Require every mode (dense solver; ValueError above 20 × ``dense_limit``).

    Raises
    ------
    ValueError
        If the eigen-solver does not converge, if ``max_modes`` modes are not enough, or
        if ``complete`` is asked of a model too large for the dense solver.
    """
    key = structure_key(model)
    candidates = []
    red = _MEMORY.get(model)
    if red is not None and red.key == key:
        candidates.append(red)
    path = _cache_path(cache, key)
    if path is not None and path.exists():
        candidates.append(ModalReduction.load(path, model))
    for red in candidates:
        if red.complete or (not complete and enough(red)):
            _MEMORY[model] = red
            return red

    n_l = len(model.l)
    if complete and n_l > 20 * dense_limit:
        raise ValueError(f"n_modes='all' asks for every fixed-interface mode of {n_l} DOFs with mass: too "
                         "large for the dense eigen-solver; give a cutoff or a tolerance instead")
    t0 = time.perf_counter()
    if n_l <= dense_limit or complete:
        red = _dense_reduction(model, key)
    else:
        red = _sparse_reduction(model, key, enough, n_start, max_modes, eigen_tol, maxiter)
    red = dataclasses.replace(red, seconds=time.perf_counter() - t0)
    log.info("modal reduction of %d DOFs with mass: %d modes (%s) in %.3f s", n_l, red.n_modes, red.solver,
             red.seconds)
    _MEMORY[model] = red
    if path is not None:
        red.save(path)
    return red


def _cache_path(cache, key: str) -> Path | None:
    if cache is None:
        return None
    if not isinstance(cache, str | Path) or str(cache) == "":
        raise TypeError(f"cache must be a directory or .npz path (str or Path), got {type(cache).__name__} "
                        f"{cache!r}")
    path = Path(cache)
    if path.suffix == ".npz":
        return path
    if path.exists() and not path.is_dir():
        raise ValueError(f"cache {str(path)!r} is neither a directory nor a .npz file")
    path.mkdir(parents=True, exist_ok=True)
    return path / f"modal-{key[:24]}.npz"


def _dense_reduction(model: Model, key: str) -> ModalReduction:
    b = model.blocks
    K, M = b["K_ll"].toarray(), b["M_ll"].toarray()
    try:
        cho = la.cho_factor(K)
    except la.LinAlgError:
        raise ValueError("K restricted to the DOFs with mass is not positive definite: the structure "
                         "with its massless DOFs clamped must be fixed") from None
    D0 = b["K_cc"] - b["K_lc"].T @ la.cho_solve(cho, b["K_lc"])
    # inverted pencil M φ = μ K φ: eigh normalises φᵀKφ = I, so φᵀMφ = diag(μ)
    mu, phi = la.eigh(M, K)
    mu, phi = mu[::-1], phi[:, ::-1]
    if not mu[-1] > 0:
        raise ValueError("M restricted to the DOFs with mass is not positive definite")
    phi = phi / np.sqrt(mu)
    n_l, n_c = phi.shape[0], D0.shape[0]
    return ModalReduction(key=key, omega=1.0 / np.sqrt(mu), phi=np.ascontiguousarray(phi),
                          B=np.ascontiguousarray(phi.T @ b["K_lc"]), D0=0.5 * (D0 + D0.T),
                          V=np.zeros((KRYLOV_BLOCKS, n_l, n_c)),
                          R=np.zeros((2 * KRYLOV_BLOCKS - 1, n_c, n_c)), complete=True, solver="dense")


def _deflated_moments(phi: np.ndarray, M, solve, Z0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(Ṽ (q+1, n_l, n_c), R (2q+1, n_c, n_c)) for the modes ``phi`` (see module docstring)."""

    def deflate(X):
        for _ in range(2):
            X = X - phi @ (phi.T @ (M @ X))
        return X

    V = np.empty((KRYLOV_BLOCKS,) + Z0.shape)
    V[0] = deflate(Z0)
    for i in range(1, KRYLOV_BLOCKS):
        V[i] = deflate(solve(np.asarray(M @ V[i - 1])))
    MV = [np.asarray(M @ V[i]) for i in range(KRYLOV_BLOCKS)]
    R = np.empty((2 * KRYLOV_BLOCKS - 1,) + (Z0.shape[1],) * 2)
    for p in range(2, 2 * KRYLOV_BLOCKS + 1):
        a = (p - 2) // 2
        Rp = V[a].T @ MV[p - 2 - a]
        R[p - 2] = 0.5 * (Rp + Rp.T)
    return V, R


def _sparse_reduction(model: Model, key: str, enough, n_start: int, max_modes: int, eigen_tol: float,
                      maxiter: int | None) -> ModalReduction:
    b = model.blocks
    # CSR for M: its products with the n_c-column blocks are 3x faster by rows than by columns
    K, M = sp.csc_matrix(b["K_ll"]), sp.csr_matrix(b["M_ll"])
    n_l = K.shape[0]
    try:
        lu = spla.splu(K, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})
    except RuntimeError as err:
        raise ValueError(f"K restricted to the DOFs with mass is singular ({err}): the structure with its "
                         "massless DOFs clamped must be fixed") from None
    Z0 = lu.solve(b["K_lc"])
    D0 = b["K_cc"] - b["K_lc"].T @ Z0
    D0 = 0.5 * (D0 + D0.T)
    op = spla.LinearOperator((n_l, n_l), matvec=lu.solve, dtype=float)
    k = min(max(int(n_start), 2), n_l - 1, int(max_modes))
    while True:
        try:
            lam, phi = spla.eigsh(K, k=k, M=M, sigma=0.0, which="LM", OPinv=op, v0=np.ones(n_l),
                                  tol=eigen_tol, maxiter=maxiter)
        except spla.ArpackNoConvergence as err:
            raise ValueError(f"the eigen-solver (ARPACK, shift-invert at 0) did not converge: "
                             f"{len(err.eigenvalues)} of {k} fixed-interface modes after maxiter="
                             f"{maxiter if maxiter is not None else n_l * 10}; raise maxiter or eigen_tol"
                             ) from None
        order = np.argsort(lam)
        lam, phi = lam[order], phi[:, order]
        if not np.all(np.isfinite(lam)) or lam[0] <= 0:
            raise ValueError(f"the eigen-solver returned a non-positive eigenvalue {lam[0]:.3e}: K and M "
                             "restricted to the DOFs with mass must be positive definite")
        # ARPACK's vectors are M-orthonormal to its tolerance: renormalise to round-off
        phi = np.ascontiguousarray(phi / np.sqrt(np.einsum("ij,ij->j", phi, M @ phi)))
        V, R = _deflated_moments(phi, M, lu.solve, Z0)
        red = ModalReduction(key=key, omega=np.sqrt(lam), phi=phi, B=np.ascontiguousarray(phi.T @ b["K_lc"]),
                             D0=D0, V=V, R=R, complete=False, solver="arpack")
        if enough(red):
            return red
        if k >= min(n_l - 1, max_modes):
            top = red.omega[-1] / (2 * np.pi)
            raise ValueError(f"the {k} lowest fixed-interface modes (up to {top:.6g} Hz) "
                             f"do not meet the truncation requirement and max_modes={max_modes} stops here: "
                             "lower the harmonics or frequency range, raise tol, or raise max_modes")
        k = min(2 * k, n_l - 1, int(max_modes))
