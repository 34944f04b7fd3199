"""Two-node Timoshenko beam element in the plane, free of shear locking.

The element is the *interdependent interpolation element* (IIE): its shape functions are
the exact static solution of the Timoshenko beam equations (cubic deflection, quadratic
rotation, coupled through the shear parameter)

    Φ = 12 E I / (κ G A L²),

so the element reproduces any static end-loaded state exactly, has no shear locking as
Φ → 0 and reduces to the Euler–Bernoulli Hermite element there. The mass matrix is the
consistent one of the same shape functions, with translational (ρA) and rotary (ρI)
inertia (Przemieniecki 1968; Friedman & Kosmatka 1993, Comput. Struct. 47(3) 473–481).

Conventions
-----------
DOFs per node: transverse deflection ``w`` (m) and cross-section rotation ``θ`` (rad);
local order ``[w1, θ1, w2, θ2]``, node 1 at x = 0 and node 2 at x = L. θ is positive
counter-clockwise, so in the Euler–Bernoulli limit θ = dw/dx and the shear strain is
γ = dw/dx − θ. The rigid-body modes are the translation ``[1, 0, 1, 0]`` and the rotation
about the element's centre ``[-L/2, 1, L/2, 1]``.

All functions are vectorised over elements: element lengths come as an array of shape
(n_e,), element matrices go out with shape (n_e, 4, 4).
"""

from __future__ import annotations

import numpy as np

from .. import _validate as check

__all__ = ["shear_parameter", "stiffness", "mass", "element_matrices", "shape_functions"]


def shear_parameter(L, E: float, G: float, A: float, I: float, kappa: float) -> np.ndarray:
    """Φ = 12 E I / (κ G A L²), the ratio of bending to shear flexibility; shape of ``L``.

    Parameters
    ----------
    L : array_like, shape (n_e,)
        Element lengths (m).
    E, G : float
        Young's and shear moduli (Pa).
    A, I : float
        Cross-section area (m²) and second moment of area (m⁴).
    kappa : float
        Shear correction factor (5/6 for a rectangle).
    """
    L = np.asarray(L, dtype=float)
    return 12.0 * E * I / (kappa * G * A * L**2)


def stiffness(L, E: float, G: float, A: float, I: float, kappa: float) -> np.ndarray:
    """Element stiffness matrices of the IIE, shape (n_e, 4, 4).

    K = E I / ((1+Φ) L³) ·
        [[ 12,   6L,        −12,  6L       ],
         [ 6L,   (4+Φ)L²,   −6L,  (2−Φ)L²  ],
         [−12,  −6L,         12, −6L       ],
         [ 6L,   (2−Φ)L²,   −6L,  (4+Φ)L²  ]]

    Units: N/m (w–w), N (w–θ), N·m/rad (θ–θ). Parameters as in :func:`shear_parameter`.
    """
    L = _lengths(L)
    _constants(E=E, G=G, A=A, I=I, kappa=kappa)
    phi = shear_parameter(L, E, G, A, I, kappa)
    c = E * I / ((1.0 + phi) * L**3)
    K = np.empty(L.shape + (4, 4))
    K[:, 0, 0] = 12.0
    K[:, 0, 1] = 6.0 * L
    K[:, 0, 2] = -12.0
    K[:, 0, 3] = 6.0 * L
    K[:, 1, 1] = (4.0 + phi) * L**2
    K[:, 1, 2] = -6.0 * L
    K[:, 1, 3] = (2.0 - phi) * L**2
    K[:, 2, 2] = 12.0
    K[:, 2, 3] = -6.0 * L
    K[:, 3, 3] = (4.0 + phi) * L**2
    _mirror(K)
    return K * c[:, None, None]


def mass(L, E: float, G: float, rho: float, A: float, I: float, kappa: float) -> np.ndarray:
    """Consistent element mass matrices of the IIE, shape (n_e, 4, 4).

    M = ρA L/(1+Φ)² · T(Φ) + ρI/((1+Φ)² L) · R(Φ) with the translational coefficients

        T11 = 13/35 + 7Φ/10 + Φ²/3          T12 = (11/210 + 11Φ/120 + Φ²/24) L
        T13 = 9/70 + 3Φ/10 + Φ²/6           T14 = −(13/420 + 3Φ/40 + Φ²/24) L
        T22 = (1/105 + Φ/60 + Φ²/120) L²    T24 = −(1/140 + Φ/60 + Φ²/120) L²

    and the rotary ones

        R11 = 6/5                           R12 = (1/10 − Φ/2) L
        R13 = −6/5                          R22 = (2/15 + Φ/6 + Φ²/3) L²
        R24 = (−1/30 − Φ/6 + Φ²/6) L²

    completed by the element's symmetry about its centre (T33 = T11, T34 = −T12,
    T23 = −T14, T44 = T22, R14 = R12, R23 = R34 = −R12, R33 = R11, R44 = R22).
    Units: kg (w–w), kg·m (w–θ), kg·m² (θ–θ). ``rho`` in kg/m³, other parameters as in
    :func:`shear_parameter`.
    """
    L = _lengths(L)
    _constants(E=E, G=G, rho=rho, A=A, I=I, kappa=kappa)
    p = shear_parameter(L, E, G, A, I, kappa)
    p2 = p * p
    T = np.empty(L.shape + (4, 4))
    t11 = 13 / 35 + 7 / 10 * p + p2 / 3
    t12 = (11 / 210 + 11 / 120 * p + p2 / 24) * L
    t13 = 9 / 70 + 3 / 10 * p + p2 / 6
    t14 = -(13 / 420 + 3 / 40 * p + p2 / 24) * L
    t22 = (1 / 105 + p / 60 + p2 / 120) * L**2
    t24 = -(1 / 140 + p / 60 + p2 / 120) * L**2
    T[:, 0, 0], T[:, 0, 1], T[:, 0, 2], T[:, 0, 3] = t11, t12, t13, t14
    T[:, 1, 1], T[:, 1, 2], T[:, 1, 3] = t22, -t14, t24
    T[:, 2, 2], T[:, 2, 3] = t11, -t12
    T[:, 3, 3] = t22
    _mirror(T)

    R = np.empty(L.shape + (4, 4))
    r11 = np.full_like(L, 6 / 5)
    r12 = (1 / 10 - p / 2) * L
    r22 = (2 / 15 + p / 6 + p2 / 3) * L**2
    r24 = (-1 / 30 - p / 6 + p2 / 6) * L**2
    R[:, 0, 0], R[:, 0, 1], R[:, 0, 2], R[:, 0, 3] = r11, r12, -r11, r12
    R[:, 1, 1], R[:, 1, 2], R[:, 1, 3] = r22, -r12, r24
    R[:, 2, 2], R[:, 2, 3] = r11, -r12
    R[:, 3, 3] = r22
    _mirror(R)

    s = 1.0 / (1.0 + p) ** 2
    return (rho * A * L * s)[:, None, None] * T + (rho * I * s / L)[:, None, None] * R


def element_matrices(L, E: float, G: float, rho: float, A: float, I: float,
                     kappa: float) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and consistent mass of the IIE for every element.

    Parameters
    ----------
    L : array_like, shape (n_e,)
        Element lengths (m), > 0.
    E, G : float
        Young's and shear moduli (Pa).
    rho : float
        Density (kg/m³).
    A, I : float
        Cross-section area (m²) and second moment of area (m⁴).
    kappa : float
        Shear correction factor.

    Returns
    -------
    K, M : ndarray, shape (n_e, 4, 4)
        Element stiffness and mass in the local order ``[w1, θ1, w2, θ2]``.
    """
    return stiffness(L, E, G, A, I, kappa), mass(L, E, G, rho, A, I, kappa)


def shape_functions(xi, L: float, phi: float) -> tuple[np.ndarray, np.ndarray]:
    """IIE shape functions at local coordinates ``xi = x/L`` in [0, 1].

    ``w(x) = N_w @ [w1, θ1, w2, θ2]`` and ``θ(x) = N_θ @ [w1, θ1, w2, θ2]``; use them to
    draw the deflection between nodes.

    Parameters
    ----------
    xi : array_like, shape (m,)
        Local coordinates.
    L : float
        Element length (m).
    phi : float
        Shear parameter Φ of the element (:func:`shear_parameter`).

    Returns
    -------
    N_w, N_theta : ndarray, shape (m, 4)
    """
    x = np.atleast_1d(np.asarray(xi, dtype=float))
    mu = 1.0 / (1.0 + phi)
    x2, x3 = x * x, x * x * x
    N_w = mu * np.stack([
        2 * x3 - 3 * x2 - phi * x + 1 + phi,
        L * (x3 - (2 + phi / 2) * x2 + (1 + phi / 2) * x),
        -(2 * x3 - 3 * x2 - phi * x),
        L * (x3 - (1 - phi / 2) * x2 - phi / 2 * x),
    ], axis=-1)
    N_t = mu * np.stack([
        6 / L * (x2 - x),
        3 * x2 - (4 + phi) * x + 1 + phi,
        -6 / L * (x2 - x),
        3 * x2 - (2 - phi) * x,
    ], axis=-1)
    return N_w, N_t


def _lengths(L) -> np.ndarray:
    """Element lengths as a 1-D float array, checked finite and > 0."""
    try:
        L = np.atleast_1d(np.asarray(L, dtype=float))
    except (TypeError, ValueError):
        raise TypeError(f"element lengths L must be numbers, got {L!r}") from None
    bad = np.flatnonzero(~(np.isfinite(L) & (L > 0)))
    if L.ndim != 1 or bad.size:
        where = f"L[{bad[0]}] = {float(L.ravel()[bad[0]])!r}" if bad.size else f"shape {L.shape}"
        raise ValueError(f"element lengths L must be a 1-D array of finite lengths > 0 (m), got {where}")
    return L


def _constants(**values) -> None:
    """Section and material constants must be finite and > 0."""
    for name, value in values.items():
        check.positive(name, value)


def _mirror(A: np.ndarray) -> None:
    """Copy the upper triangle of each (4, 4) block onto its lower triangle, in place."""
    i, j = np.triu_indices(4, k=1)
    A[:, j, i] = A[:, i, j]
