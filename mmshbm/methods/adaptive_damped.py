"""Damped nonlinear modes (EPMC) to a tolerance: H chosen per point from an error estimate.

``mmshbm.backbone(damped_model, tol=1e-4)`` (the damped nonlinear mode, method "epmc",
:mod:`mmshbm.methods.mms.epmc`) runs :func:`damped_mode_to_tolerance`, the backbone's
scheme (:mod:`mmshbm.methods.adaptive`) with two measures per point:

1. the continuation runs at ``start_harmonics`` (default 8);
2. every point is re-solved at 2H with its amplitude pinned, from its own coefficients
   padded with zeros (:mod:`mmshbm.methods.tolerance_ladder`), and the differences are
   its estimates at H, relative, with the backbone's Richardson factor 4/3 (rate 2,
   :mod:`mmshbm.results.point_errors`):

       frequency_error = 4/3 · |f(2H) − f(H)| / f(2H),
       damping_error   = 4/3 · |ζ(2H) − ζ(H)| / |ζ(2H)|,

   ζ the modal damping ratio ξ/(2Ω) (``branch.damping_ratio``); the point's estimate is
   the larger of the two;
3. a point of the family front whose estimate exceeds ``tol`` is promoted to its 2H
   solution and estimated again at 4H, and so on (the backbone's rules: never past
   ``max_harmonics``, not where the estimate stops contracting);
4. the branch keeps each point at the lowest H whose estimate met ``tol``:
   ``branch.frequency_error``, ``branch.records["damping_error"]``,
   ``branch.records["harmonics"]``; points that cannot meet it are a
   ``"tolerance_not_met"`` finding (:mod:`mmshbm.results.tolerance_checks`).

The damping ratio's relative error is the measure where the mode is damped; a mode whose
damping ratio is zero at a point (a friction mode stuck, without viscous damping) has no
relative damping error there and is measured on its frequency alone.
"""

from __future__ import annotations

import math
import time
import warnings

import numpy as np

from .tolerance_ladder import DampedLadder, pad_damped, raise_H, refine_points

__all__ = ["damped_mode_to_tolerance"]

_FAILURES = (ArithmeticError, ValueError, np.linalg.LinAlgError)
#: Richardson's factor 2^p / (2^p − 1) at the rate p = 2
FACTOR = 4.0 / 3.0


def damped_mode_to_tolerance(model, tol: float, *, start_harmonics: int, max_harmonics: int, patience: int,
                             contraction: float, run, **kwargs):
    """The damped nonlinear mode of ``model`` with every point's estimated relative
    frequency and damping-ratio errors at most ``tol`` where they can be had (module
    docstring); the parameters are those of
    :func:`mmshbm.methods.adaptive.backbone_to_tolerance`.

    Returns
    -------
    Branch
        With ``records["frequency_error"]``, ``records["damping_error"]``,
        ``records["harmonics"]`` and ``metadata["tolerance"]``.
    """
    from .._threads import blas_limit
    from ..core.pinned import solve_at_amplitude
    from .registry import make_problem

    t0 = time.perf_counter()
    with warnings.catch_warnings():  # the start H's findings are not the result's: it is checked below
        warnings.simplefilter("ignore")
        base = run(model, harmonics=start_harmonics, **kwargs)
    options = {k: v for k, v in dict(base.metadata.get("method_options", {})).items()
               if k not in ("harmonics", "n_samples")}
    ladder = DampedLadder(lambda H: make_problem(model, base.method, **{**options, "harmonics": H}),
                          base.attached_solver)
    eligible = np.zeros(len(base), dtype=bool)
    eligible[np.asarray(base.family_front(), dtype=int)] = True

    def estimate(idx, H, states):
        out = []
        for h, u in zip(H, states, strict=True):
            mon = ladder.at(h).monitor(u)
            f, a, z = float(mon["frequency"]), float(mon["amplitude"]), float(mon.get("damping_ratio", 0.0))
            nan = ({"frequency": math.nan}, None, 2 * h)
            if not (a > 0 and math.isfinite(a) and math.isfinite(f)):
                out.append(nan)
                continue
            try:
                u2 = raise_H(ladder, h, u, 2 * h, lambda s, start, it, a=a: solve_at_amplitude(
                    s, start, a, tol=1e-10, max_iter=it)[0])
            except _FAILURES:
                out.append(nan)
                continue
            m2 = ladder.at(2 * h).monitor(u2)
            f2, z2 = float(m2["frequency"]), float(m2.get("damping_ratio", 0.0))
            m = {"frequency": FACTOR * abs(f2 - f) / abs(f2),
                 "damping": FACTOR * abs(z2 - z) / abs(z2) if z2 != 0 else 0.0}
            out.append((m, u2, 2 * h))
        return out

    with blas_limit():
        ref = refine_points(list(base.states), start_harmonics, estimate, tol=tol,
                            max_harmonics=max_harmonics, patience=patience, contraction=contraction,
                            eligible=eligible)
    settings = {"tol": float(tol), "start_harmonics": start_harmonics, "max_harmonics": max_harmonics,
                "patience": patience, "contraction": float(contraction), "rate": 2.0, "levels": ref.levels,
                "measures": ["frequency", "damping_ratio"], "elapsed_s": time.perf_counter() - t0}
    return _assemble(base, ladder, ref, settings)


def _assemble(base, ladder, ref, settings: dict):
    """The result branch: every point at its own H, padded to the largest."""
    from ..results.branch import Branch

    n = len(base)
    H = ref.harmonics
    start = int(settings["start_harmonics"])
    H_top = int(H.max()) if n else start
    top = ladder.at(H_top)
    rec = {k: np.array(v, copy=True) for k, v in base.records.items()}
    freq = np.array(base.frequency, dtype=float, copy=True)
    energy = np.array(base.energy, dtype=float, copy=True)
    force = np.array(base.contact_force_max, dtype=float, copy=True)
    states = np.empty((n, top.n_unknowns))
    for i in range(n):
        own = ladder.at(int(H[i]))
        states[i] = pad_damped(own, ref.states[i], top) if int(H[i]) != H_top else ref.states[i]
        if int(H[i]) != start:
            mon = own.monitor(ref.states[i])
            freq[i] = mon["frequency"]
            energy[i] = mon.get("energy", energy[i])
            force[i] = mon.get("contact_force_max", force[i])
            for k, v in mon.items():
                if k in rec and rec[k].ndim == 1 and k not in ("frequency", "amplitude"):
                    rec[k][i] = v
    nan = np.full(n, np.nan)
    rec["frequency_error"] = ref.measures.get("frequency", nan)
    rec["damping_error"] = ref.measures.get("damping", nan)
    rec["harmonics"] = H.astype(np.int64)
    rec["error_extrapolated"] = ref.extrapolated
    meta = dict(base.metadata)
    meta["method_options"] = {**dict(meta.get("method_options", {})), "harmonics": H_top}
    meta["method_options"].pop("n_samples", None)
    meta.update(harmonics=H_top, n_samples=int(top.N), tolerance=settings)
    branch = Branch(frequency=freq, amplitude=np.array(base.amplitude, dtype=float, copy=True), energy=energy,
                    contact_force_max=force, newton_iterations=base.newton_iterations,
                    step_size=base.step_size, states=states, status=base.status, method=base.method,
                    harmonics=H_top, special_points=list(base.special_points), metadata=meta, solver=top,
                    residual_histories=base.residual_histories, records=rec)
    branch.check()
    return branch
