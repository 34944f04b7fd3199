"""Plots of friction-damper results: the optimal-normal-load curve and the damped
nonlinear mode (frequency and damping ratio against amplitude)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

__all__ = ["plot_normal_load", "plot_friction_mode"]


def plot_normal_load(study, path=None, dpi: int = 150) -> Figure:
    """Resonance amplitude (m, log) and its frequency (Hz) against normal load (N, log) of
    a :class:`~mmshbm.analysis.friction_study.NormalLoadStudy`; the optimum marked, loads
    whose largest amplitude lies at an end of the band hollow, loads with a solve that
    did not converge crossed. N = 0 is drawn as a horizontal line (the free-slip peak)."""
    fig = Figure(figsize=(6.4, 5.6), layout="constrained")
    ax, axf = fig.subplots(2, 1, sharex=True, height_ratios=(2, 1))
    N, a, f = study.normal_load, study.peak_amplitude, study.peak_frequency
    pos = N > 0
    edge = study.at_band_edge
    ax.plot(N[pos], a[pos], "C0-", lw=1)
    ax.plot(N[pos & ~edge], a[pos & ~edge], "C0o", ms=4, label="resonance peak")
    if np.any(pos & edge):
        ax.plot(N[pos & edge], a[pos & edge], "o", mfc="none", mec="C0", ms=5, label="largest at a band edge")
    bad = pos & ~study.converged
    if np.any(bad):
        ax.plot(N[bad], a[bad], "kx", ms=7, label="a solve did not converge")
    if np.any(~pos):
        ax.axhline(a[~pos][0], color="0.5", ls="--", lw=1, label="N = 0 (free slip)")
    n_opt, a_opt = study.optimum
    ax.plot([n_opt], [a_opt], "C3*", ms=12, label=f"optimum: N = {n_opt:.3g} N, {a_opt:.3g} m")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylabel("resonance amplitude (m)")
    ax.set_title(f"MMS-HBM, H = {study.harmonics}, band {study.band[0]:g}-{study.band[1]:g} Hz", fontsize=10)
    ax.legend(fontsize=8)
    axf.plot(N[pos], f[pos], "C1.-")
    axf.set_ylabel("frequency (Hz)")
    axf.set_xlabel("normal load N (N)")
    if path is not None:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=dpi)
    return fig


def plot_friction_mode(branch, path=None, dpi: int = 150, label: str | None = None) -> Figure:
    """Frequency (Hz) and damping ratio against amplitude (m, log) of a damped nonlinear
    mode with friction (:func:`mmshbm.backbone` of a friction model)."""
    fig = Figure(figsize=(6.4, 5.6), layout="constrained")
    axf, axd = fig.subplots(2, 1, sharex=True)
    axf.plot(branch.amplitude, branch.frequency, "C0.-", ms=3, label=label)
    axf.set_ylabel("frequency (Hz)")
    axd.plot(branch.amplitude, branch.damping_ratio, "C3.-", ms=3)
    axd.set_ylabel("damping ratio D")
    axd.set_xlabel("amplitude (m)")
    axd.set_xscale("log")
    axd.set_yscale("log")
    if label:
        axf.legend(fontsize=8)
    if path is not None:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=dpi)
    return fig
