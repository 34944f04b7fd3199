"""Real Fourier transforms between harmonic coefficients and time samples.

Conventions (NLvib's): a signal with harmonics 0..H in normalised time τ = Ω t is

    x(τ) = c_0 + Σ_{k=1..H} (c_k cos kτ + s_k sin kτ),

stored per signal as ``[c_0, c_1, s_1, c_2, s_2, ..., c_H, s_H]`` (length 2H+1). A batch
of signals is an array of shape (n_signals, 2H+1); NLvib's stacked vector
``[Q0; Qc1; Qs1; ...]`` in n-DOF blocks is ``coeffs.T.ravel()``. Samples are taken at
τ_j = 2πj/N, j = 0..N-1, N >= 2H+1.

:class:`HarmonicTransform` does the work with planned FFTW real transforms (pyfftw),
one plan per (n_signals, N) batched along the last axis, executed on buffers it owns;
without pyfftw it falls back to ``numpy.fft`` with the same results.
"""

from __future__ import annotations

import importlib.util
import threading
from functools import lru_cache

import numpy as np

from .. import _validate as check

__all__ = ["HarmonicTransform", "transform", "default_n_samples", "check_harmonics"]

#: pyfftw is installed (it is imported on the first FFTW plan: importing it costs ~0.1 s,
#: and ~0.4 s more when dask is installed, since ``pyfftw.interfaces`` imports dask.array)
HAVE_FFTW = importlib.util.find_spec("pyfftw") is not None


def _pyfftw():
    import pyfftw

    return pyfftw


def check_harmonics(harmonics, n_samples=None) -> tuple[int, int]:
    """Validate the harmonic order H >= 1 and the sample count N >= 2H+1.

    Returns (H, N), N defaulting to :func:`default_n_samples`.
    """
    H = check.integer("harmonics", harmonics, minimum=1)
    if n_samples is None:
        return H, default_n_samples(H)
    N = check.integer("n_samples", n_samples)
    if N < 2 * H + 1:
        raise ValueError(f"n_samples must be >= 2*harmonics+1 = {2 * H + 1}, got {N}")
    return H, N


def default_n_samples(harmonics: int) -> int:
    """Samples per period for the alternating frequency-time scheme: the power of two
    >= 16 H (and >= 64).

    The contact force has kinks, so its projection on harmonics 0..H suffers aliasing
    that decays only slowly with N; oversampling by 8 over Nyquist keeps that error
    well below the truncation error in H (see tests/test_mmshbm_oscillator.py).
    """
    return int(max(64, 2 ** int(np.ceil(np.log2(16 * harmonics)))))


class HarmonicTransform:
    """Batched transforms for ``n_signals`` signals, H harmonics, N samples.

    Parameters
    ----------
    harmonics : int
        Highest harmonic H >= 1.
    n_samples : int
        Samples per period N >= 2H+1.
    n_signals : int
        Number of signals transformed together (batched along the last axis).
    use_fftw : bool, optional
        Force pyfftw (True) or numpy.fft (False); default: pyfftw when importable.
    """

    def __init__(self, harmonics: int, n_samples: int, n_signals: int = 1, use_fftw: bool | None = None):
        self.H, self.N = check_harmonics(harmonics, n_samples)
        self.n_signals = check.integer("n_signals", n_signals, minimum=1)
        self.use_fftw = HAVE_FFTW if use_fftw is None else bool(use_fftw and HAVE_FFTW)
        n, N = self.n_signals, self.N
        self.tau = 2 * np.pi * np.arange(N) / N
        if self.use_fftw:
            pyfftw = _pyfftw()
            self._time = pyfftw.empty_aligned((n, N), dtype="float64")
            self._freq = pyfftw.empty_aligned((n, N // 2 + 1), dtype="complex128")
            # FFTW_ESTIMATE, not FFTW_MEASURE: measured planning picks algorithms by
            # timing, so round-off (and hence a branch near a resonance) would differ
            # from run to run; estimated plans are deterministic, and at these sizes
            # the difference in speed is within noise.
            self._forward = pyfftw.FFTW(self._time, self._freq, axes=(-1,), direction="FFTW_FORWARD",
                                        flags=("FFTW_ESTIMATE",), threads=1)
            self._backward = pyfftw.FFTW(self._freq, self._time, axes=(-1,), direction="FFTW_BACKWARD",
                                         flags=("FFTW_ESTIMATE", "FFTW_DESTROY_INPUT"), threads=1)
        else:
            self._time = np.empty((n, N))
            self._freq = np.empty((n, N // 2 + 1), dtype=complex)

    # ---------------------------------------------------------------- full (cos + sin)
    def to_time(self, coeffs: np.ndarray) -> np.ndarray:
        """Samples (n_signals, N) of signals with NLvib-ordered ``coeffs`` (n_signals, 2H+1)."""
        coeffs = np.asarray(coeffs, dtype=float).reshape(self.n_signals, 2 * self.H + 1)
        F = self._freq
        F[:] = 0.0
        F[:, 0] = coeffs[:, 0]
        F[:, 1 : self.H + 1] = 0.5 * (coeffs[:, 1::2] - 1j * coeffs[:, 2::2])
        return self._backward_execute()

    def to_harmonics(self, samples: np.ndarray) -> np.ndarray:
        """NLvib-ordered coefficients (n_signals, 2H+1) of the samples (n_signals, N),
        projected on harmonics 0..H (discrete Fourier projection)."""
        F = self._forward_execute(samples)
        out = np.empty((self.n_signals, 2 * self.H + 1))
        out[:, 0] = F[:, 0].real / self.N
        out[:, 1::2] = (2.0 / self.N) * F[:, 1 : self.H + 1].real
        out[:, 2::2] = (-2.0 / self.N) * F[:, 1 : self.H + 1].imag
        return out

    # ---------------------------------------------------------------- cosine only
    def cos_to_time(self, a: np.ndarray) -> np.ndarray:
        """Samples (n_signals, N) of even signals with cosine coefficients ``a`` (n_signals, H+1)."""
        F = self._freq
        F[:] = 0.0
        F[:, 0] = a[:, 0]
        F[:, 1 : self.H + 1] = 0.5 * a[:, 1:]
        return self._backward_execute()

    def time_to_cos(self, samples: np.ndarray) -> np.ndarray:
        """Cosine coefficients (n_signals, H+1) of the samples (n_signals, N)."""
        F = self._forward_execute(samples)
        out = (2.0 / self.N) * F[:, : self.H + 1].real
        out[:, 0] *= 0.5
        return out

    def cosine_spectrum(self, samples: np.ndarray) -> np.ndarray:
        """S_p = (1/N) Σ_j x_j cos(p τ_j) for p = 0..N-1 (aliased), shape (n_signals, N).

        The Jacobian of a projected product x(τ)·cos kτ uses it:
        (1/N) Σ_j x_j cos mτ_j cos kτ_j = ½ (S_{|m-k|} + S_{m+k}).
        """
        F = self._forward_execute(samples)
        half = F.real / self.N
        N = self.N
        full = np.empty((self.n_signals, N))
        full[:, : N // 2 + 1] = half
        full[:, N // 2 + 1 :] = half[:, 1 : (N + 1) // 2][:, ::-1]
        return full

    # ---------------------------------------------------------------- plumbing
    def _forward_execute(self, samples) -> np.ndarray:
        if self.use_fftw:
            self._time[:] = samples
            self._forward.execute()
            return self._freq
        return np.fft.rfft(np.asarray(samples, dtype=float).reshape(self.n_signals, self.N), axis=-1)

    def _backward_execute(self) -> np.ndarray:
        if self.use_fftw:
            self._backward.execute()  # unnormalised c2r: exactly the Fourier sum
            return self._time.copy()
        return np.fft.irfft(self._freq, n=self.N, axis=-1) * self.N


def transform(harmonics: int, n_samples: int, n_signals: int = 1) -> HarmonicTransform:
    """A cached :class:`HarmonicTransform` (plans are made once per shape and thread).

    The returned object owns its FFTW buffers, so each thread gets its own: runs in a
    thread pool then give the same numbers as serial runs.
    """
    return _thread_transform(threading.get_ident(), harmonics, n_samples, n_signals)


@lru_cache(maxsize=64)
def _thread_transform(thread: int, harmonics: int, n_samples: int, n_signals: int) -> HarmonicTransform:
    return HarmonicTransform(harmonics, n_samples, n_signals)
