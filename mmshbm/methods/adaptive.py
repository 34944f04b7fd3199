"""Backbones to a tolerance: H chosen per point from an error estimate on every point.

``mmshbm.backbone(model, tol=1e-4)`` runs :func:`backbone_to_tolerance`:

1. the continuation runs at a modest ``start_harmonics`` (default 8): every point of the
   branch, its family guard, jumps and special points come from that run;
2. every point is re-solved at 2H with its amplitude pinned, from its own coefficients
   (:mod:`mmshbm.results.point_errors`): the difference is its error estimate at H
   (relative, on the frequency at the point's amplitude);
3. a point of the family front (:meth:`~mmshbm.Branch.family_front`: the backbone,
   without the excursions into internal-resonance tongues, which keep the start H and
   their estimate at it; where the 2H solve of such a point in contact has no cheap
   start, :mod:`mmshbm.methods.adaptive_climb`, its estimate is NaN, flagged in
   ``records["error_not_estimated"]``) whose estimate exceeds ``tol`` is *promoted* to the 2H solution (the
   solve of step 2 is the refined point, seeded by the lower-H one) and estimated again
   at 4H, and so on while the estimate keeps contracting (``patience`` doublings of H in a
   row without a contraction by ``contraction`` stop it: the point does not converge in
   H in this range, e.g. orbits that rattle) and ``tol`` stays within reach (not more
   than ``FASTEST`` = 64 times per doubling the cap still allows below the estimate: a
   point out of reach keeps the 2H solution its estimate solved, the better one, with
   the estimate divided by the contraction of its last doubling where one was measured
   (between 1 and ``FASTEST``: above ``tol``), else by ``ASSUMED_CONTRACTION``, flagged
   in ``records["error_extrapolated"]``);
   no solve exceeds ``max_harmonics``: a point promoted to an H whose 2H would pass it
   gets the estimate below divided by the contraction of its last doubling (at least
   ``ASSUMED_CONTRACTION`` = 4, rate 2; at most ``FASTEST``), Richardson's estimate of
   the finer solution, flagged in ``records["error_extrapolated"]``;
4. an estimate that meets ``tol`` at H is *confirmed* on the next pair (``confirm``, on by
   default): the point's 2H solution is re-solved at 4H, and the estimate at H stands
   when |f(4H) − f(2H)| < |f(2H) − f(H)| (the pair contracts: H is in the asymptotic
   regime); where it does not, the pair (H, 2H) was pre-asymptotic (a stiff contact whose
   contact time neither series resolves: f(H) ≈ f(2H) on a plateau, then a drop once the
   series resolves it), and the point goes on from 2H with the estimate at 2H, as in step
   3. ``records["error_confirmed"]`` is 1 where the next pair contracted or the point
   carries no contact force (exact at every H), 0 where it was not checked (4H above the
   cap, a failed re-solve, ``confirm=False``, off the family front);
5. the branch keeps, at each point, the lowest H whose estimate met ``tol`` (the points
   that never needed more keep ``start_harmonics``: H is raised only where the branch
   needs it; a point whose estimate stalled keeps its last H), its frequency and that
   estimate: ``branch.frequency_error``, ``branch.records["harmonics"]``.

The amplitude of every point is pinned in the re-solves: a point is (A_i, f_i) with the
estimated error on f_i at A_i, so its relative distance to the converged backbone, in
frequency or in amplitude, is at most ``frequency_error`` (the amplitude is exact by
construction; the frequency carries the error).

The branch returned is one :class:`~mmshbm.Branch` at the largest H any point kept
(``branch.harmonics``): each point's unknowns are its own solution's coefficients padded
with zeros to that H, so that the contact DOF's series of every point is its own; the
other DOFs' signals are recovered at ``branch.harmonics``. Points where ``tol`` is not met
(estimate above it at the cap, estimate stalled, a failed re-solve) are a
``"tolerance_not_met"`` finding (:mod:`mmshbm.results.tolerance_checks`).

The points are refined one after the other along the branch
(:mod:`mmshbm.methods.adaptive_climb`): a front point in contact starts at the rung its
predecessor decided on instead of climbing to it from ``start_harmonics`` (the rungs below
tried where the estimate predicted there meets ``tol``), and where its zero-padded start
fails at a higher H the predecessor's solution there is the start.

Cost: the continuation at ``start_harmonics``, and per front point in contact about two
pinned solves (at the rung its predecessor kept and at twice it), one more for each rung it
moves up or down, and one at 4H where an estimate that met ``tol`` is confirmed; one pinned
solve at 2H per other point (two at most off the front in contact: the padded start, then
the excursion's previous point; never the √2 steps of
:func:`~mmshbm.results.point_errors.raise_point`, which served most of the points off the
front in contact on random chains and took most of the refinement's time).
"""

from __future__ import annotations

import logging
import math
import time
import warnings

import numpy as np

from .. import _validate as check

__all__ = ["backbone_to_tolerance", "check_tolerance", "TOLERANCE_DEFAULTS"]

log = logging.getLogger(__name__)

#: the defaults of the tolerance options of :func:`backbone_to_tolerance`
TOLERANCE_DEFAULTS = {"start_harmonics": 8, "max_harmonics": 64, "patience": 2, "contraction": 1.5,
                      "confirm": True}




def check_tolerance(tol, harmonics, method: str, options: dict) -> dict:
    """The checked tolerance options (popped from ``options``): tol, start_harmonics,
    max_harmonics, patience, contraction, confirm.

    Raises
    ------
    ValueError
        tol not a number in (0, 1), given together with ``harmonics``, a method without
        harmonics, a start H above the cap.
    """
    if isinstance(tol, bool) or not isinstance(tol, int | float) or not math.isfinite(tol) or not 0 < tol < 1:
        raise ValueError(f"tol must be a relative tolerance in (0, 1), e.g. 1e-4, got {tol!r}")
    if harmonics is not None:
        raise ValueError(f"pass either harmonics (a fixed H, got {harmonics!r}) or tol (H chosen to meet it, "
                         f"got {tol!r}), not both; with tol, start_harmonics and max_harmonics bound H")
    if method not in ("mmshbm", "penalty"):
        raise ValueError(f"tol is available for the conservative harmonic balance methods 'mmshbm' and "
                         f"'penalty', not {method!r}: pass harmonics instead")
    out = {k: options.pop(k, v) for k, v in TOLERANCE_DEFAULTS.items()}
    out["start_harmonics"] = check.integer("start_harmonics", out["start_harmonics"], minimum=1)
    out["max_harmonics"] = check.integer("max_harmonics", out["max_harmonics"], minimum=2)
    out["patience"] = check.integer("patience", out["patience"], minimum=1)
    if 2 * out["start_harmonics"] > out["max_harmonics"]:
        raise ValueError(f"max_harmonics ({out['max_harmonics']}) caps every solve, the error estimate's at "
                         f"2H included: it must be at least 2 * start_harmonics "
                         f"({2 * out['start_harmonics']})")
    if not isinstance(out["confirm"], bool):
        raise ValueError(f"confirm must be True or False, got {out['confirm']!r}")
    c = out["contraction"]
    if isinstance(c, bool) or not isinstance(c, int | float) or not c >= 1:
        raise ValueError(f"contraction must be a number >= 1, got {c!r}")
    out["tol"] = float(tol)
    return out


def backbone_to_tolerance(model, tol: float, *, start_harmonics: int, max_harmonics: int, patience: int,
                          contraction: float, confirm: bool = True, run, **kwargs):
    """The backbone of ``model`` with every point's estimated relative frequency error
    at most ``tol`` where it can be had (module docstring).

    Parameters
    ----------
    model : Model
    tol : float
        Relative tolerance on each point's frequency at its amplitude.
    start_harmonics : int
        H of the continuation.
    max_harmonics : int
        The largest H of any solve, the estimates' included (step 3 of the module
        docstring): the most harmonics a point can have.
    patience : int
        Doublings of H without the estimate contracting by ``contraction`` after which a
        point is left where it is (not converging in H here).
    contraction : float
        The factor by which an estimate must fall per doubling of H to count as converging.
    confirm : bool
        Check an estimate that meets ``tol`` on the next pair (step 4 of the module
        docstring; one more pinned solve, at 4H, per such point in contact).
    run : callable
        ``run(model, harmonics=H, **kwargs)`` -> Branch: the fixed-H backbone.
    **kwargs
        The other arguments of the fixed-H backbone.

    Returns
    -------
    Branch
        With ``records["frequency_error"]``, ``records["harmonics"]``,
        ``records["error_extrapolated"]``, ``records["error_confirmed"]``,
        ``records["error_not_estimated"]`` (1 at a point off the family front in contact
        whose 2H solve had no cheap start: its estimate NaN, no part of the tolerance's
        findings) and ``metadata["tolerance"]``.
    """
    from .._threads import blas_limit
    from .adaptive_climb import refine_points_along

    t0 = time.perf_counter()
    with warnings.catch_warnings():  # the findings of the start H are not the result's: it is checked below
        warnings.simplefilter("ignore")
        base = run(model, harmonics=start_harmonics, **kwargs)
    with blas_limit():  # small dense solves: one BLAS thread unless the user chose (mmshbm._threads)
        refined = refine_points_along(base, tol, start_harmonics, max_harmonics, patience, contraction,
                                      confirm)
        ladder, H, states, freq, err, flags, levels, solves = refined
        return _assemble(base, ladder, H, states, freq, err, flags, settings={
            "tol": float(tol), "start_harmonics": start_harmonics, "max_harmonics": max_harmonics,
            "patience": patience, "contraction": float(contraction), "confirm": bool(confirm), "rate": 2.0,
            "levels": levels, "pinned_solves": solves,
            "elapsed_s": time.perf_counter() - t0})


def _assemble(base, ladder, H, states, freq, err, flags, settings: dict):
    """The result branch: every point at its own H, padded to the largest (module docstring)."""
    from ..results.branch import Branch
    from ..results.point_errors import pad

    n = len(base)
    H_top = int(H.max()) if n else int(settings["start_harmonics"])
    top = ladder.at(H_top)
    rec = {k: np.array(v, copy=True) for k, v in base.records.items()}
    energy = np.array(base.energy, dtype=float, copy=True)
    force = np.array(base.contact_force_max, dtype=float, copy=True)
    out_states = np.empty((n, top.n_unknowns)) if n else np.empty((0, top.n_unknowns))
    for i in range(n):
        own = ladder.at(int(H[i]))
        out_states[i] = pad(own, states[i], top) if int(H[i]) != H_top else states[i]
        if int(H[i]) != int(settings["start_harmonics"]):
            mon = own.monitor(states[i])
            energy[i] = mon.get("energy", energy[i])
            force[i] = mon.get("contact_force_max", force[i])
            for k, v in mon.items():
                if k in rec and rec[k].ndim == 1 and k not in ("frequency", "amplitude"):
                    rec[k][i] = v
    rec["frequency_error"] = err
    rec["harmonics"] = H.astype(np.int64)
    rec["error_extrapolated"], rec["error_confirmed"], rec["error_not_estimated"] = flags
    meta = dict(base.metadata)
    meta["method_options"] = {**dict(meta.get("method_options", {})), "harmonics": H_top}
    meta["method_options"].pop("n_samples", None)
    meta.update(harmonics=H_top, n_samples=int(top.N), tolerance=settings)
    branch = Branch(frequency=freq, amplitude=np.array(base.amplitude, dtype=float, copy=True), energy=energy,
                    contact_force_max=force, newton_iterations=base.newton_iterations,
                    step_size=base.step_size, states=out_states, status=base.status, method=base.method,
                    harmonics=H_top, special_points=list(base.special_points), metadata=meta, solver=top,
                    residual_histories=base.residual_histories, records=rec)
    branch.check()
    return branch
