"""Modal condensation onto the massless DOFs (``backend="modal"``).

With the massless DOFs clamped, the DOFs with mass have M_ll-orthonormal modes (φ_j, ω_j)
and b_j = K_cl φ_j (:mod:`mmshbm.harmonic.modal_reduction`). Since
(K_ll − ω² M_ll)⁻¹ = Σ_j φ_j φ_jᵀ/(ω_j² − ω²), the condensed dynamic stiffness of
:mod:`mmshbm.harmonic.condense` is, for harmonic k (ω = kΩ),

    D_k  = D_0 − Σ_j b_j b_jᵀ ω² / (ω_j² (ω_j² − ω²))
    ∂D_k/∂Ω = −Σ_j b_j b_jᵀ 2k²Ω / (ω_j² − ω²)²

exactly, with all modes (both checked against the banded LU and by finite differences
in the tests). Each term is a rank-one n_c × n_c matrix: after the one-time reduction a
harmonic costs O(m n_c²) whatever the size of the FE model.

Truncation. Keeping the m lowest modes, the left-out ones are replaced by the first P
terms of their low-frequency expansion (the static, residual-flexibility correction:
D_0 is exact, and the missing modes' residual inertia and its higher moments are added
in closed form, :mod:`mmshbm.harmonic.modal_reduction`):

    D_k ≈ D_0 − Σ_{j<=m} b_j b_jᵀ ω²/(ω_j²(ω_j² − ω²)) − Σ_{p=1..P} ω^{2p} R(p+1),
    R(p) = Σ_{j>m} b_j b_jᵀ/ω_j^{2p}.

This leaves E_k = Σ_{j>m} b_j b_jᵀ ω^{2P+2}/(ω_j^{2P+2}(ω_j² − ω²)), which for
ω < ω_{m+1} obeys 0 ⪯ E_k ⪯ ω^{2P+2}/(ω_{m+1}² − ω²) · R(P+1) (each term's factor is at
most that times 1/ω_j^{2P+2}). :meth:`ModalCondensation.truncation_error` reports this
bound relative to ‖D_0‖₂; the default number of modes is the smallest m for which it
stays below ``tol`` up to ω = H·Ω_max, with Ω_max the fixed-interface eigenfrequency of
the branch's mode (a bound on the nonlinear mode's frequency: the contact can at most
clamp the massless DOFs, and clamping raises every eigenfrequency). With P = 1 (the
classical residual inertia alone) a Timoshenko beam needs almost every mode for
‖E‖ <= 10⁻¹⁰‖D_0‖ (its interface forces b_j grow quickly with j); with the default
P = 5, 11 modes on any mesh from 21 to 1000 elements at H = 5.

Poles. At kΩ = ω_j the term of mode j is singular. ``dynamic_stiffness(...,
exclude=[(k, j), ...])`` leaves that term out of harmonic k (D and ∂D/∂Ω), so that a
solver can carry η_jk = b_jᵀ a_k/(ω_j² − (kΩ)²) as an unknown instead: the force is then
D_k^reg a_k − b_j η_jk (kΩ)²/ω_j², with the regular equation
(ω_j² − (kΩ)²) η_jk − b_jᵀ a_k = 0.
"""

from __future__ import annotations

import math
import warnings
import weakref

import numpy as np

from .. import _validate as check
from .._warnings import ModelWarning
from ..model.model import Model
from ._errors import SingularDynamicStiffness
from ._modal_kernels import _modal_dynamic_stiffness
from .modal_reduction import DENSE_LIMIT, KRYLOV_BLOCKS, ModalReduction, reduce_model

__all__ = ["ModalCondensation", "DEFAULT_TOL", "MAX_RESIDUAL_TERMS"]

#: most terms of the left-out modes' expansion the stored Krylov blocks allow (2q + 1)
MAX_RESIDUAL_TERMS = 2 * KRYLOV_BLOCKS - 1

#: default bound on the truncation error ‖D_k − D_k^exact‖₂ / ‖D_0‖₂ over the design range
DEFAULT_TOL = 1e-10
_POLE_RTOL = 64 * np.finfo(float).eps
#: reduction -> {m: (Ṽ_i, Z_0)} of the recovery with m modes kept (read only)
_RECOVERY: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
#: reduction -> {request: modes kept (:meth:`ModalCondensation._select`), ("modes", m, P, H,
#: mode, max_frequency): (R(2..P+1), error estimate) (:meth:`ModalCondensation._set_modes`)}:
#: what a condensation of the same model and request computes again otherwise (read only)
_SELECTION: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
#: reduction -> {modes kept: {projector id: (projector, its projections)}} of
#: :meth:`ModalCondensation.projected_cosine_recovery` (read only)
_SHARED_PROJECTIONS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
#: projectors whose projections :meth:`ModalCondensation.projected_cosine_recovery` keeps
_PROJECTORS = 4
#: warn once when kΩ exceeds this fraction of the first left-out mode
_LEFT_OUT_WARNING = 0.8


class ModalCondensation:
    """Per-harmonic condensation onto the massless DOFs from fixed-interface modes.

    Same interface as :class:`~mmshbm.harmonic.condense.Condensation` (``D0``, ``n_l``,
    ``n_c``, ``backend``, :meth:`dynamic_stiffness`, :meth:`recover`), plus the modes
    (:attr:`omega_j`, :attr:`phi_j`, :attr:`b_j`) for pole handling.

    Parameters
    ----------
    model : Model
        The structure (at least one massless DOF).
    harmonics : int
        H of the solver: the design range of the truncation is kΩ <= H·Ω_max.
    mode : int
        The branch's linear mode (1-based): Ω_max defaults to the ``mode``-th
        fixed-interface eigenfrequency.
    max_frequency : float, optional
        Ω_max/2π (Hz): the highest fundamental frequency the solver will visit.
    n_modes : int or "all", optional
        Keep exactly this many modes (``"all"``: every mode, exact; dense eigen-solver).
    cutoff : float, optional
        Keep the modes up to this frequency (Hz), > 0.
    residual_terms : int
        P, the terms of the left-out modes' expansion, 1..5 (1: residual inertia only).
    tol : float
        With neither ``n_modes`` nor ``cutoff``: keep the fewest modes whose truncation
        error bound (relative to ‖D_0‖₂) is at most ``tol`` up to H·Ω_max.
    reduction : ModalReduction, optional
        A precomputed reduction of this model (e.g. :meth:`ModalReduction.load`).
    cache : str or Path, optional
        Directory or ``.npz`` file where the reduction is kept between runs
        (:mod:`mmshbm.harmonic.modal_reduction`).
    dense_limit, max_modes, eigen_tol, maxiter
        Eigen-solver controls (:func:`~mmshbm.harmonic.modal_reduction.reduce_model`).

    Attributes
    ----------
    n_modes : int
        m, the modes kept.
    cutoff : float
        Frequency (Hz) of the first mode left out (inf when all are kept).
    error_estimate : float
        :meth:`truncation_error` bound at H·Ω_max (0 with all modes).
    design_frequency : float
        H·Ω_max/2π (Hz).

    Raises
    ------
    ValueError, TypeError
        For a bad option (named), a cutoff <= 0, an eigen-solver that does not converge,
        or a tolerance that ``max_modes`` modes cannot meet.
    """

    backend = "modal"

    def __init__(self, model: Model, *, harmonics: int = 5, mode: int = 1, max_frequency: float | None = None,
                 n_modes=None, cutoff: float | None = None, tol: float = DEFAULT_TOL,
                 residual_terms: int = MAX_RESIDUAL_TERMS,
                 reduction: ModalReduction | None = None, cache=None, dense_limit: int = DENSE_LIMIT,
                 max_modes: int = 400, eigen_tol: float = 0.0, maxiter: int | None = None):
        if not isinstance(model, Model):
            raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
        self.H = check.integer("harmonics", harmonics, minimum=1)
        self.mode = check.integer("mode", mode, minimum=1)
        self.max_frequency = None if max_frequency is None else check.positive("max_frequency", max_frequency)
        self.tol = check.positive("tol", tol)
        self.P = check.integer("residual_terms", residual_terms, minimum=1)
        if self.P > MAX_RESIDUAL_TERMS:
            raise ValueError(f"residual_terms must be in [1, {MAX_RESIDUAL_TERMS}], got {residual_terms}")
        if n_modes is not None and cutoff is not None:
            raise ValueError(f"give n_modes or cutoff, not both (got n_modes={n_modes!r}, cutoff={cutoff!r})")
        complete = isinstance(n_modes, str)
        if complete and n_modes != "all":
            raise ValueError(f"n_modes must be a positive integer or 'all', got {n_modes!r}")
        if n_modes is not None and not complete:
            n_modes = check.integer("n_modes", n_modes, minimum=1)
        if cutoff is not None:
            cutoff = check.real_number("cutoff", cutoff)
            if not cutoff > 0:
                raise ValueError(f"cutoff must be a frequency > 0 (Hz), got {cutoff!r}")
        dense_limit = check.integer("dense_limit", dense_limit, minimum=0)
        max_modes = check.integer("max_modes", max_modes, minimum=2)
        eigen_tol = check.non_negative("eigen_tol", eigen_tol)
        if maxiter is not None:
            maxiter = check.integer("maxiter", maxiter, minimum=1)
        self.n_l, self.n_c = len(model.l), len(model.c)
        if self.n_c == 0:
            raise ValueError("the model has no massless DOF: there is nothing to condense onto")
        if self.mode > self.n_l:
            raise ValueError(f"mode must be <= the number of DOFs with mass ({self.n_l}), got {self.mode}")
        self._n_modes_request, self._cutoff_request, self._complete_request = n_modes, cutoff, complete

        if reduction is not None:
            if not isinstance(reduction, ModalReduction):
                raise TypeError(f"reduction must be a ModalReduction, got {type(reduction).__name__}")
            if reduction.n_l != self.n_l or reduction.n_c != self.n_c:
                raise ValueError(f"reduction has {reduction.n_l} DOFs with mass and {reduction.n_c} massless "
                                 f"ones, the model {self.n_l} and {self.n_c}")
            if self._select(reduction) is None:
                raise ValueError(f"the given reduction's {reduction.n_modes} modes are too few for this "
                                 "request")
            red = reduction
        else:
            red = reduce_model(model, lambda r: self._select(r) is not None, cache=cache,
                               dense_limit=dense_limit, max_modes=max_modes, eigen_tol=eigen_tol,
                               maxiter=maxiter, complete=complete)
        self.reduction = red
        m = self._select(red)
        self._set_modes(red, m)
        self._keep_all = np.ones((self.H + 1, self.n_modes), dtype=np.uint8)
        self._warned = False

    # ------------------------------------------------------------------ selection
    def _omega_max(self, red: ModalReduction) -> float:
        if self.max_frequency is not None:
            return 2 * np.pi * self.max_frequency
        return float(red.omega[self.mode - 1]) if red.n_modes >= self.mode else math.inf

    def _select(self, red: ModalReduction) -> int | None:
        """Number of modes m this request keeps from ``red``, or None if ``red`` holds too few
        (the first left-out mode must be known, unless all are kept); kept per reduction and
        request (:data:`_SELECTION`)."""
        request = (self._complete_request, self._n_modes_request, self._cutoff_request, self.H, self.mode,
                   self.max_frequency, self.tol, self.P)
        memo = _SELECTION.setdefault(red, {})
        if request not in memo:
            memo[request] = self._select_modes(red)
        return memo[request]

    def _select_modes(self, red: ModalReduction) -> int | None:
        """:meth:`_select` computed."""
        k, n_l = red.n_modes, red.n_l
        if self._complete_request:
            return n_l if red.complete else None
        if self._n_modes_request is not None:
            m = min(self._n_modes_request, n_l)
            return m if (m < k or red.complete) else None
        if self._cutoff_request is not None:
            m = int(np.searchsorted(red.omega, 2 * np.pi * self._cutoff_request, side="right"))
            return m if (m < k or red.complete) else None
        w = self.H * self._omega_max(red)
        if not math.isfinite(w):
            return None
        limit = self.tol * _norm2(red.D0)
        for m in range(k):
            if red.omega[m] <= w:
                continue
            if _bound(w, red.omega[m], _tail(red, m, self.P + 1), self.P) <= limit:
                return m
        return n_l if red.complete else None

    def _set_modes(self, red: ModalReduction, m: int) -> None:
        self.n_modes = m
        self.omega_j = red.omega[:m].copy()
        self.phi_j = red.phi[:, :m]
        self.b_j = np.ascontiguousarray(red.B[:m])
        self._w2 = self.omega_j**2
        self.D0 = red.D0
        self.complete = bool(red.complete and m == red.n_l)
        self._omega_next = math.inf if m >= red.n_modes else float(red.omega[m])
        self.cutoff = self._omega_next / (2 * np.pi)
        self._V = None  # recovery blocks, built on the first recover()
        self._recovery_factors = None  # (Ω, H, exclusions) of the last recover() and its factors
        # projector id -> its projections (projected_cosine_recovery): shared by the
        # condensations of one reduction with the same modes (the same numbers)
        self._projections = _SHARED_PROJECTIONS.setdefault(red, {}).setdefault(m, {})
        self.design_frequency = self.H * self._omega_max(red) / (2 * np.pi)
        memo = _SELECTION.setdefault(red, {})
        key = ("modes", m, self.P, self.H, self.mode, self.max_frequency)
        if key not in memo:
            self.Rs = np.ascontiguousarray(np.array([_tail(red, m, p) for p in range(2, self.P + 2)]))
            memo[key] = (self.Rs, float(self.truncation_error(2 * np.pi * self.design_frequency / self.H,
                                                              self.H)[-1]) if math.isfinite(
                self.design_frequency) else math.nan)
        Rs, self.error_estimate = memo[key]
        self.Rs = Rs.copy()

    # ------------------------------------------------------------------ public
    def truncation_error(self, omega: float, harmonics: int) -> np.ndarray:
        """Bound on ‖D_k − D_k^exact‖₂ / ‖D_0‖₂ for k = 0..H at Ω = ``omega`` (rad/s);
        shape (H+1,); inf where kΩ reaches the first left-out mode, 0 with all modes."""
        H = check.integer("harmonics", harmonics, minimum=0)
        w = np.arange(H + 1) * abs(float(omega))
        if self.complete:
            return np.zeros(H + 1)
        return np.array([_bound(x, self._omega_next, self.Rs[-1], self.P) for x in w]) / _norm2(self.D0)

    def poles_near(self, omega: float, harmonics: int, window: float = 0.05) -> list[tuple[int, int]]:
        """The (k, j), 1 <= k <= H, with |kΩ − ω_j| <= ``window``·ω_j: the kept modes whose
        pole harmonic k of Ω (rad/s) is near."""
        H = check.integer("harmonics", harmonics, minimum=1)
        window = check.positive("window", window)
        k = np.arange(1, H + 1)[:, None]
        w = self.omega_j[None, :]
        kk, jj = np.nonzero(np.abs(k * float(omega) - w) <= window * w)
        return [(int(a + 1), int(b)) for a, b in zip(kk, jj, strict=True)]

    def dynamic_stiffness(self, omega: float, harmonics: int, derivative: bool = True, exclude=()):
        """Condensed dynamic stiffness for k = 0..H (as
        :meth:`Condensation.dynamic_stiffness <mmshbm.harmonic.condense.Condensation.dynamic_stiffness>`).

        Parameters
        ----------
        omega : float
            Ω (rad/s).
        harmonics : int
            H.
        derivative : bool
            Also return ∂D_k/∂Ω.
        exclude : iterable of (k, j)
            Leave mode j's term (0-based index into :attr:`omega_j`) out of harmonic k,
            1 <= k <= H, in D and ∂D/∂Ω (the regular part near that pole).

        Returns
        -------
        D : ndarray, shape (H+1, n_c, n_c)
        dD : ndarray, shape (H+1, n_c, n_c), only if ``derivative``

        Raises
        ------
        SingularDynamicStiffness
            When kΩ equals a kept ω_j to round-off and (k, j) is not excluded.
        """
        H = check.integer("harmonics", harmonics, minimum=0)
        omega = float(omega)
        if not math.isfinite(omega):
            raise ValueError(f"omega must be finite, got {omega!r}")
        keep = self._keep(H, exclude)
        n_c = self.n_c
        D = np.empty((H + 1, n_c, n_c))
        dD = np.empty((H + 1, n_c, n_c)) if derivative else D
        info = _modal_dynamic_stiffness(self.D0, self.b_j, self._w2, self.Rs, omega, H, keep, _POLE_RTOL,
                                        D, dD, derivative)
        if info:
            k, j = divmod(info - 1, self.n_modes)
            raise SingularDynamicStiffness(
                f"K_ll - ({k}·{omega:.6g} rad/s)^2 M_ll is singular: harmonic {k} of Ω sits on the "
                f"fixed-interface eigenfrequency {self.omega_j[j]:.9g} rad/s (mode index {j})")
        return (D, dD) if derivative else D

    def check_range(self, omega: float, harmonics: int) -> bool:
        """Warn (once, :class:`~mmshbm.ModelWarning`) if harmonic H of Ω (rad/s) reaches 0.8 ×
        the first left-out mode, where the truncation misses that mode's pole; returns
        whether Ω is inside. For converged points (e.g. from a problem's ``monitor``): a
        Newton iterate may wander far out and back, so :meth:`dynamic_stiffness` does not
        check."""
        # called for every converged point: validate only what is not already a plain int
        H = harmonics if type(harmonics) is int and harmonics >= 1 else check.integer("harmonics", harmonics,
                                                                                        minimum=1)
        inside = H * abs(float(omega)) <= _LEFT_OUT_WARNING * self._omega_next
        if not inside and not self._warned:
            self._warned = True
            f_top = H * abs(omega) / (2 * np.pi)
            warnings.warn(f"harmonic {H} of Ω = {omega / (2 * np.pi):.6g} Hz reaches {f_top:.6g} Hz, near "
                          "or past the first mode the modal condensation leaves out "
                          f"({self.cutoff:.6g} Hz): its pole is missing; build it with a higher "
                          "max_frequency, harmonics or cutoff", ModelWarning, stacklevel=2)
        return inside

    def recover(self, omega: float, Qc: np.ndarray, exclude=()) -> np.ndarray:
        """Coefficients of the DOFs with mass (``model.l`` order), shape (n_l, 2H+1), from the
        NLvib-ordered coefficients ``Qc`` (n_c, 2H+1) of the massless DOFs: Q_l,k = −Z_k Q_c,k,

            Z_k = Z_0 + Σ_{j<=m} φ_j b_jᵀ ω²/(ω_j²(ω_j² − ω²)) + Σ_{i=1..q} ω^{2i} Ṽ_i,

        exact with all modes; truncated, the left-out modes enter to order ω^{2q} (q = 2).
        ``exclude`` pairs (k, j) leave mode j's term out of harmonic k, as in
        :meth:`dynamic_stiffness` (the caller adds −φ_j η_jk (kΩ)²/ω_j² itself)."""
        Qc = np.asarray(Qc, dtype=float)
        if Qc.ndim != 2 or Qc.shape[0] != self.n_c or Qc.shape[1] % 2 != 1:
            raise ValueError(f"Qc must have shape ({self.n_c}, 2H+1), got {Qc.shape}")
        H = (Qc.shape[1] - 1) // 2
        omega = float(omega)
        key = (H, omega, tuple(exclude))
        last = self._recovery_factors
        if last is not None and last[0] == key:
            x, c = last[1]  # the same Ω, H and exclusions as the last call
        else:
            x, c = self._recovery_coefficients(H, omega, key[2])
            self._recovery_factors = ((H, omega, tuple(map(tuple, exclude))), (x, c))
        Z = self._Z0 @ Qc + self.phi_j @ ((self.b_j @ Qc) * c.T)
        if not self.complete:
            for i in range(1, KRYLOV_BLOCKS):
                Z += (self._V[i] @ Qc) * x[None, :] ** i
        return -Z

    def _recovery_coefficients(self, H: int, omega: float, exclude: tuple) -> tuple[np.ndarray, np.ndarray]:
        """((kΩ)² per column (2H+1,), the kept modes' factors (2H+1, m)) of :meth:`recover`;
        raises :class:`SingularDynamicStiffness` where a kept term has its pole."""
        k = np.repeat(np.arange(H + 1), 2)[1:]  # harmonic of each column
        x = (k * omega) ** 2
        den = self._w2[None, :] - x[:, None]
        excluded = np.zeros(den.shape, dtype=bool)
        if len(exclude):  # harmonic kk has the columns 2kk − 1 (cosine) and 2kk (sine)
            kk, j = np.asarray(exclude, dtype=np.int64).reshape(-1, 2).T
            excluded[0, j[kk == 0]] = True
            inside = (kk >= 1) & (kk <= H)
            excluded[2 * kk[inside] - 1, j[inside]] = excluded[2 * kk[inside], j[inside]] = True
        den = np.where(excluded, 1.0, den)
        if np.any(np.abs(den) <= _POLE_RTOL * self._w2[None, :]):
            raise SingularDynamicStiffness(f"a harmonic of Ω = {omega:.6g} rad/s sits on a fixed-interface "
                                           "eigenfrequency: the DOFs with mass are unbounded there")
        self._static_recovery()
        return x, np.where(excluded, 0.0, x[:, None] / (self._w2[None, :] * den))  # (2H+1, m)

    def _static_recovery(self) -> None:
        """Builds the left-out modes' share Ṽ_i(m) = Σ_{j>m} φ_j b_jᵀ/ω_j^{2i+2} and Z_0 once per
        reduction and m (n_l-sized: kept with the reduction for the next condensation)."""
        if self._V is None:
            red, m = self.reduction, self.n_modes
            memo = _RECOVERY.setdefault(red, {})
            if m not in memo:
                left = slice(m, red.n_modes)
                V = [red.V[i] + red.phi[:, left] @ (red.B[left] / red.omega[left, None] ** (2 * i + 2))
                     for i in range(KRYLOV_BLOCKS)]
                memo[m] = (V, V[0] + self.phi_j @ (self.b_j / self._w2[:, None]))
            self._V, self._Z0 = memo[m]

    def projected_cosine_recovery(self, omega: float, a: np.ndarray, projector: np.ndarray,
                                  exclude=()) -> np.ndarray:
        """``projector @ Q_l,k`` of the cosine motion ``a`` (H+1, n_c) of the massless DOFs,
        shape (n_p, H+1), without forming Q_l: the projections of Z_0, φ_j and Ṽ_i are
        computed once per projector (n_p, n_l) and reused (e.g. modal coordinates
        Φᵀ M q_l of a few modes, for their energy shares along a branch; the last
        :data:`_PROJECTORS` projectors are kept). Same formula and ``exclude`` convention
        as :meth:`recover`."""
        a = np.asarray(a, dtype=float)
        key = id(projector)
        store = self._projections
        cached = store.pop(key, None)
        if cached is not None and cached[0] is projector:
            store[key] = cached  # the most recently used last
        else:
            self._static_recovery()
            P = np.asarray(projector, dtype=float)
            cached = (projector, P @ self._Z0, P @ self.phi_j, [P @ V for V in self._V])
            store.pop(key, None)
            while len(store) >= _PROJECTORS:
                del store[next(iter(store))]
            store[key] = cached
        _, S0, S, SV = cached
        H = a.shape[0] - 1
        x = (np.arange(H + 1) * float(omega)) ** 2
        den = self._w2[None, :] - x[:, None]
        excluded = np.zeros(den.shape, dtype=bool)
        for k, j in exclude:
            excluded[k, j] = True
        excluded[0] = True  # harmonic 0: static, c = 0
        c = np.where(excluded, 0.0, x[:, None] / (self._w2[None, :] * np.where(excluded, 1.0, den)))
        out = S0 @ a.T + S @ (c.T * (self.b_j @ a.T))
        if not self.complete:
            for i in range(1, KRYLOV_BLOCKS):
                out += (SV[i] @ a.T) * x[None, :] ** i
        return -out

    def _keep(self, H: int, exclude) -> np.ndarray:
        if self._keep_all.shape[0] != H + 1:
            self._keep_all = np.ones((H + 1, self.n_modes), dtype=np.uint8)
        pairs = list(exclude)
        if not pairs:
            return self._keep_all
        keep = np.ones((H + 1, self.n_modes), dtype=np.uint8)
        for pair in pairs:
            try:
                k, j = (check.integer("exclude harmonic", pair[0]), check.integer("exclude mode", pair[1]))
            except (TypeError, IndexError):
                raise TypeError(f"exclude must hold (harmonic, mode) pairs of integers, got {pair!r}"
                                ) from None
            if not (1 <= k <= H and 0 <= j < self.n_modes):
                raise ValueError(f"exclude pair {pair!r} out of range: harmonic in [1, {H}], mode index in "
                                 f"[0, {self.n_modes - 1}]")
            keep[k, j] = 0
        return keep

    def __repr__(self) -> str:
        kept = "all" if self.complete else f"{self.n_modes} (cutoff {self.cutoff:.6g} Hz)"
        return (f"ModalCondensation(n_l={self.n_l}, n_c={self.n_c}, modes={kept}, "
                f"error_estimate={self.error_estimate:.2e})")


def _tail(red: ModalReduction, m: int, p: int) -> np.ndarray:
    """R(p; m) = Σ_{j>m} b_j b_jᵀ/ω_j^{2p} (n_c, n_c): the reduction's deflated moment
    (modes beyond those computed) plus the computed modes left out (positive terms)."""
    Bt = red.B[m:] / red.omega[m:, None] ** p
    R = red.R[p - 2] + Bt.T @ Bt
    return 0.5 * (R + R.T)


def _bound(w: float, w_next: float, R: np.ndarray, P: int) -> float:
    """ω^{2P+2}/(ω_{m+1}² − ω²) ‖R(P+1)‖₂ (inf at or past ω_{m+1}); 0 without left-out modes."""
    if not math.isfinite(w_next):
        return 0.0
    if w >= w_next:
        return math.inf
    return w ** (2 * P + 2) / (w_next**2 - w**2) * _norm2(R)


def _norm2(A: np.ndarray) -> float:
    """Spectral norm of a symmetric matrix."""
    return float(np.max(np.abs(np.linalg.eigvalsh(A)))) if A.size else 0.0
