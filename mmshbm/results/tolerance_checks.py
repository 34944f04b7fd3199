"""The branch check of a tolerance asked for (``backbone(model, tol=...)``): where the
per-point error estimate (``branch.frequency_error``, :mod:`mmshbm.results.point_errors`)
meets it and where not (:func:`mmshbm.results.diagnostics.check_branch` runs it).

``"tolerance_not_met"``
    Points of the family front (:meth:`~mmshbm.Branch.family_front`) whose estimate is
    above the tolerance, or could not be made (a re-solve at 2H failed), after H was
    raised as far as the run allowed (``max_harmonics``, or the estimate stopped
    contracting: the orbit does not converge in H at these H). The message names the
    amplitude from which it no longer holds and the estimates reached there; ``first``
    is that point, ``last`` the last such point, ``value`` the largest estimate reached.
    Points off the front are not counted: the backbone's contract is its front's (its
    excursions keep the start H, and the estimate of one in contact is NaN where
    ``records["error_not_estimated"]`` is 1, :mod:`mmshbm.methods.adaptive_climb`).

:func:`tolerance_summary` is the one line a run that met its tolerance reports (the
command line prints it).
"""

from __future__ import annotations

import math

import numpy as np

from .findings import Finding
from .findings import where as _where

__all__ = ["tolerance_findings", "tolerance_summary", "tolerance_of", "unmet_points", "point_estimate"]


def tolerance_of(branch) -> float | None:
    """The tolerance the branch was computed to (``metadata["tolerance"]["tol"]``), or None."""
    settings = branch.metadata.get("tolerance")
    if not isinstance(settings, dict) or "tol" not in settings:
        return None
    return float(settings["tol"])


def unmet_points(branch) -> np.ndarray:
    """Indices of the family front's points whose estimate does not meet the tolerance
    (above it or NaN), in front order; empty without a tolerance."""
    tol = tolerance_of(branch)
    if tol is None or not len(branch):
        return np.zeros(0, dtype=int)
    front = np.asarray(branch.family_front(), dtype=int)
    err = point_estimate(branch)[front]
    return front[~(err <= tol)]


def point_estimate(branch) -> np.ndarray:
    """The estimate ``tol`` bounds at each point, shape (n_points,): ``frequency_error``,
    and for a damped nonlinear mode the larger of it and ``records["damping_error"]``."""
    err = branch.frequency_error
    damping = branch.records.get("damping_error")
    if damping is not None and len(damping) == len(branch):
        err = np.maximum(err, np.asarray(damping, dtype=float))
    return err


def _amp(branch, a: float) -> str:
    gap = branch.gap
    return f"{a / gap:.4g} gaps" if gap else f"{a:.4g} m"


def tolerance_findings(branch) -> list[Finding]:
    """The ``"tolerance_not_met"`` finding of ``branch`` (module docstring); empty when it
    was computed without a tolerance or meets it on its whole family front."""
    bad = unmet_points(branch)
    if not len(bad):
        return []
    tol = tolerance_of(branch)
    settings = branch.metadata["tolerance"]
    err = point_estimate(branch)[bad]
    finite = err[np.isfinite(err)]
    H = np.asarray(branch.records.get("harmonics", np.full(len(branch), branch.harmonics)))[bad]
    first = int(bad[0])
    n_front = len(branch.family_front())
    reached = (f"estimates reached there {np.min(finite):.2g} to {np.max(finite):.2g} (median "
               f"{np.median(finite):.2g})" if len(finite) else "no estimate could be made there")
    failed = int(np.sum(~np.isfinite(err)))
    again = [int(i) for i in branch.family_front() if branch.amplitude[i] > branch.amplitude[bad[-1]]]
    on = "on the frequency and damping ratio" if "damping_error" in branch.records else "on the frequency"
    message = (f"{branch.method} branch: the tolerance {tol:g} {on} is not met from "
               f"{_amp(branch, float(branch.amplitude[first]))} ({_where(branch, first)}) on: {len(bad)} of "
               f"{n_front} family points, {reached}"
               + (f", {failed} re-solves at 2H failed" if failed else "")
               + f", with H up to {int(H.max())} (max_harmonics {settings.get('max_harmonics')}: H is not "
               "raised past it, nor where tol is out of reach below it, nor where the estimate stopped "
               "contracting as H doubled, an orbit that does not converge in H there)"
               + (f"; it holds again above {_amp(branch, float(branch.amplitude[bad[-1]]))}"
                  if again else ""))
    value = float(np.max(finite)) if len(finite) else math.nan
    return [Finding("tolerance_not_met", message, first, int(bad[-1]), value)]


def tolerance_summary(branch) -> str | None:
    """One line on the tolerance of ``branch``: met everywhere (with the largest estimate
    and the range of H), or not met from an amplitude on; None without a tolerance."""
    tol = tolerance_of(branch)
    if tol is None:
        return None
    H = np.asarray(branch.records.get("harmonics", [branch.harmonics]))
    bad = unmet_points(branch)
    err = point_estimate(branch)
    hs = f"H {int(H.min())}" + (f"-{int(H.max())}" if H.max() != H.min() else "")
    if not len(bad):
        worst = float(np.nanmax(err[branch.family_front()])) if len(branch) else math.nan
        what = "frequency and damping-ratio error" if "damping_error" in branch.records else "frequency error"
        return (f"tolerance {tol:g} met at every point of the backbone (largest estimated {what} "
                f"{worst:.2g}, {hs})")
    return (f"tolerance {tol:g} met up to {_amp(branch, float(branch.amplitude[bad[0]]))} only "
            f"({len(bad)} points beyond it miss it; {hs}): see the tolerance_not_met finding")
