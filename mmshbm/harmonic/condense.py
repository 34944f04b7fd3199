"""Condensation of the linear subsystem onto the massless contact DOFs, per harmonic.

For harmonic k at frequency Ω (rad/s) the DOFs with mass obey

    S_k Q_l,k + K_lc Q_c,k = 0,       S_k = K_ll − (kΩ)² M_ll,

so Q_l,k = −Z_k Q_c,k with Z_k = S_k⁻¹ K_lc, and the force the structure needs at the
massless DOFs is D_k Q_c,k with the condensed dynamic stiffness

    D_k(Ω) = K_cc − K_cl Z_k,            ∂D_k/∂Ω = −2 k² Ω Z_kᵀ M_ll Z_k.

One LU factorisation of S_k per harmonic and frequency, solved for the n_c columns of
K_lc. Two back ends:

``"banded"`` (default when the matrices have a narrow band)
    The DOFs are renumbered once by reverse Cuthill–McKee; S_k is then factored by a
    band LU with partial pivoting (the algorithm of LAPACK's ``gbtf2``) in a Numba
    kernel that does all harmonics, D_k and ∂D_k/∂Ω in one call. Measured on the
    21-element beam (40 DOFs with mass): scipy ``splu`` costs ~110 µs per harmonic and
    LAPACK ``gbsv`` through scipy ~11 µs (mostly call overhead); the kernel does all
    five harmonics of H = 5 in a few µs. Its cost grows linearly with the DOF count.
``"splu"``
    SuperLU (``scipy.sparse.linalg.splu``) on the RCM-ordered matrix in its natural
    order; used for matrices without a narrow band.
``"modal"``
    Fixed-interface normal modes plus the static correction
    (:class:`~mmshbm.harmonic.modal.ModalCondensation`): O(m n_c²) per harmonic after a
    one-time reduction, independent of the model's size. :func:`make_condensation`
    builds any of the three and picks the fastest with ``"auto"``.

A singular S_k (kΩ on an eigenfrequency of the structure with the massless DOFs
clamped) raises :class:`SingularDynamicStiffness`, which the Newton solver treats as a
failed step.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.sparse.csgraph import reverse_cuthill_mckee

from .. import _validate as check
from ..model.model import Model
from ._errors import SingularDynamicStiffness
from .kernels import _band_quadratic_form, _band_solve, _condensed_stiffness

__all__ = ["Condensation", "SingularDynamicStiffness", "make_condensation", "BACKENDS"]

#: the condensation back ends :func:`make_condensation` knows
BACKENDS = ("auto", "banded", "splu", "modal")


class Condensation:
    """Per-harmonic condensation of a :class:`~mmshbm.model.Model` onto its massless DOFs.

    Parameters
    ----------
    model : Model
        The structure.
    backend : {"auto", "banded", "splu"}
        Linear solver for S_k (see module docstring). ``"auto"`` picks ``"banded"`` when
        the RCM-ordered half bandwidth is at most ``max(8, √n_l)``.
    """

    def __init__(self, model: Model, backend: str = "auto"):
        if not isinstance(model, Model):
            raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
        if backend not in ("auto", "banded", "splu"):
            raise ValueError(f"backend must be 'auto', 'banded' or 'splu', got {backend!r}")
        b = model.blocks
        K, M = b["K_ll"], b["M_ll"]
        pattern = (abs(K) + abs(M)).tocsr()
        perm = reverse_cuthill_mckee(pattern, symmetric_mode=True)
        self.perm = perm
        self.n_l, self.n_c = K.shape[0], b["K_cc"].shape[0]
        # RCM order by index maps on the COO triplets (no permuted sparse copies: scipy's
        # fancy indexing dominated the set-up of small models)
        inverse = np.empty_like(perm)
        inverse[perm] = np.arange(len(perm))
        K = _permuted_coo(K, inverse)
        M = _permuted_coo(M, inverse)
        coo = pattern.tocoo()
        half_band = int(np.max(np.abs(inverse[coo.row] - inverse[coo.col]))) if coo.nnz else 0
        if backend == "auto":
            backend = "banded" if half_band <= max(8, int(np.sqrt(self.n_l))) else "splu"
        self.backend = backend
        self.half_band = half_band
        self.K_lc = np.ascontiguousarray(b["K_lc"][perm])
        self.K_cc = b["K_cc"]
        self.M_ll = M.tocsr()
        if backend == "banded":
            kl = half_band
            self._Kb = _band_storage(K, kl)
            self._Mb = _band_storage(M, kl)
            self._AB = np.empty_like(self._Kb)
            self._Zwork = np.empty((self.n_l, self.n_c))
            self._ZMZ = np.empty((self.n_c, self.n_c))
        else:
            K, M = K.tocsc(), M.tocsc()
            S = (abs(K) + abs(M)).tocsc()
            S.sort_indices()
            rows = S.indices
            cols = np.repeat(np.arange(S.shape[1]), np.diff(S.indptr))
            self._S = S
            self._K_data = np.asarray(K[rows, cols]).ravel()
            self._M_data = np.asarray(M[rows, cols]).ravel()
        self._Z0 = self._solve(0.0)
        self.D0 = self.K_cc - self.K_lc.T @ self._Z0

    # ------------------------------------------------------------------ core
    def _solve(self, omega_k: float) -> np.ndarray:
        """Z = (K_ll − omega_k² M_ll)⁻¹ K_lc in RCM order; shape (n_l, n_c)."""
        w2 = omega_k * omega_k
        if self.backend == "banded":
            Z = np.empty((self.n_l, self.n_c))
            info = _band_solve(self._Kb, self._Mb, self.half_band, w2, self.K_lc, self._AB, Z)
            if info:
                raise SingularDynamicStiffness(
                    f"K_ll - ({omega_k:.6g} rad/s)^2 M_ll is singular (zero pivot in column {info})")
            return Z
        self._S.data = self._K_data - w2 * self._M_data
        try:
            lu = spla.splu(self._S, permc_spec="NATURAL")
        except RuntimeError as err:
            raise SingularDynamicStiffness(
                f"K_ll - ({omega_k:.6g} rad/s)^2 M_ll is singular: {err}") from None
        return lu.solve(self.K_lc)

    def dynamic_stiffness(self, omega: float, harmonics: int, derivative: bool = True):
        """Condensed dynamic stiffness for k = 0..H.

        Parameters
        ----------
        omega : float
            Fundamental frequency Ω (rad/s).
        harmonics : int
            H.
        derivative : bool
            Also return ∂D_k/∂Ω.

        Returns
        -------
        D : ndarray, shape (H+1, n_c, n_c)
            D_k(Ω) (N/m, N·m/rad), symmetric.
        dD : ndarray, shape (H+1, n_c, n_c), only if ``derivative``
            ∂D_k/∂Ω (N·s/m ...).
        """
        H = check.integer("harmonics", harmonics, minimum=0)
        if not math.isfinite(omega):
            raise ValueError(f"omega must be finite, got {omega!r}")
        n_c = self.n_c
        D = np.empty((H + 1, n_c, n_c))
        dD = np.zeros((H + 1, n_c, n_c)) if derivative else None
        D[0] = self.D0
        if self.backend == "banded":
            info = _condensed_stiffness(self._Kb, self._Mb, self.half_band, self.K_lc, self.K_cc,
                                        float(omega), H, D, dD if derivative else D, self._AB,
                                        self._Zwork, self._ZMZ, derivative)
            if info:
                k = info // (self.n_l + 1)
                raise SingularDynamicStiffness(
                    f"K_ll - ({k}·{omega:.6g} rad/s)^2 M_ll is singular: harmonic {k} of Ω sits on an "
                    "eigenfrequency of the structure with its massless DOFs clamped")
            return (D, dD) if derivative else D
        KlcT = self.K_lc.T
        ZMZ = np.empty((n_c, n_c))
        for k in range(1, H + 1):
            Z = self._solve(k * omega)
            D[k] = self.K_cc - KlcT @ Z
            if derivative:
                self._quadratic_mass(Z, ZMZ)
                dD[k] = (-2.0 * k * k * omega) * ZMZ
        return (D, dD) if derivative else D

    def _quadratic_mass(self, Z: np.ndarray, out: np.ndarray) -> None:
        """out = Zᵀ M_ll Z (RCM order)."""
        if self.backend == "banded":
            _band_quadratic_form(self._Mb, self.half_band, Z, out)
        else:
            out[:] = Z.T @ (self.M_ll @ Z)

    def recover(self, omega: float, Qc: np.ndarray) -> np.ndarray:
        """Coefficients of the DOFs with mass from those of the massless DOFs.

        Parameters
        ----------
        omega : float
            Ω (rad/s).
        Qc : ndarray, shape (n_c, 2H+1)
            NLvib-ordered coefficients of the massless DOFs (``model.c`` order).

        Returns
        -------
        Ql : ndarray, shape (n_l, 2H+1)
            Coefficients of the DOFs with mass (``model.l`` order): Q_l,k = −Z_k Q_c,k.
        """
        Qc = np.asarray(Qc, dtype=float)
        H = (Qc.shape[1] - 1) // 2
        Ql = np.empty((self.n_l, 2 * H + 1))
        Ql[self.perm, 0] = -self._Z0 @ Qc[:, 0]
        for k in range(1, H + 1):
            Z = self._solve(k * omega)
            Ql[self.perm, 2 * k - 1] = -Z @ Qc[:, 2 * k - 1]
            Ql[self.perm, 2 * k] = -Z @ Qc[:, 2 * k]
        return Ql


def _permuted_coo(A: sp.spmatrix, inverse: np.ndarray) -> sp.coo_matrix:
    """A with rows and columns renumbered i -> inverse[i] (duplicates summed)."""
    A = A.tocsr()  # canonical: duplicate entries summed, as the former csr slicing did
    A.sum_duplicates()
    coo = A.tocoo()
    return sp.coo_matrix((coo.data, (inverse[coo.row], inverse[coo.col])), shape=A.shape)


def _band_storage(A: sp.spmatrix, kl: int) -> np.ndarray:
    """Row band layout of A (half bandwidth kl): shape (n, 3kl+1), AB[i, j − i + kl] = A[i, j];
    the last kl columns are zero, room for the fill-in of partial pivoting."""
    n = A.shape[0]
    ab = np.zeros((n, 3 * kl + 1))
    coo = A.tocoo()
    ab[coo.row, coo.col - coo.row + kl] = coo.data
    return ab


#: ``"auto"`` uses the modal back end from this many DOFs with mass, i.e. always. Per
#: evaluation (beam, H = 5, one BLAS thread) a modal one costs 3.3 µs at any size against
#: 5, 9, 13, 23, 54, 108, 321 and 682 µs for the banded LU at n_l = 6 … 998, and its
#: reduction (0.4-15 ms up to n_l = 1000) is repaid after 15-70 evaluations. Below ~20 DOFs
#: with mass the evaluations differ by less than 10 µs and the banded LU was kept until
#: 0.2.0; but only the modal back end runs MMS-HBM's compiled corrector, so on whole
#: backbones it is the faster one at every size: one-DOF oscillator H = 13 to 2 gaps
#: 16.9 → 7.9 ms, 8-element beam to 10 gaps H = 5 88 → 20 ms, H = 7 615 → 236 ms, same
#: branches (frequencies equal to ~1e-11). With the exact projection both back ends pass the
#: pole 5Ω = ω_1 near 1.6 gaps of the 21-element beam (87 and 86 points to 10 gaps, 2 gaps
#: at 57.06321 and 57.06322 Hz); on 100 elements at H = 5 the banded branch stops with
#: ds_min where the modal one reaches 10 gaps.
MODAL_CROSSOVER = 1


def make_condensation(model: Model, backend: str = "auto", *, harmonics: int = 5, mode: int = 1,
                      **modal_options):
    """The condensation of ``model`` onto its massless DOFs with the chosen back end.

    Parameters
    ----------
    model : Model
    backend : {"auto", "banded", "splu", "modal"}
        ``"auto"``: ``"modal"`` from :data:`MODAL_CROSSOVER` DOFs with mass on, else
        :class:`Condensation`'s own choice between ``"banded"`` and ``"splu"``.
    harmonics, mode : int
        The solver's H and the branch's linear mode: they set the modal truncation's
        design range (ignored by the LU back ends).
    **modal_options
        Options of :class:`~mmshbm.harmonic.modal.ModalCondensation` (``tol``, ``cutoff``,
        ``n_modes``, ``max_frequency``, ``cache``, ...); TypeError with an LU back end.

    Returns
    -------
    Condensation or ModalCondensation
        Both have ``D0``, ``n_l``, ``n_c``, ``backend``, ``dynamic_stiffness(omega, H,
        derivative=True)`` and ``recover(omega, Qc)``.
    """
    if not isinstance(model, Model):
        raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if backend == "auto":
        backend = "modal" if len(model.l) >= MODAL_CROSSOVER else "auto"
    if backend == "modal":
        from .modal import ModalCondensation

        return ModalCondensation(model, harmonics=harmonics, mode=mode, **modal_options)
    if modal_options:
        raise TypeError(f"options {sorted(modal_options)} apply to backend='modal' only, not {backend!r}")
    return Condensation(model, backend)
