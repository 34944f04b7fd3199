"""The error band of a backbone: each point's frequency with its estimated relative error
(``branch.frequency_error``, :mod:`mmshbm.results.point_errors`)."""

from __future__ import annotations

import numpy as np

from .common import _figure, _finish

__all__ = ["plot_error_band"]


def plot_error_band(branch, *, ax=None, path=None, figsize=(6.4, 4.2)):
    """Amplitude (in gaps, m without a gap) against frequency (Hz) along the family front,
    with the band ``f · (1 ± frequency_error)`` shaded and, for a branch computed to a
    tolerance, the points that miss it marked.

    Parameters
    ----------
    branch : Branch
        A branch whose points carry an estimate (a run with ``tol``, or
        :meth:`~mmshbm.Branch.estimate_frequency_error`); points without one (NaN) have no
        band.
    ax : matplotlib Axes, optional
        Draw into these axes.
    path : str or Path, optional
        Write the figure there.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = _figure(ax, figsize)
    front = np.asarray(branch.family_front(), dtype=int)
    gap = branch.gap or 0.0
    scale, unit = (gap, "gaps") if gap > 0 else (1.0, "m")
    a = np.asarray(branch.amplitude, dtype=float)[front] / scale
    f = np.asarray(branch.frequency, dtype=float)[front]
    e = branch.frequency_error[front]
    known = np.isfinite(e)
    ax.plot(f, a, color="C0", lw=1.2, label="backbone")
    ax.fill_betweenx(a, f * (1 - np.where(known, e, 0)), f * (1 + np.where(known, e, 0)), where=known,
                     color="C0", alpha=0.25, lw=0, label="estimated error")
    settings = branch.metadata.get("tolerance")
    if isinstance(settings, dict):
        miss = ~(e <= float(settings["tol"]))
        if miss.any():
            ax.plot(f[miss], a[miss], "x", color="C3", ms=4, label=f"tolerance {settings['tol']:g} not met")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel(f"amplitude ({unit})")
    ax.legend(loc="best", fontsize="small")
    return _finish(fig, path)
