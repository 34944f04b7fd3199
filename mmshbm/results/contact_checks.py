"""The branch checks of the contact: the depth past each stop and the pull of the
contact force, from the signals of every point at once (:mod:`mmshbm.results.diagnostics`
runs them)."""

from __future__ import annotations

import math

import numpy as np

from .findings import CheckThresholds, Finding
from .findings import where as _where

__all__ = ["contact_findings"]


def contact_findings(branch, solver, th: CheckThresholds) -> list[Finding]:
    model = getattr(solver, "model", None)
    if model is None or not hasattr(solver, "time_signals") or not hasattr(solver, "contact_force"):
        return []
    n = th.n_samples
    dofs = [c.dof for c in model.contacts]
    sides = np.array([c.side for c in model.contacts], dtype=float)[:, None]
    gaps = np.array([c.gap for c in model.contacts], dtype=float)[:, None]
    f_abs = np.abs(np.asarray(branch.contact_force_max, dtype=float))
    # np.nanmax of the finite-holding array is np.fmax.reduce (what nanmax computes for an ndarray)
    f_scale = float(np.fmax.reduce(f_abs)) if len(f_abs) and np.isfinite(f_abs).any() else 0.0
    k_c = getattr(solver, "contact_stiffness", None)  # a number, or one per contact DOF
    if k_c is not None and type(k_c) is not float:
        k_c = float(np.max(np.atleast_1d(np.asarray(k_c, dtype=float))))
    if k_c is not None and math.isfinite(k_c):
        f_scale = max(f_scale, k_c * float(np.max(gaps)))
    tau = _grid(n)
    cheap = model.n_contacts == 1 and hasattr(solver, "contact_signals")
    # the signals of every point first, the reductions over points and samples at once
    # (numpy calls per point cost more than the signals of a small model)
    n_pts, n_k = len(branch), len(dofs)
    amp = np.maximum(np.asarray(branch.amplitude, dtype=float), 1e-300)[:, None, None]
    scale = np.where(gaps[None] > 0, gaps[None], amp)  # (n_pts, n_k, 1)
    many = cheap and hasattr(solver, "contact_signals_many") and n_pts
    if many:  # every point's contact DOF and force at once, (n_pts, n_k, n) each
        Q, L = solver.contact_signals_many(np.asarray(branch.states, dtype=float), tau)
    else:
        Q = np.empty((n_pts, n_k, n))
        L = np.zeros((n_pts, n_k, n))  # the force of each stop, > 0 when it pushes
    for i, u in enumerate(() if many else branch.states):
        if cheap:  # the contact DOF and the force without recovering every DOF
            _, Q[i, 0], L[i, 0] = solver.contact_signals(u, tau)
        else:
            Q[i] = solver.time_signals(u, dofs, n)[1]
            # the force right after the motion: a solver may cache the last point's orbit
            if np.max((sides * Q[i] - gaps) / scale[i]) >= -th.penetration:
                L[i] = _stop_forces(model, Q[i], np.atleast_2d(solver.contact_force(u, n)[1]))
    # the deepest sample past each stop, (n_pts, n_k) gaps: (s·q − gap)/scale of the extreme
    # sample of s·q (the largest q for s >= 0, the smallest for s < 0), the same number as the
    # largest of every sample's depth (each operation is monotone in q, the scale positive)
    depth = np.zeros((n_pts, n_k))
    if n_pts:
        s = sides[None, :, 0]
        if (s >= 0).all():  # only upper stops (the common case): np.where's first choice everywhere
            reach = s * Q.max(axis=2)
        else:
            reach = np.where(s >= 0, s * Q.max(axis=2), s * Q.min(axis=2))
        depth = (reach - gaps[None, :, 0]) / scale[:, :, 0]
    pen = depth.max(axis=1) if n_pts else np.zeros(0)
    # a contact that never comes near its stop carries no force but Newton's residual
    need_force = pen >= -th.penetration
    neg = np.zeros(n_pts)
    if n_pts:  # per stop: its pull against its own peak push
        floor = th.force_floor * f_scale
        near = depth >= -th.penetration  # (n_pts, n_k)
        peak = np.maximum(L.max(axis=2), floor)
        lo = L.min(axis=2)
        ratio = np.where(near & (peak > 0) & (lo < -floor), -lo / peak, 0.0)
        neg = ratio.max(axis=1) * need_force
    out = []
    bad = np.flatnonzero(pen > th.penetration)
    if len(bad):
        worst = int(bad[np.argmax(pen[bad])])
        what = "truncated Fourier series of the contact DOF" if branch.harmonics else "contact DOF"
        out.append(Finding(
            "penetration",
            f"{branch.method} branch: the {what} passes the stop by more than {th.penetration:g} gaps at "
            f"{len(bad)} of {len(branch)} points, from {_where(branch, int(bad[0]))}; deepest "
            f"{pen[worst]:.3g} gaps at point {worst} ({branch.frequency[worst]:.4g} Hz)"
            + ("; more harmonics reduce it, branch.time_signals(i, admissible=True) gives admissible "
               "signals, branch.truncation_error(A) estimates the frequency's error at amplitude A"
               if branch.harmonics else "")
            + _against_tolerance(branch, bad), int(bad[0]), int(bad[-1]), float(pen[worst])))
    bad = np.flatnonzero(neg > th.negative_force)
    if len(bad):
        worst = int(bad[np.argmax(neg[bad])])
        out.append(Finding(
            "negative_force",
            f"{branch.method} branch: the contact force changes sign (pulls) by more than "
            f"{th.negative_force:g} of the peak force at {len(bad)} of {len(branch)} points, from "
            f"{_where(branch, int(bad[0]))}; worst {neg[worst]:.3g} of the peak at point {worst}"
            + (" (a truncation effect of the Fourier series; branch.truncation_error(A) estimates the "
               "frequency's error at amplitude A)" if branch.harmonics else "")
            + _against_tolerance(branch, bad), int(bad[0]), int(bad[-1]), float(-neg[worst])))
    return out


def _against_tolerance(branch, points: np.ndarray) -> str:
    """For a branch computed to a tolerance (``tol``): what the truncation effect at
    ``points`` costs the frequency there, against the tolerance (empty otherwise). Only the
    points of the family front (:meth:`~mmshbm.Branch.family_front`) are counted, as in
    :mod:`mmshbm.results.tolerance_checks`: the tolerance is the front's; a point off it
    keeps the start H and, in contact, may carry a NaN estimate
    (``records["error_not_estimated"]``)."""
    settings = branch.metadata.get("tolerance")
    err = branch.records.get("frequency_error")
    if not isinstance(settings, dict) or err is None or len(err) != len(branch) or not len(points):
        return ""
    tol = float(settings["tol"])
    on = np.intersect1d(np.asarray(points, dtype=int), np.asarray(branch.family_front(), dtype=int))
    off = len(points) - len(on)
    aside = f" ({off} off the family front not counted)" if off else ""
    if not len(on):
        return f"; against the tolerance {tol:g}: none of these points is on the family front{aside}"
    e = np.asarray(err, dtype=float)[on]
    met = int(np.sum(e <= tol))
    worst = float(np.max(e[np.isfinite(e)])) if np.isfinite(e).any() else math.nan
    return (f"; against the tolerance {tol:g}: the frequency's estimated error at these points is up to "
            f"{worst:.2g} on the family front, within the tolerance at {met} of the {len(on)} there{aside}")


#: n -> τ = 2π·arange(n)/n (read only) of the checks' sample grids
_GRIDS: dict = {}


def _grid(n: int) -> np.ndarray:
    """The check's sample grid ``2 * np.pi * np.arange(n) / n`` (rad), kept per n (read only)."""
    tau = _GRIDS.get(n)
    if tau is None:
        tau = 2 * np.pi * np.arange(n) / n
        tau.flags.writeable = False
        if len(_GRIDS) < 16:
            _GRIDS[n] = tau
    return tau


def _stop_forces(model, q: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """The force of each stop (rows in the order of ``model.contacts``, > 0 when it pushes)
    from a solver's contact forces ``lam``: one row per contact (already per stop), or one
    per contact DOF (:func:`~mmshbm.model.contact.admissible_intervals` order; the net force
    the structure needs, > 0 for a push of an upper stop, < 0 for one of a lower stop).
    On a DOF between two stops the net force is the upper stop's where the DOF is nearer
    to it and the lower one's elsewhere: the two never push at once. ``q`` (n_contacts, n)
    is the motion of each contact's DOF."""
    from ..model.contact import admissible_intervals

    contacts = model.contacts
    if lam.shape[0] == len(contacts):
        return lam
    dofs, lo, hi = admissible_intervals(contacts)
    if lam.shape[0] != len(dofs):  # a solver reporting fewer rows: the same force for every stop
        return np.broadcast_to(lam, (len(contacts), lam.shape[1]))
    row = {int(d): i for i, d in enumerate(dofs)}
    out = np.zeros((len(contacts), lam.shape[1]))
    for i, ct in enumerate(contacts):
        r = row[ct.dof]
        if np.isfinite(lo[r]) and np.isfinite(hi[r]):
            mid = 0.5 * (lo[r] + hi[r])
            mine = q[i] >= mid if ct.side > 0 else q[i] < mid
            out[i] = np.where(mine, ct.side * lam[r], 0.0)
        else:
            out[i] = lam[r]
    return out


#: what an unfinished status means, by its first word
