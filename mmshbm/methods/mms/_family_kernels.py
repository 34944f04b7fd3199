"""Compiled per-point family records of an MMS-HBM backbone: the kinetic energy of each
harmonic, the fundamental's share and the strongest higher harmonic's detuning from the
nearest tracked mode (:meth:`~mmshbm.methods.mms.family.FamilyMixin.family_records`).

The kernels reproduce the NumPy expressions they replace operation for operation, so
their results are the same floating-point numbers: ``einsum("ki,kij,kj->k")`` sums
(a_ki·D_kij)·a_kj over i then j into one accumulator, ``ndarray.sum`` is NumPy's
pairwise summation (8 accumulators on blocks of up to 128 numbers), ``argmax``/``argmin``
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
    """NumPy's sum of a block of n <= 128 numbers x[lo:lo+n] (8 accumulators)."""
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
def _pairwise_sum(x, lo, n):
    """NumPy's pairwise sum of x[lo:lo+n] (the order of ``x[lo:lo+n].sum()``): blocks of
    up to 128 numbers, halved (to a multiple of 8) above that. Without recursion (Numba's
    cache does not keep recursive kernels): the halving tree is walked with a stack of
    (lo, n, partial) frames."""
    if n <= 128:
        return _block_sum(x, lo, n)
    # frames: lo, n, state (0: left half to do, 1: right half to do, 2: both done), left value
    f_lo = np.empty(64, dtype=np.int64)
    f_n = np.empty(64, dtype=np.int64)
    f_state = np.zeros(64, dtype=np.int64)
    f_left = np.zeros(64)
    top = 0
    f_lo[0], f_n[0], f_state[0] = lo, n, 0
    result = 0.0
    while top >= 0:
        m = f_n[top]
        half = m // 2
        half -= half % 8
        if f_state[top] == 0:
            f_state[top] = 1
            c_lo, c_n = f_lo[top], half
        elif f_state[top] == 1:
            f_state[top] = 2
            c_lo, c_n = f_lo[top] + half, m - half
        else:
            value = f_left[top] + result  # left + right
            top -= 1
            result = value
            if top >= 0:
                if f_state[top] == 1:
                    f_left[top] = value
                # state 2: result already holds the right half's value
            continue
        if c_n <= 128:
            v = _block_sum(x, c_lo, c_n)
            if f_state[top] == 1:
                f_left[top] = v
            else:
                result = v
        else:
            top += 1
            f_lo[top], f_n[top], f_state[top] = c_lo, c_n, 0
    return result


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
    total = _pairwise_sum(energies, 1, H)
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
    as :func:`harmonic_energies`, ``freqs`` (n_t,) Hz the tracked open-contact modes."""
    out = np.empty(4)
    _family_records(np.ascontiguousarray(a), np.ascontiguousarray(dD), np.ascontiguousarray(eta), pole_k,
                    float(omega), np.ascontiguousarray(freqs, dtype=float), np.empty(a.shape[0]), out, 2.0)
    return {"fundamental_share": float(out[0]), "resonance_harmonic": float(out[1]),
            "resonance_mode": float(out[2]), "resonance_detuning": float(out[3])}
