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
[lo, hi] = [−s, s] (:func:`mmshbm.core.projection.project_contact`): the instants where
p = ±s are the zeros of the trigonometric polynomials p ∓ s, located by its root finder,
the pieces are integrated in closed form, and its Jacobian G (the projection of the
indicator of |p| > s) gives ∂proj[clip]/∂p = I − G exactly. This module calls that
projection and does not copy it; the pointwise kernels below are self-contained (Numba
caches a kernel per file).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..core.kernels import JIT_OPTIONS

__all__ = ["coulomb_residual", "coulomb_derivative", "project_coulomb", "derivative_matrix"]


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
    from ..core.projection import project_contact

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
