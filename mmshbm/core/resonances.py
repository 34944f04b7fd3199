"""Naming the internal resonances a branch meets.

Where harmonic k of the motion reaches another linear mode j (kΩ ≈ ω_j), energy moves
from the starting mode into mode j at that harmonic. Along a branch with per-point modal
energy shares (``records["modal_shares"]``, shape (n_points, n_modes, H+1), kinetic-energy
share of mode j in harmonic k) :func:`internal_resonances` finds, for every pair (k, j),
the stretches of points within ``ratio_tol`` of kΩ = ω_j where mode j holds at least
``min_share`` of the energy at harmonic k, and names each stretch by its point of largest
share: a :class:`~mmshbm.core.special_points.SpecialPoint` of kind
``"internal_resonance"`` with ``k``, ``j`` (1-based), ``ratio`` = kΩ/ω_j, ``share`` and
``mode_frequency`` (Hz).
"""

from __future__ import annotations

import numpy as np

from .special_points import SpecialPoint

__all__ = ["internal_resonances"]


def internal_resonances(frequency: np.ndarray, modal_shares: np.ndarray, mode_frequencies: np.ndarray,
                        mode: int = 1, *, ratio_tol: float = 0.05, min_share: float = 1e-3) -> list:
    """Internal resonances along a branch.

    Parameters
    ----------
    frequency : ndarray, shape (n_points,)
        Ω/2π per point (Hz).
    modal_shares : ndarray, shape (n_points, n_modes, H+1)
        Kinetic-energy share of mode j (axis 1) in harmonic k (axis 2).
    mode_frequencies : ndarray, shape (n_modes,)
        Linear frequencies (Hz) of those modes.
    mode : int
        The starting mode (1-based), not a resonance partner.
    ratio_tol, min_share : float
        A point takes part when |kΩ/ω_j − 1| <= ratio_tol and the share >= min_share.

    Returns
    -------
    list of SpecialPoint, sorted by index.
    """
    frequency = np.asarray(frequency, dtype=float)
    shares = np.asarray(modal_shares, dtype=float)
    if shares.ndim != 3 or shares.shape[0] != len(frequency) or len(frequency) == 0:
        return []
    n_modes, H1 = shares.shape[1], shares.shape[2]
    fj = np.asarray(mode_frequencies, dtype=float)[:n_modes]
    found = []
    # every pair (j, k) at once: the same numbers, k·f/ω_j, as one pair at a time
    with np.errstate(divide="ignore", invalid="ignore"):
        ratios = (np.arange(H1, dtype=float)[None, None, :] * frequency[:, None, None]) / fj[None, :, None]
        hits = (np.abs(ratios - 1.0) <= ratio_tol) & (shares >= min_share)  # (n, n_modes, H+1)
    any_hit = hits.any(axis=0)
    for j in range(n_modes):
        if j == mode - 1 or not fj[j] > 0:
            continue
        for k in range(1, H1):
            if not any_hit[j, k]:
                continue
            ratio = ratios[:, j, k]
            s = shares[:, j, k]
            idx = np.flatnonzero(hits[:, j, k])
            runs = np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1)
            for run in runs:
                i = int(run[np.argmax(s[run])])
                found.append(SpecialPoint("internal_resonance", i, k=int(k), j=int(j + 1),
                                          ratio=float(ratio[i]), share=float(s[i]),
                                          mode_frequency=float(fj[j])))
    found.sort(key=lambda p: (p.index, -p.data["share"]))
    return found
