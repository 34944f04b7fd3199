"""The check of a tolerance asked of a forced response (``frequency_response(..., tol=...)``,
:mod:`mmshbm.methods.adaptive_forced`): where the per-point estimate meets it.

Each point carries ``records["amplitude_error"]`` and ``records["frequency_error"]``;
the one measured (``records["error_pinned"]``: 0 the frequency was pinned and the
amplitude measured, 1 the amplitude pinned and the frequency measured) is the point's
estimate, and ``tol`` bounds it.

``"tolerance_not_met"``
    Points whose estimate is above the tolerance, or could not be made (a re-solve at
    2H failed), after H was raised as far as the run allowed. The message names the
    frequency and amplitude of the first such point along the path, how many there are,
    the estimates reached and the H used; ``first``/``last`` are the first and last such
    points, ``value`` the largest estimate.

:func:`response_tolerance_summary` is the one line the command line prints.
"""

from __future__ import annotations

import math

import numpy as np

from .findings import Finding

__all__ = ["response_tolerance_findings", "response_tolerance_summary", "point_estimate", "unmet"]


def _tol(resp) -> float | None:
    settings = resp.metadata.get("tolerance")
    return float(settings["tol"]) if isinstance(settings, dict) and "tol" in settings else None


def point_estimate(resp) -> np.ndarray:
    """Each point's measured relative error (the one ``tol`` bounds), shape (n_points,);
    NaN where none was made or without a tolerance."""
    n = len(resp)
    rec = resp.records
    if "error_pinned" not in rec or "amplitude_error" not in rec:
        return np.full(n, np.nan)
    pinned = np.asarray(rec["error_pinned"], dtype=bool)
    return np.where(pinned, np.asarray(rec["frequency_error"], dtype=float),
                    np.asarray(rec["amplitude_error"], dtype=float))


def unmet(resp) -> np.ndarray:
    """Indices of the points whose estimate does not meet the tolerance (above it or NaN);
    empty without a tolerance."""
    tol = _tol(resp)
    if tol is None or not len(resp):
        return np.zeros(0, dtype=int)
    return np.flatnonzero(~(point_estimate(resp) <= tol))


def _amp(resp, a: float) -> str:
    gap = float(resp.metadata.get("model_gap", 0.0) or 0.0)
    return f"{a / gap:.4g} gaps" if gap > 0 else f"{a:.4g} m"


def response_tolerance_findings(resp) -> list[Finding]:
    """The ``"tolerance_not_met"`` finding of a forced response (module docstring); empty
    when it was computed without a tolerance or meets it everywhere."""
    bad = unmet(resp)
    if not len(bad):
        return []
    tol = _tol(resp)
    est = point_estimate(resp)[bad]
    finite = est[np.isfinite(est)]
    H = np.asarray(resp.records.get("harmonics", np.full(len(resp), resp.harmonics)))
    first = int(bad[0])
    reached = (f"estimates reached there {np.min(finite):.2g} to {np.max(finite):.2g} (median "
               f"{np.median(finite):.2g})" if len(finite) else "no estimate could be made there")
    failed = int(np.sum(~np.isfinite(est)))
    f = resp.frequency[bad]
    message = (f"{resp.method} frequency response: the tolerance {tol:g} is not met at {len(bad)} of "
               f"{len(resp)} points, first at {resp.frequency[first]:.6g} Hz "
               f"({_amp(resp, resp.amplitude[first])}), "
               f"between {f.min():.6g} and {f.max():.6g} Hz; {reached}"
               + (f", {failed} re-solves at 2H failed" if failed else "")
               + f", with H up to {int(H[bad].max())} (max_harmonics "
               f"{resp.metadata['tolerance'].get('max_harmonics')}: H is not raised past it, nor where tol "
               "is out of reach below it, nor where the estimate stopped contracting as H doubled)")
    value = float(np.max(finite)) if len(finite) else math.nan
    return [Finding("tolerance_not_met", message, first, int(bad[-1]), value)]


def response_tolerance_summary(resp) -> str | None:
    """One line on the tolerance of a forced response: met everywhere (largest estimate,
    range of H), or at how many points not; None without a tolerance."""
    tol = _tol(resp)
    if tol is None:
        return None
    H = np.asarray(resp.records.get("harmonics", [resp.harmonics]))
    hs = f"H {int(H.min())}" + (f"-{int(H.max())}" if len(H) and H.max() != H.min() else "")
    bad = unmet(resp)
    if not len(bad):
        worst = float(np.nanmax(point_estimate(resp))) if len(resp) else math.nan
        return (f"tolerance {tol:g} met at every point of the response (largest estimated error "
                f"{worst:.2g}, {hs})")
    return (f"tolerance {tol:g} met except at {len(bad)} of {len(resp)} points, from "
            f"{resp.frequency[bad[0]]:.6g} Hz on the path ({hs}): see the tolerance_not_met finding")
