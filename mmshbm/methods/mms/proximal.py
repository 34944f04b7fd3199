"""The proximal parameter r of the MMS-HBM contact law, and what it does at finite H.

The proximal form of the Signorini law, f + r((p − hi)₊ − (lo − p)₊) = 0 with
p = q − f/r, has the same zeros for every r > 0 as long as q and f are the exact signals.
The harmonic balance solves it only on the harmonics 0..H of a degree-H q and f, and that
truncated solution *does* depend on r: the series is cut in a different variable.

What r = D_∞ means. Let D(ω) be the condensed dynamic stiffness at the massless DOFs and
q = D(kΩ)⁻¹ f harmonic by harmonic. For a contact DOF i write the compliance of the
harmonics the series drops, k > H, as 1/r: then the exact q is q_H + (f − f_H)/r, and

    p = q − f/r = q_H − f_H/r

has no harmonics above H to the extent that compliance is 1/r: the truncated problem solves for the
quasi-static position of the contact DOF driven by the rest of the structure, with the
contact force computed pointwise from it, instead of for the contact DOF's own position
(which rests on the stop for a while and has kinks where the contact opens and closes:
coefficients ~1/k², the slowest series of the problem). On a one-DOF oscillator with a
stiff stop this is the harmonic balance of the mass's displacement under a bilinear
force (the classical alternating frequency-time scheme), whose coefficients fall ~1/k⁴.

The compliance of the dropped harmonics. For k > H the open-contact modes below
(H+1)·ω_ref respond mass-like (their receptance ~ −φ²/(kΩ)², small) and those above
respond statically, so

    1/r_i = [ D_0⁻¹ − Σ_{ω_j ≤ (H+1) ω_ref} φ_j φ_jᵀ / ω_j² ]_ii ,

the residual compliance of the modes above the truncation frequency (``r="residual"``),
bounded below by the compliance with every DOF with mass clamped, [K_cc⁻¹]_ii, its
H → ∞ limit. The default r is the static stiffness (D_0⁻¹)_ii⁻¹ of 0.1 (all modes
counted as static), which keeps the branches of earlier versions bit for bit.

Measured (docs/exact.md): on chains whose contact is much stiffer than the structure
``r="residual"`` cuts the truncation error at H = 31 by 5–90× against the exact orbit;
on the 21-element beam the truncated solutions with the two r differ by up to 10 % near
grazing, where no harmonic balance is converged (the exact orbits rattle).
"""

from __future__ import annotations

import numpy as np

from ... import _validate as check

__all__ = ["PROXIMAL_RULES", "proximal_parameter", "residual_stiffness"]

#: the named choices of ``r``: "static" (the default, None) and "residual"
PROXIMAL_RULES = ("static", "residual")


def residual_stiffness(model, D0: np.ndarray, cdof: np.ndarray, harmonics: int, mode: int = 1) -> np.ndarray:
    """r of each contact DOF from the residual compliance of the modes above the truncation
    frequency (module docstring), N/m; shape (len(cdof),).

    Parameters
    ----------
    model : Model
        The structure (its open-contact modes, mass-normalised, and ``K_cc``).
    D0 : ndarray, shape (n_c, n_c)
        The condensed static stiffness at the massless DOFs (``model.c`` order).
    cdof : ndarray of int
        Positions of the contact DOFs inside ``model.c``.
    harmonics : int
        The truncation H: modes up to (H+1) times the starting mode's frequency count as
        mass-like for the dropped harmonics.
    mode : int
        The linear mode (1-based) the branch starts from (its frequency is ω_ref).
    """
    n_l = len(model.l)
    f_ref = float(model.linear_modes(mode)[0][-1])
    cut = (harmonics + 1) * f_ref
    n = min(n_l, max(mode, 8))
    while True:
        freqs, modes = model.linear_modes(n)
        if freqs[-1] > cut or n == n_l:
            break
        n = min(n_l, 2 * n)
    low = freqs <= cut
    phi_c = modes[np.ix_(model.c, np.flatnonzero(low))]
    w2 = (2 * np.pi * freqs[low]) ** 2
    compliance = np.linalg.inv(D0) - (phi_c / w2) @ phi_c.T
    clamped = np.linalg.inv(np.asarray(model.blocks["K_cc"], dtype=float))
    c_res = np.maximum(np.diag(compliance)[cdof], np.diag(clamped)[cdof])
    return 1.0 / c_res


def proximal_parameter(r, static: np.ndarray, model, D0: np.ndarray, cdof: np.ndarray, harmonics: int,
                       mode: int = 1) -> np.ndarray:
    """r of each contact DOF (N/m), shape (len(cdof),), from the option ``r``: None or
    "static" (``static``, the contact DOFs' condensed static stiffness), "residual"
    (:func:`residual_stiffness`), or a positive number, one for all or one per contact DOF.

    Raises
    ------
    ValueError
        For another name, a non-positive number or the wrong count.
    """
    n = len(cdof)
    if r is None or (isinstance(r, str) and r == "static"):
        return np.array(static, dtype=float).copy()
    if isinstance(r, str):
        if r != "residual":
            raise ValueError(f"r must be a positive number, one per contact DOF, or one of "
                             f"{PROXIMAL_RULES}, got {r!r}")
        return residual_stiffness(model, D0, cdof, harmonics, mode)
    r_arr = np.atleast_1d(np.asarray(r, dtype=float))
    if r_arr.ndim != 1 or len(r_arr) not in (1, n):
        raise ValueError(f"r must be a number or one per contact DOF ({n}), got {r!r}")
    for v in r_arr:
        check.positive("r", float(v))
    return np.broadcast_to(r_arr, (n,)).astype(float).copy()
