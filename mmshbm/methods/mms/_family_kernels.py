"""Compiled per-point family records of an MMS-HBM backbone: the kinetic energy of each
harmonic, the fundamental's share and the strongest higher harmonic's detuning from the
nearest tracked mode (:meth:`~mmshbm.methods.mms.family.FamilyMixin.family_records`).

The kernels reproduce the NumPy expressions they replace operation for operation, so
their results are the same floating-point numbers: ``einsum("ki,kij,kj->k")`` sums
(a_ki·D_kij)·a_kj over i then j into one accumulator, ``ndarray.sum`` is NumPy's
pairwise summation (8 accumulators on a block of up to 128 numbers: H <= 128 here, the
NumPy expressions themselves above), ``argmax``/``argmin``
take the first extremum (the first NaN where there is one). They are compiled without
fast-math flags for that reason (no contraction into fused multiply-adds, no
reassociation).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["harmonic_energies", "family_records"]

_JIT = dict(cache=True, nogil=True)  # exact IEEE arithmetic: no fast-math flags


@njit(**_JIT)
def _block_sum(x, lo, n):
    """NumPy's sum of n <= 128 numbers x[lo:lo+n] (``x[lo:lo+n].sum()``: 8 accumulators;
    NumPy halves longer arrays into such blocks)."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += x[lo + i]
        return res
    r0, r1, r2, r3 = x[lo], x[lo + 1], x[lo + 2], x[lo + 3]
    r4, r5, r6, r7 = x[lo + 4], x[lo + 5], x[lo + 6], x[lo + 7]
    i = 8
    stop = n - n % 8
    while i < stop:
        r0 += x[lo + i]
        r1 += x[lo + i + 1]
        r2 += x[lo + i + 2]
        r3 += x[lo + i + 3]
        r4 += x[lo + i + 4]
        r5 += x[lo + i + 5]
        r6 += x[lo + i + 6]
        r7 += x[lo + i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += x[lo + i]
        i += 1
    return res


@njit(**_JIT)
def _harmonic_energies(a, dD, eta, pole_k, omega, energies, two):
    """In place: energies (H+1,) J, T_k = max(−(Ω/8)(a_kᵀ ∂D_k/∂Ω a_k − 2k²Ω Σ_p η_p²), 0),
    T_0 = 0; a (H+1, n_c), dD (H+1, n_c, n_c), eta (n_p,), pole_k (n_p,) int. ``two`` is
    2.0, passed at run time: η² is C's pow(η, 2.0) as for a NumPy scalar (η·η differs from
    it in the last bit now and then, and a literal exponent would be folded into η·η)."""
    n_k, n_c = a.shape
    for k in range(n_k):
        s = 0.0
        for i in range(n_c):
            for j in range(n_c):
                s += a[k, i] * dD[k, i, j] * a[k, j]
        energies[k] = s
    for p in range(len(pole_k)):
        k = pole_k[p]
        energies[k] -= 2.0 * k * k * omega * math.pow(eta[p], two)
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
def _family_records(a, dD, eta, pole_k, omega, freqs, energies, out, two):
    """In place: energies as :func:`_harmonic_energies`; out (4,) = fundamental_share,
    resonance_harmonic k, resonance_mode j (1-based), resonance_detuning kΩ/ω_j − 1 (0, 0,
    NaN for H = 1 or no motion); freqs (n_t,) Hz."""
    _harmonic_energies(a, dD, eta, pole_k, omega, energies, two)
    H = len(energies) - 1
    total = _block_sum(energies, 1, H)  # H <= 128: one block of NumPy's pairwise sum
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
                       pole_k, float(omega), energies, 2.0)
    return energies


def family_records(a: np.ndarray, dD: np.ndarray, eta: np.ndarray, pole_k: np.ndarray, omega: float,
                   freqs: np.ndarray) -> dict:
    """The family records of one point (see :meth:`FamilyMixin.family_records`): arguments
    as :func:`harmonic_energies`, ``freqs`` (n_t,) Hz the tracked open-contact modes.
    Above H = 128 (NumPy sums in several blocks) the NumPy expressions themselves."""
    if a.shape[0] - 1 > _MAX_H:
        return _family_records_numpy(a, dD, eta, pole_k, omega, freqs)
    out = np.empty(4)
    _family_records(np.ascontiguousarray(a), np.ascontiguousarray(dD), np.ascontiguousarray(eta), pole_k,
                    float(omega), np.ascontiguousarray(freqs, dtype=float), np.empty(a.shape[0]), out, 2.0)
    return {"fundamental_share": float(out[0]), "resonance_harmonic": float(out[1]),
            "resonance_mode": float(out[2]), "resonance_detuning": float(out[3])}


#: the largest H of the compiled records (NumPy's sum of H numbers is one block up to 128)
_MAX_H = 128


def _family_records_numpy(a, dD, eta, pole_k, omega, freqs) -> dict:
    """:func:`family_records` by the NumPy expressions the kernel reproduces."""
    energies = harmonic_energies(a, dD, eta, pole_k, omega)
    total = float(energies[1:].sum())
    out = {"fundamental_share": float(energies[1] / total) if total > 0 else 1.0,
           "resonance_harmonic": 0.0, "resonance_mode": 0.0, "resonance_detuning": float("nan")}
    H = len(energies) - 1
    if H >= 2 and total > 0:
        k = int(np.argmax(energies[2:])) + 2
        f = k * float(omega) / (2 * np.pi)
        j = int(np.argmin(np.abs(freqs - f)))
        out.update(resonance_harmonic=float(k), resonance_mode=float(j + 1),
                   resonance_detuning=float(f / freqs[j] - 1.0))
    return out
