"""The per-point measures every method reports, each defined once: the amplitude (the peak
of a periodic signal), the harmonic content of a DOF and the period-averaged energy.

Amplitude convention: the branch amplitude is measured at ``model.amplitude_dof``; when the
model has a single (one-sided) contact and the amplitude DOF is its DOF, it is the largest
excursion *away from the stop* (``max −side·q``); for any other amplitude DOF it is the
largest |q| over the period (:func:`amplitude_sign` gives the sign).
The peak is taken

* from samples (:func:`refined_max`, :func:`amplitude_peak`): the largest sample, refined
  by a parabola through it and its neighbours (baselines with sampled signals);
* from a series, exactly: the largest sample of the series on a grid refined by Newton on
  its derivative (:func:`_series_peak`, value only, inside the MMS-HBM monitor kernel;
  :func:`_cosine_peak`, value, maximiser and sign, for the amplitude's gradient: samples by
  one FFT of the coefficients, Newton from every sampled maximum within the sampling error
  of the largest).

Harmonic content: |Q_k| = √(c_k² + s_k²) for k = 0..H (|Q_0| the mean's magnitude) of
NLvib-ordered coefficients (:func:`harmonic_content`); methods with sampled signals take
the coefficients of the samples first (:func:`sample_coefficients`).

Energy: the period average of kinetic + potential energy by Parseval, from the
coefficients of every DOF (:func:`mean_energy`) or from the massless DOFs and the
condensed dynamic stiffness alone (:func:`condensed_energy`; the same number). The
MMS-HBM monitor kernel sums the terms of :func:`condensed_energy` in its own loop, with the
pole unknowns' share. Shooting and the exact reference report the energy of a state
instead (conserved by their motion, so it equals the period average): each evaluates
½ vᵀMv + ½ qᵀKq at its state, the exact reference in extended precision.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .. import _validate as check
from .._kernel_cache import JIT_OPTIONS
from .._kernel_cache import install as _install_cache_policy
from ..contact.trig import _TWO_PI, _trig_eval
from ..model.model import Model

__all__ = ["amplitude_sign", "refined_max", "amplitude_peak", "harmonic_content", "sample_coefficients",
           "check_dof", "mean_energy", "condensed_energy"]

_install_cache_policy()


# ---------------------------------------------------------------------------- peaks
def amplitude_sign(model: Model) -> int:
    """How the amplitude is measured at ``model.amplitude_dof``: ``side`` (±1) when the
    model has a single contact and the amplitude DOF is its DOF (amplitude = max of
    ``−side·q``, the excursion away from the stop), 0 otherwise (amplitude = max |q|)."""
    amp = model.amplitude_dof
    if model.n_contacts == 1 and model.contacts[0].dof == amp:
        return int(model.contacts[0].side)
    return 0


def refined_argmax(y: np.ndarray) -> tuple[float, float]:
    """(largest value, its position in samples) of a periodic sampled signal ``y`` (shape
    (n,)), refined by a parabola through the sampled peak and its neighbours; the position
    is fractional, in [−0.5, n − 0.5]."""
    j = int(np.argmax(y))
    ym, y0, yp = y[j - 1], y[j], y[(j + 1) % len(y)]
    denom = ym - 2 * y0 + yp
    if denom < 0:
        return float(y0 - 0.125 * (yp - ym) ** 2 / denom), j + 0.5 * (ym - yp) / denom
    return float(y0), float(j)


def refined_max(y: np.ndarray) -> float:
    """Largest value of a periodic sampled signal, refined by a parabola through the peak."""
    return refined_argmax(y)[0]


def amplitude_peak(q: np.ndarray, sign: int) -> float:
    """The amplitude of the periodic samples ``q`` (shape (n,)) by the module's convention:
    the largest ``−sign·q`` (sign ±1, a single stop's side) or |q| (sign 0), refined by a
    parabola through the sampled peak."""
    y = np.abs(q) if sign == 0 else -sign * q
    return refined_max(y)


@njit(**JIT_OPTIONS)
def _series_peak(c, s, cos_table, sin_table, y):
    """Largest value of g = c_0 + Σ_k (c_k cos kτ + s_k sin kτ) over the period: the largest of
    the samples ``y`` (= g on the table's grid, filled here), refined by safeguarded Newton
    on g′ = 0 between its neighbours (to round-off)."""
    N = y.shape[0]
    H = c.shape[0] - 1
    j = 0
    for i in range(N):
        v = c[0]
        for k in range(1, H + 1):
            v += c[k] * cos_table[k, i] + s[k] * sin_table[k, i]
        y[i] = v
        if v > y[j]:
            j = i
    best = y[j]
    h = _TWO_PI / N
    lo = (j - 1) * h
    hi = (j + 1) * h
    tau = j * h
    for _ in range(12):
        g, g1, g2 = _trig_eval(c, s, tau)
        if g > best:
            best = g
        if g2 >= 0.0:
            break
        step = g1 / g2
        tau_new = tau - step
        if tau_new <= lo or tau_new >= hi:
            break
        tau = tau_new
        if abs(step) <= 1e-15:
            g, g1, g2 = _trig_eval(c, s, tau)
            if g > best:
                best = g
            break
    return best


def _cosine_samples(row: np.ndarray, n: int) -> np.ndarray:
    """q(τ_i) = Σ_k row_k cos kτ_i on the grid τ_i = 2πi/n, i = 0..n−1 (shape (n,)), by one
    real FFT of the coefficients (H + 1 = len(row) <= n/2): O(n log n) instead of the
    O(nH) of a table."""
    spectrum = np.zeros(n // 2 + 1)
    spectrum[0] = row[0]
    spectrum[1:row.shape[0]] = 0.5 * row[1:]
    return np.fft.hfft(spectrum, n)


def _cosine_peak(row: np.ndarray, sign: float, n_fine: int, cos_k: np.ndarray) -> tuple[float, float]:
    """Largest value of sign·q (|q| when sign is 0) for q(τ) = Σ_k row_k cos kτ (row shape
    (H+1,), units of q) over the period: ``n_fine`` equispaced samples by one FFT
    (:func:`_cosine_samples`), then Newton on q′(τ) = 0 from each sampled local maximum
    within the sampling error of the largest sample (:func:`_cosine_refine_best`; compiled).
    Returns (the value, the sign s with value = s·q(τ*)); ``cos_k`` (H+1,) <- cos kτ* (the
    gradient of q(τ*) in row, envelope theorem)."""
    row = np.ascontiguousarray(row, dtype=float)
    if not 2 * row.shape[0] <= n_fine:
        raise ValueError(f"n_fine must be at least 2(H + 1) = {2 * row.shape[0]}, got {n_fine}")
    y = _cosine_samples(row, n_fine)
    return _cosine_refine_best(row, float(sign), y, cos_k)


#: the most sampled local maxima :func:`_cosine_refine_best` refines (the largest ones)
_PEAK_CANDIDATES = 8


@njit(**JIT_OPTIONS)
def _cosine_refine_best(row, sign, q_samples, cos_k):
    """The peak of :func:`_cosine_peak` from the samples q(2πi/n) (shape (n,)): every sampled
    local maximum of y = sign·q (|q| for sign 0) within the sampling error of the largest,
    (h²/8) Σ k²|row_k| (h = 2π/n, the drop of y from its maximum to the nearest sample)
    plus the samples' round-off, is refined by :func:`_cosine_refine` (the
    ``_PEAK_CANDIDATES`` largest of them); the largest refined value wins. Returns
    (value, s); ``cos_k`` <- cos kτ* of the winner."""
    n = q_samples.shape[0]
    H1 = row.shape[0]
    y = np.empty(n)
    j = 0
    for i in range(n):
        y[i] = sign * q_samples[i] if sign != 0.0 else abs(q_samples[i])
        if y[i] > y[j]:
            j = i
    h = _TWO_PI / n
    curvature = 0.0
    size = 0.0
    for k in range(H1):
        curvature += k * k * abs(row[k])
        size += abs(row[k])
    margin = 0.125 * h * h * curvature + 8.0 * (math.log2(n) + 2.0) * 2.220446049250313e-16 * size
    cand = np.empty(_PEAK_CANDIDATES, dtype=np.int64)
    n_cand = 0
    for i in range(n):
        if y[i] < y[j] - margin or y[i] < y[i - 1] or y[i] < y[(i + 1) % n]:
            continue
        if n_cand < _PEAK_CANDIDATES:
            cand[n_cand] = i
            n_cand += 1
        else:  # replace the smallest candidate kept
            low = 0
            for c in range(1, n_cand):
                if y[cand[c]] < y[cand[low]]:
                    low = c
            if y[i] > y[cand[low]]:
                cand[low] = i
    if n_cand == 0:
        cand[0] = j
        n_cand = 1
    best = -np.inf
    best_s = 1.0
    trial = np.empty(H1)
    for c in range(n_cand):
        value, s = _cosine_refine(row, sign, cand[c] * h, trial)
        if value > best:
            best = value
            best_s = s
            cos_k[:] = trial
    return best, best_s


@njit(**JIT_OPTIONS)
def _cosine_refine(row, sign, tau, cos_k):
    """Newton on q′(τ) = 0 from τ for q(τ) = Σ_k row_k cos kτ (at most 8 steps, to 1e-14 in
    τ; q′, q″ by the angle-addition recurrence). Returns (s·q(τ*), s), s = sign (that of
    q(τ*) when sign is 0); ``cos_k`` <- cos kτ* (each by ``math.cos``)."""
    H1 = row.shape[0]
    for _ in range(8):
        c1 = math.cos(tau)
        s1 = math.sin(tau)
        ck = 1.0
        sk = 0.0
        d1 = 0.0
        d2 = 0.0
        for k in range(1, H1):
            ck, sk = ck * c1 - sk * s1, sk * c1 + ck * s1
            d1 -= k * row[k] * sk
            d2 -= k * k * row[k] * ck
        if d2 == 0.0:
            break
        step = d1 / d2
        tau -= step
        if abs(step) < 1e-14:
            break
    value = 0.0
    for k in range(H1):
        cos_k[k] = math.cos(k * tau)
        value += row[k] * cos_k[k]
    s = sign if sign != 0.0 else math.copysign(1.0, value)
    return s * value, s


# ---------------------------------------------------------------------------- harmonic content
def check_dof(dof, n_dof: int, default: int) -> int:
    """``dof`` (``default`` when None) as an int in [0, n_dof).

    Raises
    ------
    ValueError, TypeError
        Naming ``dof``: not an integer, or out of range.
    """
    dof = default if dof is None else check.integer("dof", dof)
    if not 0 <= dof < n_dof:
        raise ValueError(f"dof must be in [0, {n_dof - 1}], got {dof}")
    return dof


def harmonic_content(Q: np.ndarray) -> np.ndarray:
    """|Q_k| = √(c_k² + s_k²), k = 0..H, of NLvib-ordered coefficients ``Q`` (2H+1,)
    [Q_0, Q_c1, Q_s1, ...] (units of Q); shape (H+1,), entry 0 the mean's magnitude."""
    Q = np.asarray(Q, dtype=float)
    if Q.ndim != 1 or Q.shape[0] % 2 != 1:
        raise ValueError(f"Q must be 1-D with 2H+1 entries, got shape {Q.shape}")
    return np.concatenate([[abs(Q[0])], np.hypot(Q[1::2], Q[2::2])])


def sample_coefficients(q: np.ndarray, harmonics: int) -> np.ndarray:
    """NLvib-ordered coefficients (..., 2H+1), H = ``harmonics``, of the equispaced samples
    ``q`` (..., N) over one period (DFT along the last axis; H <= N/2 − 1)."""
    q = np.asarray(q, dtype=float)
    N = q.shape[-1]
    if not 0 <= harmonics <= N // 2 - 1:
        raise ValueError(f"harmonics must be in [0, N/2 - 1 = {N // 2 - 1}], got {harmonics}")
    c = np.fft.rfft(q, axis=-1) / N
    Q = np.zeros(q.shape[:-1] + (2 * harmonics + 1,))
    Q[..., 0] = c[..., 0].real
    Q[..., 1::2] = 2 * c[..., 1:harmonics + 1].real
    Q[..., 2::2] = -2 * c[..., 1:harmonics + 1].imag
    return Q


# ---------------------------------------------------------------------------- energy
def mean_energy(model: Model, Q: np.ndarray, omega: float) -> float:
    """Period average of kinetic + potential energy (J) of the motion with NLvib-ordered
    coefficients Q (n_dof, 2H+1) at Ω (Parseval). A harmonic-balance solution conserves
    energy only up to truncation; its period average is the natural single number."""
    H = (Q.shape[1] - 1) // 2
    KQ = np.einsum("ij,ij->j", Q, model.K @ Q)  # qᵀKq per column
    MQ = np.einsum("ij,ij->j", Q, model.M @ Q)
    k = np.repeat(np.arange(1, H + 1), 2)
    V = 0.5 * KQ[0] + 0.25 * KQ[1:].sum()
    T = 0.25 * omega**2 * (k**2 * MQ[1:]).sum()
    return float(V + T)


def condensed_energy(D: np.ndarray, dD: np.ndarray, a: np.ndarray, omega: float) -> float:
    """Period average of kinetic + potential energy (J) from the massless DOFs alone.

    With q_l,k = −Z_k a_k the mass-carrying DOFs satisfy their equations exactly, so
    q_kᵀ(K − (kΩ)²M)q_k = a_kᵀ D_k a_k and q_kᵀ M q_k = a_kᵀ Z_kᵀ M Z_k a_k
    = −a_kᵀ ∂D_k/∂Ω a_k / (2k²Ω). Parseval on the cosine motion then gives
    E = ½ a_0ᵀD_0 a_0 + ¼ Σ_{k>=1} (a_kᵀ D_k a_k − Ω a_kᵀ ∂D_k/∂Ω a_k), the same number as
    :func:`mean_energy` on the recovered coefficients (up to round-off) without
    recovering any DOF with mass. D, dD: (H+1, n_c, n_c); a: (H+1, n_c). The MMS-HBM
    monitor kernel (:func:`~mmshbm.methods.mms.contact_kernels._mmshbm_monitor_multi`) sums the
    same terms inside its loop, with the pole unknowns' share.
    """
    quad = np.einsum("ki,kij,kj->k", a, D, a)
    quad_m = np.einsum("ki,kij,kj->k", a[1:], dD[1:], a[1:])
    return float(0.5 * quad[0] + 0.25 * (quad[1:].sum() - omega * quad_m.sum()))
