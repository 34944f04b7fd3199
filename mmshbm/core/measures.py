"""The per-point measures every method reports, each defined once: the amplitude (the peak
of a periodic signal), the harmonic content of a DOF and the period-averaged energy.

Amplitude convention: the branch amplitude is measured at ``model.amplitude_dof``; when the
model has a single (one-sided) contact and the amplitude DOF is its DOF, it is the largest
excursion *away from the stop* (``max −side·q``); for any other amplitude DOF it is the
largest |q| over the period (:func:`amplitude_sign` gives the sign).
The peak is taken

* from samples (:func:`refined_max`, :func:`amplitude_peak`): the largest sample, refined
  by a parabola through it and its neighbours (baselines with sampled signals);
* from a series, exactly: every sampled local maximum of the series on a grid that could
  be the global one (within the sampling error of the largest sample) refined by Newton on
  its derivative (:func:`_series_peak`, value only, inside the MMS-HBM monitor kernel;
  :func:`_cosine_peak`, value, maximiser and sign, for the amplitude's gradient: samples by
  one FFT of the coefficients on :func:`peak_grid` (16 samples per period of the highest
  harmonic), Newton from every sampled local maximum within the sampling error of the
  largest, however many: a contact's dwell has many nearly equal maxima).

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


#: the fewest samples of the grids the series peaks are searched on
PEAK_GRID_MIN = 64
#: samples per period of the highest harmonic on those grids
PEAK_GRID_DENSITY = 16


def peak_grid(harmonics: int) -> int:
    """Samples of the grid a series with harmonics 0..H is searched on for its peak
    (:func:`_cosine_peak`): the power of two >= ``PEAK_GRID_DENSITY`` (H + 1), at least
    ``PEAK_GRID_MIN``. Every sampled local maximum that could be the global one is refined,
    so the grid need only separate the maxima of the highest harmonic."""
    n = PEAK_GRID_DENSITY * (int(harmonics) + 1)
    return max(PEAK_GRID_MIN, 1 << (n - 1).bit_length())


@njit(**JIT_OPTIONS)
def _sampling_margin(c, s, h):
    """How far below a maximum of g = c_0 + Σ_k (c_k cos kτ + s_k sin kτ) its nearest sample
    on a grid of spacing ``h`` (rad) can lie: (h/2)²/2 · max|g″| <= (h²/8) Σ k²(|c_k| + |s_k|),
    plus the round-off of the samples (relative 8(log₂ n + 2) ε of Σ(|c_k| + |s_k|), n the
    grid's samples)."""
    curvature = 0.0
    size = 0.0
    for k in range(c.shape[0]):
        curvature += k * k * (abs(c[k]) + abs(s[k]))
        size += abs(c[k]) + abs(s[k])
    n = _TWO_PI / h
    return 0.125 * h * h * curvature + 8.0 * (math.log2(n) + 2.0) * 2.220446049250313e-16 * size


@njit(**JIT_OPTIONS)
def _climb(c, s, tau, h):
    """The largest value of g = c_0 + Σ_k (c_k cos kτ + s_k sin kτ) that Newton on g′ = 0
    from ``tau`` meets inside [tau − h, tau + h] (at most 12 steps, to 1e-14 in τ; it stops
    where g″ >= 0 or a step leaves the interval): (value, its τ; the last iterate whose
    value ties the largest to round-off, so that τ is Newton's converged one). The start's
    value is among those compared, so the result is never below g(tau)."""
    lo = tau - h
    hi = tau + h
    size = 0.0
    for k in range(c.shape[0]):
        size += abs(c[k]) + abs(s[k])
    noise = 4.0 * c.shape[0] * 2.220446049250313e-16 * size  # the round-off of one evaluation
    best = -np.inf
    best_tau = tau
    last = np.inf
    for _ in range(12):
        g, g1, g2 = _trig_eval(c, s, tau)
        if g >= best - noise:  # Newton's later iterate, where the values tie to round-off
            best = max(best, g)
            best_tau = tau
        if abs(last) <= 1e-14 or g2 >= 0.0:
            break
        step = g1 / g2
        tau_new = tau - step
        if tau_new < lo or tau_new > hi:
            break
        tau = tau_new
        last = step
    return best, best_tau


@njit(**JIT_OPTIONS)
def _best_of_samples(c, s, y, h):
    """The peak of g (coefficients c, s (H+1,)) from its samples ``y`` = g(ih) (shape (n,),
    h = 2π/n): every sampled local maximum within :func:`_sampling_margin` of the largest
    sample (any of them can be the nearest sample of the global maximum) refined by
    :func:`_climb`; (the largest value, its τ)."""
    n = y.shape[0]
    j = 0
    for i in range(n):
        if y[i] > y[j]:
            j = i
    floor = y[j] - _sampling_margin(c, s, h)
    best = -np.inf
    best_tau = j * h
    for i in range(n):
        if y[i] < floor or y[i] < y[i - 1] or y[i] < y[(i + 1) % n]:
            continue
        value, tau = _climb(c, s, i * h, h)
        if value > best:
            best = value
            best_tau = tau
    return best, best_tau


@njit(**JIT_OPTIONS)
def _series_peak(c, s, cos_table, sin_table, y):
    """Largest value of g = c_0 + Σ_k (c_k cos kτ + s_k sin kτ) over the period: the samples
    ``y`` (= g on the table's grid, filled here), every sampled local maximum that could be
    the global one refined by Newton on g′ = 0 (:func:`_best_of_samples`; to round-off)."""
    N = y.shape[0]
    H = c.shape[0] - 1
    for i in range(N):
        y[i] = c[0]
    for k in range(1, H + 1):  # row by row: the tables are C-ordered (k, i)
        ck = c[k]
        sk = s[k]
        for i in range(N):
            y[i] += ck * cos_table[k, i] + sk * sin_table[k, i]
    return _best_of_samples(c, s, y, _TWO_PI / N)[0]


def _cosine_samples(row: np.ndarray, n: int) -> np.ndarray:
    """q(τ_i) = Σ_k row_k cos kτ_i on the grid τ_i = 2πi/n, i = 0..n−1 (shape (n,)), by one
    real FFT of the coefficients (H + 1 = len(row) <= n/2): O(n log n) instead of the
    O(nH) of a table."""
    spectrum = np.zeros(n // 2 + 1)
    spectrum[0] = row[0]
    spectrum[1:row.shape[0]] = 0.5 * row[1:]
    return np.fft.hfft(spectrum, n)


def _cosine_peak(row: np.ndarray, sign: float, cos_k: np.ndarray,
                 n_fine: int | None = None) -> tuple[float, float]:
    """Largest value of sign·q (|q| when sign is 0) for q(τ) = Σ_k row_k cos kτ (row shape
    (H+1,), units of q) over the period: equispaced samples by one FFT
    (:func:`_cosine_samples`; ``n_fine`` of them, default :func:`peak_grid` (H)), then
    Newton on q′(τ) = 0 from every sampled local maximum within the sampling error of the
    largest sample (:func:`_cosine_refine_best`; compiled). Returns (the value, the sign s
    with value = s·q(τ*)); ``cos_k`` (H+1,) <- cos kτ* (the gradient of q(τ*) in row,
    envelope theorem)."""
    row = np.ascontiguousarray(row, dtype=float)
    n_fine = peak_grid(row.shape[0] - 1) if n_fine is None else int(n_fine)
    if not 2 * row.shape[0] <= n_fine:
        raise ValueError(f"n_fine must be at least 2(H + 1) = {2 * row.shape[0]}, got {n_fine}")
    y = _cosine_samples(row, n_fine)
    return _cosine_refine_best(row, float(sign), y, cos_k)


@njit(**JIT_OPTIONS)
def _cosine_refine_best(row, sign, q_samples, cos_k):
    """The peak of :func:`_cosine_peak` from the samples q(2πi/n) (shape (n,)): the peak of
    sign·q (sign ±1) by :func:`_best_of_samples`; for sign 0 (|q|) the larger of the peaks
    of q and −q. Returns (value, s), the value recomputed as s·Σ_k row_k cos kτ* from
    ``cos_k`` <- cos kτ* (each by ``math.cos``)."""
    n = q_samples.shape[0]
    H1 = row.shape[0]
    h = _TWO_PI / n
    zeros = np.zeros(H1)
    best = -np.inf
    best_tau = 0.0
    best_s = 1.0
    for s in (1.0, -1.0):
        if sign != 0.0 and s != sign:
            continue
        value, tau = _best_of_samples(s * row, zeros, s * q_samples, h)
        if value > best:
            best = value
            best_tau = tau
            best_s = s
    value = 0.0
    for k in range(H1):
        cos_k[k] = math.cos(k * best_tau)
        value += row[k] * cos_k[k]
    return best_s * value, best_s


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
