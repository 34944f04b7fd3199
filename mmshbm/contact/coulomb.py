"""Coulomb dry friction at a massless DOF, without regularisation.

Notation. ``f`` is the force the node exerts on the support in the friction direction (N;
the support pushes back with −f), ``u̇`` the node's velocity, s = μN >= 0 the slip force.
Coulomb's law f ∈ s·Sign(u̇) (|f| <= s; u̇ ≠ 0 only where |f| = s, with f u̇ = s|u̇| >= 0,
the power dissipated) is, for any r > 0, the proximal point equation

    f = prox_[−s, s](f + r u̇) = clip(f + r u̇, −s, s):

stick (u̇ = 0): f = clip(f) ⇔ |f| <= s; slip u̇ > 0: clip(f + r u̇) = f only at f = s
(below s the argument exceeds f and clip moves it up); u̇ < 0 mirrors it. The solution
does not depend on r; Newton's conditioning does (r of the order of the condensed
tangential stiffness over Ω). In the solvers' convention the force the structure *needs*
at the DOF (K_cl q_l + K_cc q_c) is the support's force on the node, −f.

Residual R = f − clip(p, −s, s), p = f + r u̇, with the derivative
∂clip/∂p = [|p| < s] (clip is continuous: no boundary terms).

Harmonic projection. On the Fourier ansatz p(τ) is a trigonometric polynomial, and

    clip(p, −s, s) = p − [(p − s)₊ − (−s − p)₊],

the bracket being exactly the unilateral law's projection on the admissible interval
[lo, hi] = [−s, s] (:func:`mmshbm.contact.unilateral.project_contact`): the instants where
p = ±s are the zeros of the trigonometric polynomials p ∓ s, located by its root finder,
the pieces are integrated in closed form, and its Jacobian G (the projection of the
indicator of |p| > s) gives ∂proj[clip]/∂p = I − G exactly. This module calls that
projection and does not copy it; the pointwise kernels below are self-contained (Numba
caches a kernel per file). The displacement-level projection (:func:`project_coulomb_play`)
is one compiled call (:mod:`mmshbm.contact.coulomb_play_kernels`: the extrema of y, the
walk over them, the spectra, the force and its Jacobian); :func:`play_pieces` and the NumPy
reference of the projection (``_project_play_numpy``) call the root finder of
:mod:`mmshbm.contact.trig` from Python and the compiled walk.

The Jenkins element of penalty harmonic balance (a spring in series with the slider:
Coulomb's law at a massless node behind a spring) is evaluated by AFT with the return map
f_j = clip(f_{j−1} + k Δu_j, −s, s) over two passes (:func:`jenkins_hysteresis`), the same
clip as the proximal equation above, applied to displacement increments.
"""

from __future__ import annotations

import functools

import numpy as np
from numba import njit

from .._kernel_cache import JIT_OPTIONS
from .._kernel_cache import install as _install_cache_policy
from .coulomb_play_kernels import _play_pieces, _play_projection, _play_walk
from .trig import _TWO_PI, _zeros

__all__ = ["coulomb_residual", "coulomb_derivative", "project_coulomb", "project_coulomb_play", "play_pieces",
           "derivative_matrix", "jenkins_hysteresis"]

_install_cache_policy()


@njit(**JIT_OPTIONS)
def _coulomb_residual(f, v, s, r, R):
    """In place: R_j = f_j − clip(f_j + r v_j, −s_j, s_j); all arrays shape (N,), r > 0."""
    for j in range(f.shape[0]):
        p = f[j] + r * v[j]
        if p > s[j]:
            R[j] = f[j] - s[j]
        elif p < -s[j]:
            R[j] = f[j] + s[j]
        else:
            R[j] = -r * v[j]


@njit(**JIT_OPTIONS)
def _coulomb_derivative(f, v, s, r, dR_df, dR_dv):
    """In place: ∂R/∂f = 1 − χ, ∂R/∂v = −r χ with χ_j = [|f_j + r v_j| < s_j] (stick)."""
    for j in range(f.shape[0]):
        p = f[j] + r * v[j]
        if -s[j] < p < s[j]:
            dR_df[j] = 0.0
            dR_dv[j] = -r
        else:
            dR_df[j] = 1.0
            dR_dv[j] = 0.0


def _pointwise_args(f, v, s, r):
    f = np.ascontiguousarray(f, dtype=float)
    v = np.ascontiguousarray(v, dtype=float)
    if f.ndim != 1 or v.shape != f.shape:
        raise ValueError(f"f and v must be 1-D of equal length, got {f.shape} and {v.shape}")
    s = np.ascontiguousarray(np.broadcast_to(np.asarray(s, dtype=float), f.shape))
    if np.any(s < 0) or not np.all(np.isfinite(s)):
        raise ValueError("slip force s must be finite and >= 0")
    r = float(r)
    if not r > 0:
        raise ValueError(f"r must be > 0, got {r!r}")
    return f, v, s, r


def coulomb_residual(f: np.ndarray, v: np.ndarray, s, r: float) -> np.ndarray:
    """Pointwise residual R = f − clip(f + r v, −s, s).

    Parameters
    ----------
    f : ndarray, shape (N,)
        Force the node exerts on the support (N).
    v : ndarray, shape (N,)
        Node velocity (m/s, or m per unit of normalised time when r is scaled alike).
    s : float or ndarray (N,)
        Slip force μN >= 0 (N).
    r : float
        Proximal parameter > 0 (N·s/m).

    Returns
    -------
    R : ndarray, shape (N,) (N); zero exactly where (f, v) satisfy Coulomb's law.
    """
    f, v, s, r = _pointwise_args(f, v, s, r)
    R = np.empty_like(f)
    _coulomb_residual(f, v, s, r, R)
    return R


def coulomb_derivative(f: np.ndarray, v: np.ndarray, s, r: float) -> tuple[np.ndarray, np.ndarray]:
    """Pointwise (∂R/∂f, ∂R/∂v), each shape (N,), of :func:`coulomb_residual` (the
    semismooth derivative; at |p| = s exactly the slip branch is taken)."""
    f, v, s, r = _pointwise_args(f, v, s, r)
    a, b = np.empty_like(f), np.empty_like(f)
    _coulomb_derivative(f, v, s, r, a, b)
    return a, b


def derivative_matrix(H: int) -> np.ndarray:
    """(2H+1, 2H+1) matrix of d/dτ on NLvib-ordered coefficients [c_0, c_1, s_1, ...]:
    (c_k cos kτ + s_k sin kτ)' = k s_k cos kτ − k c_k sin kτ."""
    Dt = np.zeros((2 * H + 1, 2 * H + 1))
    for k in range(1, H + 1):
        Dt[2 * k - 1, 2 * k] = k
        Dt[2 * k, 2 * k - 1] = -k
    return Dt


def project_coulomb(f: np.ndarray, v: np.ndarray, s: float, r: float, exact: bool = True,
                    n_samples: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Harmonic projection of R(τ) = f − clip(f + r v, −s, s) and its exact Jacobian.

    Parameters
    ----------
    f, v : ndarray, shape (2H+1,)
        NLvib-ordered coefficients of the force on the support (N) and of the velocity
        (in the time unit that makes r v a force).
    s : float
        Constant slip force μN >= 0 (N).
    r : float
        Proximal parameter > 0.
    exact : bool
        Switching instants located and the pieces integrated in closed form (default), or
        sampled on ``n_samples`` points (AFT).
    n_samples : int, optional
        Bracketing grid (exact) or sample count (sampled); default 16·(2H+1).

    Returns
    -------
    R : ndarray (2H+1,)
        NLvib-ordered projection of the residual (N).
    dR_df, dR_dv : ndarray (2H+1, 2H+1)
        G and −r (I − G), G the projection of the slip indicator [|p| > s].
    slip : float
        Fraction of the period in slip, G[0, 0] (0: the node sticks throughout).
    """
    from .unilateral import project_contact

    f = np.asarray(f, dtype=float)
    v = np.asarray(v, dtype=float)
    if f.ndim != 1 or f.shape[0] % 2 != 1 or v.shape != f.shape:
        raise ValueError(f"f and v must be 1-D with 2H+1 entries each, got {f.shape} and {v.shape}")
    s = float(s)
    if not (s >= 0 and np.isfinite(s)):
        raise ValueError(f"slip force s must be finite and >= 0, got {s!r}")
    r = float(r)
    if not r > 0:
        raise ValueError(f"r must be > 0, got {r!r}")
    p = f + r * v
    phi, G = project_contact(p, -s, s, exact=exact, n_samples=n_samples)
    # R = f − (p − φ) = φ − r v
    R = phi - r * v
    dR_dv = -r * (np.eye(len(f)) - G)
    return R, G, dR_dv, float(G[0, 0])


# ---------------------------------------------------------------------- displacement level
def _phi(H: int, tau: float) -> np.ndarray:
    """NLvib-ordered basis [1, cos τ, sin τ, ..., cos Hτ, sin Hτ] at one τ."""
    k = np.arange(1, H + 1)
    out = np.empty(2 * H + 1)
    out[0] = 1.0
    out[1::2] = np.cos(k * tau)
    out[2::2] = np.sin(k * tau)
    return out


@functools.lru_cache(maxsize=32)
def _sample_basis(H: int, N: int):
    """τ_j = 2πj/N and cos/sin(k τ_j), k = 0..H ((H+1, N) each), read-only."""
    tau = 2 * np.pi * np.arange(N) / N
    k = np.arange(H + 1)
    out = (tau, np.cos(np.outer(k, tau)), np.sin(np.outer(k, tau)))
    for arr in out:
        arr.flags.writeable = False
    return out


def _play_arrays(y: np.ndarray, s: float, r: float, n_samples: int | None = None):
    """The pieces of :func:`play_pieces` as arrays (a, b, σ, u, τ_e)."""
    y = np.asarray(y, dtype=float)
    H = (y.shape[0] - 1) // 2
    N = 16 * (2 * H + 1) if n_samples is None else int(n_samples)
    k = np.arange(1, H + 1)
    c, sn = np.concatenate([[y[0]], y[1::2]]), np.concatenate([[0.0], y[2::2]])
    dc, ds = np.concatenate([[0.0], k * sn[1:]]), np.concatenate([[0.0], -k * c[1:]])  # y′
    tau, cos_t, sin_t = _sample_basis(H, N)
    d1 = dc @ cos_t + ds @ sin_t
    d2 = (k * ds[1:]) @ cos_t[1:] - (k * dc[1:]) @ sin_t[1:]
    roots = np.empty(2 * N + 2)
    n_ext = _zeros(dc, ds, d1, d2, tau, roots)
    ext = roots[:n_ext]
    width = s / r

    def one(a, b, sg, u, te):
        return tuple(np.array([v], dtype=float) for v in (a, b, sg, u, te))

    if n_ext == 0:
        return one(0.0, _TWO_PI, 0, float(y[0]), np.nan)
    vals = c[0] + np.cos(np.outer(ext, k)) @ c[1:] + np.sin(np.outer(ext, k)) @ sn[1:]
    i_max, i_min = int(np.argmax(vals)), int(np.argmin(vals))
    y_max, y_min = vals[i_max], vals[i_min]
    if y_max - y_min <= 2 * width:
        if y[0] < y_max - width:
            return one(0.0, _TWO_PI, 0, y_max - width, float(ext[i_max]))
        if y[0] > y_min + width:
            return one(0.0, _TWO_PI, 0, y_min + width, float(ext[i_min]))
        return one(0.0, _TWO_PI, 0, float(y[0]), np.nan)
    order = np.roll(np.arange(n_ext), -i_max)
    pts = np.concatenate([ext[order], [ext[i_max] + _TWO_PI]])
    pv = np.concatenate([vals[order], [y_max]])
    pts[1:-1] = np.where(pts[1:-1] < pts[0], pts[1:-1] + _TWO_PI, pts[1:-1])
    cap = 2 * len(pts)
    out = [np.empty(cap) for _ in range(5)]
    m = _play_walk(pts, pv, c, sn, width, *out)
    return tuple(arr[:m] for arr in out)


def play_pieces(y: np.ndarray, s: float, r: float, n_samples: int | None = None) -> list:
    """Stick and slip pieces of the periodic Coulomb law driven by ``y`` (see
    :func:`project_coulomb_play`), over one period starting at y's global maximum.

    Returns a list of (a, b, σ, u, τ_e): the arc [a, b] (a in [0, 2π), b <= a + 2π), σ = 0
    stick at the node position u (set at the extremum τ_e of y, so ∂u/∂y = φ(τ_e)), σ = ±1
    slip in the direction σ (u = y − σ s/r). Full stick (y's range <= 2s/r): one piece
    [0, 2π] at the symmetric position u = mean(y) (mean force zero, τ_e = NaN: ∂u/∂y = e_0),
    or clamped into the band where |r (u − y)| <= s (at y's maximum or minimum, τ_e there).
    Compiled (:func:`mmshbm.contact.coulomb_play_kernels._play_pieces`; ``_play_arrays``
    is its NumPy reference).
    """
    y, s, r, H = _play_args(y, s, r)
    N = 16 * (2 * H + 1) if n_samples is None else int(n_samples)
    tau, cos_t, sin_t = _sample_basis(H, N)
    cap = 2 * (2 * N + 3)
    a, b, sg, u, te = (np.empty(cap) for _ in range(5))
    m = _play_pieces(y, s, r, tau, cos_t, sin_t, a, b, sg, u, te)
    return [(float(a[i]), float(b[i]), int(sg[i]), float(u[i]), float(te[i])) for i in range(m)]


def project_coulomb_play(y: np.ndarray, s: float, r: float, n_samples: int | None = None,
                         jacobian: bool = True) -> tuple[np.ndarray, np.ndarray | None, float]:
    """Exact harmonic projection of the support's force g = r (u − y) of a massless Coulomb
    node whose position u is driven by the periodic signal y, and its exact Jacobian.

    The law at the displacement level. For a massless node with the force g the support
    exerts on it and any r > 0, write y = u − g/r. Coulomb's law (stick while |g| < s,
    slip with g = −s sign u̇) is then exactly: u stays put while |u − y| < s/r and is
    dragged at u = y ∓ s/r when y pushes it (the play operator of half-width s/r, the time
    integral of the proximal equation). For a periodic y with range > 2s/r the periodic
    motion is reached in one pass from y's global maximum, where the node has just been
    dragged up, u = y_max − s/r (:func:`play_pieces`); with a smaller range the node sticks
    throughout and its position is history: the symmetric position (mean force zero) is
    taken. Extrema of y are the zeros of the trigonometric polynomial y′ and stick-to-slip
    instants the zeros of y − level, located by the unilateral projection's root finder
    (:mod:`mmshbm.contact.trig`); g is r (u − y) or −σ s on the pieces, integrated
    in closed form. g is continuous at every switch and u's dependence on the extremum's
    time vanishes there (y′ = 0), so the Jacobian has no boundary terms:

        ∂proj[g]/∂y = Σ_stick r (proj[χ_arc] φ(τ_e)ᵀ − proj[χ_arc φ_b]).

    Parameters
    ----------
    y : ndarray (2H+1,)
        NLvib-ordered coefficients of y (m).
    s : float
        Slip force >= 0 (N).
    r : float
        Stiffness parameter > 0 (N/m).
    n_samples : int, optional
        Bracketing grid of the root finder; default 16·(2H+1).
    jacobian : bool
        If False skip the Jacobian (returned as None): a residual-only evaluation.

    Returns
    -------
    g : ndarray (2H+1,)
        NLvib-ordered projection of the support's force (N).
    dg_dy : ndarray (2H+1, 2H+1) or None
    slip : float
        Fraction of the period in slip.
    """
    y, s, r, H = _play_args(y, s, r)
    N = 16 * (2 * H + 1) if n_samples is None else int(n_samples)
    tau, cos_t, sin_t = _sample_basis(H, N)
    g = np.empty(2 * H + 1)
    J = np.empty((2 * H + 1, 2 * H + 1)) if jacobian else np.empty((0, 0))
    slip = _play_projection(y, s, r, tau, cos_t, sin_t, jacobian, g, J)
    return g, (J if jacobian else None), float(slip)


def _play_args(y, s, r):
    """Validated (y as contiguous float64 (2H+1,), s, r, H) of the play projection."""
    y = np.ascontiguousarray(y, dtype=float)
    if y.ndim != 1 or y.shape[0] % 2 != 1:
        raise ValueError(f"y must be 1-D with 2H+1 entries, got shape {y.shape}")
    s, r = float(s), float(r)
    if not (s >= 0 and np.isfinite(s)):
        raise ValueError(f"slip force s must be finite and >= 0, got {s!r}")
    if not r > 0:
        raise ValueError(f"r must be > 0, got {r!r}")
    return y, s, r, (y.shape[0] - 1) // 2


def _project_play_numpy(y: np.ndarray, s: float, r: float, n_samples: int | None = None,
                        jacobian: bool = True) -> tuple[np.ndarray, np.ndarray | None, float]:
    """:func:`project_coulomb_play` evaluated piece by piece in NumPy from
    :func:`play_pieces`: the readable reference of the compiled kernel
    (:func:`mmshbm.contact.coulomb_play_kernels._play_projection`)."""
    from .projection import _product_matrix

    y, s, r, H = _play_args(y, s, r)
    a, b, sigma, u, t_e = _play_arrays(y, s, r, n_samples)
    # spectra C_n = (1/2π)∫_a^b cos nτ, S_n = (1/2π)∫_a^b sin nτ (n = 0..2H) of every
    # piece's indicator, in closed form
    n = np.arange(1, 2 * H + 1)
    C = np.empty((len(a), 2 * H + 1))
    S = np.empty((len(a), 2 * H + 1))
    C[:, 0], S[:, 0] = b - a, 0.0
    C[:, 1:] = (np.sin(np.outer(b, n)) - np.sin(np.outer(a, n))) / n
    S[:, 1:] = (np.cos(np.outer(a, n)) - np.cos(np.outer(b, n))) / n
    C /= 2 * np.pi
    S /= 2 * np.pi
    ind = np.empty((len(a), 2 * H + 1))  # NLvib-ordered projection of each indicator
    ind[:, 0] = C[:, 0]
    ind[:, 1::2] = 2 * C[:, 1:H + 1]
    ind[:, 2::2] = 2 * S[:, 1:H + 1]
    slipping = sigma != 0
    stick = ~slipping
    slip = float(np.sum(b[slipping] - a[slipping]) / (2 * np.pi))
    g = -s * (sigma[slipping] @ ind[slipping]) + r * (u[stick] @ ind[stick])
    C_stick, S_stick = C[stick].sum(axis=0), S[stick].sum(axis=0)
    if not jacobian:
        return g - r * _product_vector(C_stick, S_stick, y, H), None, slip
    J = np.zeros((2 * H + 1, 2 * H + 1))
    for i in np.flatnonzero(stick):
        if np.isnan(t_e[i]):  # full stick at the symmetric position u = mean(y)
            J[:, 0] += r * ind[i]
        else:
            J += r * np.outer(ind[i], _phi(H, t_e[i]))
    G = _product_matrix(C_stick, S_stick, H)
    g -= r * (G @ y)
    J -= r * G
    return g, J, slip


def _product_vector(C: np.ndarray, S: np.ndarray, y: np.ndarray, H: int) -> np.ndarray:
    """proj[χ y] for the indicator χ of spectrum (C, S) (n = 0..2H) and the NLvib-ordered
    y (2H+1,): the product of the two series truncated to harmonics 0..H, without forming
    the product matrix."""
    a = np.concatenate([[y[0]], 0.5 * y[1::2]])   # y = Σ_k a_k e^{ikτ} + c.c. (a_0 real)
    b = np.concatenate([[0.0], -0.5 * y[2::2]])
    yc = a + 1j * b                                 # complex coefficient of e^{ikτ}, k >= 0
    chi = C - 1j * S                                # χ = Σ_n χ_n e^{inτ}, χ_{-n} = conj(χ_n)
    full_y = np.concatenate([np.conj(yc[:0:-1]), yc])         # k = −H..H
    full_c = np.concatenate([np.conj(chi[:0:-1]), chi])       # n = −2H..2H
    prod = np.convolve(full_c, full_y)                        # index of m: m + 3H
    p = prod[3 * H:4 * H + 1]                                 # m = 0..H
    out = np.empty(2 * H + 1)
    out[0] = p[0].real
    out[1::2] = 2 * p[1:].real
    out[2::2] = -2 * p[1:].imag
    return out


@njit(**JIT_OPTIONS)
def _jenkins_passes(u, B, s, k, f, df):
    """In place: the periodic force f (N,) of a Jenkins element (spring k, slider of slip
    force s) driven by the samples u (N,) and df[j] = ∂f_j/∂c (N, m) for u = B c (B the
    (N, m) derivative of the samples with respect to m parameters), by two passes of the
    return map f_j = clip(f_{j−1} + k (u_j − u_{j−1}), −s, s). The first pass starts
    with the slider at mean(u) (f = k (u_0 − mean u), clipped); the second starts from the
    end of the first, so the hysteresis is periodic whenever the slider slipped in the
    first pass (and the symmetric stuck position, mean force zero, where it never slips)."""
    n, m = B.shape
    mean = 0.0
    for i in range(n):
        mean += u[i]
    mean /= n
    d = np.zeros(m)  # ∂f_prev/∂c
    for i in range(n):
        for c in range(m):
            d[c] -= k * B[i, c] / n
    for c in range(m):
        d[c] += k * B[0, c]
    fp = k * (u[0] - mean)
    if fp > s or fp < -s:
        fp = s if fp > s else -s
        d[:] = 0.0
    for sweep in range(2):
        for j in range(n):
            jm = j - 1 if j > 0 else n - 1
            if sweep == 0 and j == 0:
                trial = fp  # the start itself
            else:
                trial = fp + k * (u[j] - u[jm])
                for c in range(m):
                    d[c] += k * (B[j, c] - B[jm, c])
            if trial > s or trial < -s:
                fp = s if trial > s else -s
                d[:] = 0.0
            else:
                fp = trial
            if sweep == 1:
                f[j] = fp
                for c in range(m):
                    df[j, c] = d[c]


def jenkins_hysteresis(u: np.ndarray, s: float, k: float,
                       basis: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Periodic force of a Jenkins element (a spring k in series with a Coulomb slider of
    slip force s) driven by the samples u of one period, and its exact derivative.

    The slider is Coulomb's law at a massless node joined to the driven point by the
    spring: the node sticks while |k (u − w)| < s and slides with |f| = s, the discrete
    return map f_j = clip(f_{j−1} + k Δu_j, −s, s) being its exact solution for u
    piecewise linear between samples. Two passes over the period make the hysteresis
    periodic (the slip erases the start); this is the alternating frequency-time (AFT)
    evaluation of the Jenkins element of penalty harmonic balance (NLvib's
    ``elasticDryFriction``, pyHarm's Jenkins element).

    Parameters
    ----------
    u : ndarray (N,)
        Displacement of the driven point at τ_j = 2πj/N (m).
    s : float
        Slip force >= 0 (N).
    k : float
        Spring stiffness > 0 (N/m).
    basis : ndarray (N, m), optional
        ∂u/∂c for m parameters c (e.g. the harmonic coefficients: the synthesis matrix);
        default the identity (derivatives with respect to the samples).

    Returns
    -------
    f : ndarray (N,)
        The force the element exerts on its support (N), the spring's tension k (u − w).
    df : ndarray (N, m)
        ∂f_j/∂c (∂f_j/∂u_i without ``basis``), propagated along the passes (O(N m)).
    """
    u = np.ascontiguousarray(u, dtype=float)
    if u.ndim != 1 or u.shape[0] < 2:
        raise ValueError(f"u must be 1-D with at least 2 samples, got shape {u.shape}")
    s, k = float(s), float(k)
    if not (s >= 0 and np.isfinite(s)):
        raise ValueError(f"slip force s must be finite and >= 0, got {s!r}")
    if not (k > 0 and np.isfinite(k)):
        raise ValueError(f"spring stiffness k must be finite and > 0, got {k!r}")
    B = np.eye(u.shape[0]) if basis is None else np.ascontiguousarray(basis, dtype=float)
    if B.ndim != 2 or B.shape[0] != u.shape[0]:
        raise ValueError(f"basis must have shape ({u.shape[0]}, m), got {B.shape}")
    f = np.empty(u.shape[0])
    df = np.empty((u.shape[0], B.shape[1]))
    _jenkins_passes(u, B, s, k, f, df)
    return f, df
