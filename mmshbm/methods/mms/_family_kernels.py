"""Compiled per-point family records of an MMS-HBM backbone: the kinetic energy of each
harmonic, the fundamental's share and the strongest higher harmonic's detuning from the
nearest tracked mode (:meth:`~mmshbm.methods.mms.family.FamilyMixin.family_records`).

Plain loops: the energies a_kᵀ ∂D_k/∂Ω a_k and their total are sums of a few terms, equal to
NumPy's expressions of them up to the round-off of those sums. ``argmax``/``argmin`` take the
first extremum (the first NaN where there is one), as NumPy's do.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["harmonic_energies", "family_records"]

_JIT = dict(cache=True, nogil=True)  # no fast-math: NaNs propagate as in NumPy


@njit(**_JIT)
def _harmonic_energies(a, dD, eta, pole_k, omega, energies):
    """In place: energies (H+1,) J, T_k = max(−(Ω/8)(a_kᵀ ∂D_k/∂Ω a_k − 2k²Ω Σ_p η_p²), 0),
    T_0 = 0; a (H+1, n_c), dD (H+1, n_c, n_c), eta (n_p,), pole_k (n_p,) int."""
    n_k, n_c = a.shape
    for k in range(n_k):
        s = 0.0
        for i in range(n_c):
            for j in range(n_c):
                s += a[k, i] * dD[k, i, j] * a[k, j]
        energies[k] = s
    for p in range(len(pole_k)):
        k = pole_k[p]
        energies[k] -= 2.0 * k * k * omega * (eta[p] * eta[p])
    c = -omega / 8.0
    for k in range(n_k):
        energies[k] = c * energies[k]
    energies[0] = 0.0
    for k in range(n_k):
        e = energies[k]
        if not (e >= 0.0 or math.isnan(e)):  # np.maximum(e, 0.0)
            energies[k] = 0.0


@njit(**_JIT)
def _first_argmax(x, lo):
    best = lo
    for i in range(lo, len(x)):
        if math.isnan(x[i]):
            return i
        if x[i] > x[best]:
            best = i
    return best


@njit(**_JIT)
def _family_records(a, dD, eta, pole_k, omega, freqs, energies, out):
    """In place: energies as :func:`_harmonic_energies`; out (4,) = fundamental_share,
    resonance_harmonic k, resonance_mode j (1-based), resonance_detuning kΩ/ω_j − 1 (0, 0,
    NaN for H = 1 or no motion); freqs (n_t,) Hz."""
    _harmonic_energies(a, dD, eta, pole_k, omega, energies)
    H = len(energies) - 1
    total = 0.0
    for k in range(1, H + 1):
        total += energies[k]
    out[0] = energies[1] / total if total > 0 else 1.0
    out[1] = 0.0
    out[2] = 0.0
    out[3] = np.nan
    if H >= 2 and total > 0:
        k = _first_argmax(energies, 2)
        f = k * omega / (2 * np.pi)
        j = 0
        best = abs(freqs[0] - f)
        if not math.isnan(best):
            for i in range(1, len(freqs)):
                d = abs(freqs[i] - f)
                if math.isnan(d):
                    j = i
                    break
                if d < best:
                    best, j = d, i
        out[1] = k
        out[2] = j + 1
        out[3] = f / freqs[j] - 1.0


def harmonic_energies(a: np.ndarray, dD: np.ndarray, eta: np.ndarray, pole_k: np.ndarray,
                      omega: float) -> np.ndarray:
    """Period-mean kinetic energy (J) of each harmonic k = 0..H, shape (H+1,), from the
    cosine coefficients ``a`` (H+1, n_c), the Ω-derivative of the condensed stiffness ``dD``
    (H+1, n_c, n_c), the pole unknowns ``eta`` (n_p,) of harmonics ``pole_k`` (n_p,), at Ω
    (rad/s)."""
    energies = np.empty(a.shape[0])
    _harmonic_energies(np.ascontiguousarray(a), np.ascontiguousarray(dD), np.ascontiguousarray(eta),
                       pole_k, float(omega), energies)
    return energies


def family_records(a: np.ndarray, dD: np.ndarray, eta: np.ndarray, pole_k: np.ndarray, omega: float,
                   freqs: np.ndarray) -> dict:
    """The family records of one point (see :meth:`FamilyMixin.family_records`): arguments
    as :func:`harmonic_energies`, ``freqs`` (n_t,) Hz the tracked open-contact modes."""
    out = np.empty(4)
    _family_records(np.ascontiguousarray(a), np.ascontiguousarray(dD), np.ascontiguousarray(eta), pole_k,
                    float(omega), np.ascontiguousarray(freqs, dtype=float), np.empty(a.shape[0]), out)
    return {"fundamental_share": float(out[0]), "resonance_harmonic": float(out[1]),
            "resonance_mode": float(out[2]), "resonance_detuning": float(out[3])}

