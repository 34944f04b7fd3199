"""Forced responses to a tolerance: H chosen per point from an error estimate on every point.

``mmshbm.frequency_response(model, force, frequency_range, tol=1e-4)`` runs
:func:`response_to_tolerance`:

1. the continuation in the excitation frequency runs at ``start_harmonics`` (default 8):
   the path, its folds, grazing and stability come from that run;
2. every point is re-solved at 2H from its own coefficients padded with zeros, with one
   of its coordinates pinned, and the difference is its error estimate at H:

   - the excitation frequency is the response's parameter: it is pinned (the 2H point
     is the response at the same frequency) and the amplitude A measured,
     ``amplitude_error = 4/3 · |A(2H) − A(H)| / A(2H)``;
   - except near the folds of the path, where the amplitude at a given frequency is
     ill-conditioned (a relative frequency error ε moves it by |s|·ε, s = d ln A / d ln f
     the local slope) or not unique, and the pinned-frequency solve is singular: where
     |s| > ``PIN_SLOPE`` (10) the amplitude is pinned and the frequency measured,
     ``frequency_error = 4/3 · |f(2H) − f(H)| / f(2H)``;

   the other error follows from the slope of the path (differences between neighbouring
   points): ``frequency_error = amplitude_error / |s|``, resp. ``amplitude_error =
   |s| · frequency_error``. ``tol`` bounds the measured one: the amplitude at the
   frequency, and near folds the point's distance to the converged response along the
   frequency axis (``records["error_pinned"]`` says which);
3. a point whose estimate exceeds ``tol`` is promoted to its 2H solution and estimated at
   4H, and so on, with the backbone's rules (:mod:`mmshbm.methods.tolerance_ladder`,
   :mod:`mmshbm.methods.adaptive`): H is raised only where the response needs it, never
   past ``max_harmonics``, not where the estimate stops contracting;
4. the response keeps each point at the lowest H whose estimate met ``tol``; points that
   cannot meet it are a ``"tolerance_not_met"`` finding
   (:mod:`mmshbm.results.response_tolerance`).

The factor 4/3. Under the algebraic model of the truncation, A(H) = A_∞ + C·H^−p, the
error of A(H) is (A(H) − A(2H)) · 2^p / (2^p − 1): 4/3 at the rate p = 2 of the
backbone's estimator (:mod:`mmshbm.results.point_errors`), the same series of the same
contact law (the forced orbit of an impact oscillator is a backbone orbit with a
different phase balance; its contact events, whose resolution in H sets the rate, are the
same kind). The factor moves the estimate by at most 4/3 against p → ∞ and 2/3 against
p = 1; docs/accuracy.md gives the measured ratio estimate / true error on forced cases.

Stability, the Floquet multipliers, comes with every point at its own H (the re-solves
skip it; the promoted points get it again at their H).

Cost: the continuation at ``start_harmonics``, one pinned solve per point at 2H, and one
more per point for each doubling a point needs.
"""

from __future__ import annotations

import math
import time
import warnings

import numpy as np

from .._warnings import BranchWarning
from .tolerance_ladder import AmplitudePinned, DampedLadder, pad_damped, raise_H, refine_points

__all__ = ["response_to_tolerance", "path_slope", "PIN_SLOPE", "FORCED_TOLERANCE_METHODS"]

#: |d ln A / d ln f| above which a point's amplitude is pinned and its frequency measured
#: (below it the frequency is pinned and the amplitude measured): the amplification of a
#: frequency error into the amplitude beyond which the amplitude at a given frequency is
#: too ill-conditioned to measure (near a fold); a damped linear peak reaches about
#: 1/(2ζ) on its flanks (at the half-power points: 100 at ζ = 0.5 %), so the steep flanks
#: of lightly damped peaks are measured in frequency too
PIN_SLOPE = 10.0
#: the forced methods whose responses take ``tol`` (unknowns laid out harmonic by harmonic)
FORCED_TOLERANCE_METHODS = ("mmshbm",)
#: how far along the path (points) a neighbour's 2H solution may serve as a start
NEIGHBOURS = 3
_FAILURES = (ArithmeticError, ValueError, np.linalg.LinAlgError)
#: Richardson's factor 2^p / (2^p − 1) at the rate p = 2 (module docstring)
FACTOR = 4.0 / 3.0


def path_slope(frequency: np.ndarray, amplitude: np.ndarray) -> np.ndarray:
    """d ln A / d ln f along a path of points (central differences in the point index,
    one-sided at the ends), shape (n_points,); ±inf where the frequency does not move
    (a fold), NaN for fewer than two points."""
    f = np.log(np.asarray(frequency, dtype=float))
    a = np.log(np.maximum(np.asarray(amplitude, dtype=float), 1e-300))
    if len(f) < 2:
        return np.full(len(f), np.nan)
    df, da = np.gradient(f), np.gradient(a)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = da / df
    s[(df == 0) & (da == 0)] = 0.0
    return s


def response_to_tolerance(model, excitation, frequency_range, tol: float, *, start_harmonics: int,
                          max_harmonics: int, patience: int, contraction: float, method: str, run,
                          make_problem, **kwargs):
    """The forced response of ``model`` with every point's estimated relative error at
    most ``tol`` where it can be had (module docstring).

    Parameters
    ----------
    model : Model
    excitation : Excitation
    frequency_range : (float, float)
        Hz.
    tol : float
        Relative tolerance on each point's amplitude at its frequency, or its frequency at
        its amplitude near the folds (module docstring).
    start_harmonics, max_harmonics, patience, contraction
        As in :func:`mmshbm.methods.adaptive.backbone_to_tolerance`.
    method : str
        One of :data:`FORCED_TOLERANCE_METHODS`.
    run : callable
        ``run(model, excitation, frequency_range, harmonics=H, method=method, **kwargs)``
        -> FrequencyResponse: the fixed-H response.
    make_problem : callable
        ``make_problem(model, excitation, method, H, options)`` -> the forced problem at H
        (:func:`mmshbm.methods.frequency_response.make_forced_problem`), passed in so that
        this module does not import its caller.

    Returns
    -------
    FrequencyResponse
        With ``records["amplitude_error"]``, ``records["frequency_error"]``,
        ``records["harmonics"]``, ``records["error_pinned"]`` (0: the frequency pinned,
        1: the amplitude) and ``metadata["tolerance"]``.
    """
    from .._threads import blas_limit
    from ..core.pinned import solve_at_amplitude
    from .tolerance_ladder import solve_at_frequency

    t0 = time.perf_counter()
    with warnings.catch_warnings():  # the start H's findings are not the result's
        warnings.simplefilter("ignore")
        base = run(model, excitation, frequency_range, harmonics=start_harmonics, method=method, **kwargs)
    options = {k: v for k, v in dict(base.metadata.get("method_options", {})).items() if k != "harmonics"}

    def build(H, stability=False):
        try:
            return make_problem(model, excitation, method, H, {**options, "stability": stability})
        except TypeError:  # a problem without Floquet multipliers
            return make_problem(model, excitation, method, H, options)

    quick = DampedLadder(build)
    full = DampedLadder(lambda H: make_problem(model, excitation, method, H, options), base.solver)
    n = len(base)
    slope = path_slope(base.frequency, base.amplitude)
    pin_amplitude = ~(np.abs(slope) <= PIN_SLOPE)  # NaN (a single point): the amplitude

    def pinned_solver(i, a):
        if pin_amplitude[i]:
            return lambda s, start, it: solve_at_amplitude(AmplitudePinned(s), start, a, tol=1e-10,
                                                           max_iter=it)[0]
        return lambda s, start, it: solve_at_frequency(s, start, tol=1e-10, max_iter=it)

    def estimate(idx, H, states):
        mons = [quick.at(h).monitor(u) for h, u in zip(H, states, strict=True)]
        raised: list = [None] * len(idx)
        for j, (i, h, u) in enumerate(zip(idx, H, states, strict=True)):
            if _usable(mons[j]):
                try:
                    raised[j] = raise_H(quick, h, u, 2 * h, pinned_solver(i, float(mons[j]["amplitude"])))
                except _FAILURES:
                    pass
        _from_neighbours(quick, idx, H, states, mons, raised, pinned_solver)
        out = []
        for j, (i, h) in enumerate(zip(idx, H, strict=True)):
            if raised[j] is None:
                out.append(({"error": math.nan}, None, 2 * h))
                continue
            m2 = quick.at(2 * h).monitor(raised[j])
            key = "frequency" if pin_amplitude[i] else "amplitude"
            ref, new = float(mons[j][key]), float(m2[key])
            out.append(({"error": FACTOR * abs(new - ref) / abs(new)}, raised[j], 2 * h))
        return out

    with blas_limit():
        ref = refine_points(list(base.states), start_harmonics, estimate, tol=tol,
                            max_harmonics=max_harmonics, patience=patience, contraction=contraction)
    settings = {"tol": float(tol), "start_harmonics": start_harmonics, "max_harmonics": max_harmonics,
                "patience": patience, "contraction": float(contraction), "rate": 2.0, "levels": ref.levels,
                "pin_slope": PIN_SLOPE, "elapsed_s": time.perf_counter() - t0}
    err = ref.error
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.abs(slope)
        amp_err = np.where(pin_amplitude, err * s, err)
        freq_err = np.where(pin_amplitude, err, err / s)
    return _assemble(base, full, ref, n, {"amplitude_error": amp_err, "frequency_error": freq_err,
                                          "error_pinned": pin_amplitude.astype(np.int8)}, settings)


def _usable(mon: dict) -> bool:
    f, a = float(mon["frequency"]), float(mon["amplitude"])
    return a > 0 and math.isfinite(a) and math.isfinite(f)


def _from_neighbours(ladder, idx, H, states, mons, raised, pinned_solver) -> None:
    """Where a point's own coefficients are no start for its 2H solve (the H point is far
    from the 2H response, before the asymptotic regime in H), start it from a neighbour
    on the path already solved at the same 2H, at this point's frequency: sweeps forward,
    then backward, over the points of ``idx`` (in path order), filling ``raised``."""
    for order in (range(len(idx)), range(len(idx) - 1, -1, -1)):
        prev = None
        for j in order:
            if raised[j] is not None:
                prev = j
                continue
            if prev is None or H[prev] != H[j] or abs(int(idx[prev]) - int(idx[j])) > NEIGHBOURS \
                    or not _usable(mons[j]):
                continue
            start = np.array(raised[prev], dtype=float)
            start[-1] = states[j][-1]  # this point's Ω (the scaled Ω does not depend on H)
            try:
                raised[j] = pinned_solver(int(idx[j]), float(mons[j]["amplitude"]))(
                    ladder.at(2 * int(H[j])), start, 40)
                prev = j
            except _FAILURES:
                pass


def _assemble(base, full, ref, n: int, errors: dict, settings: dict):
    """The response at the largest H kept, every point's unknowns its own padded to it."""
    from ..results.response import FrequencyResponse
    from ..results.response_tolerance import response_tolerance_findings

    H = ref.harmonics
    start = int(settings["start_harmonics"])
    H_top = int(H.max()) if n else start
    top = full.at(H_top)
    rec = {k: np.array(v, copy=True) for k, v in base.records.items()}
    cols = {k: np.array(getattr(base, k), copy=True) for k in (
        "frequency", "amplitude", "phase", "energy", "contact_force_max", "floquet_max")}
    stable = np.array(base.stable, dtype=bool, copy=True)
    states = np.empty((n, top.n_unknowns))
    for i in range(n):
        own = full.at(int(H[i]))
        states[i] = pad_damped(own, ref.states[i], top) if int(H[i]) != H_top else ref.states[i]
        if int(H[i]) != start:
            mon = own.monitor(ref.states[i])
            for k in cols:
                if k in mon:
                    cols[k][i] = mon[k]
            if "stable" in mon:
                stable[i] = bool(mon["stable"])
            for k, v in mon.items():
                if k in rec and np.shape(rec[k][i]) == np.shape(v):
                    rec[k][i] = v
    rec.update(errors)
    rec["harmonics"] = H.astype(np.int64)
    rec["error_extrapolated"] = ref.extrapolated
    meta = dict(base.metadata)
    meta.update(harmonics=H_top, n_samples=int(top.N), tolerance=settings)
    resp = FrequencyResponse(
        stable=stable, newton_iterations=base.newton_iterations, step_size=base.step_size, states=states,
        status=base.status, method=base.method, harmonics=H_top, special_points=list(base.special_points),
        metadata=meta, solver=top, residual_histories=base.residual_histories, model=base.model, records=rec,
        **cols)
    found = response_tolerance_findings(resp)
    meta["checks"] = [f.to_dict() for f in found]
    for f in found:
        warnings.warn(f.message, BranchWarning, stacklevel=4)
    return resp
