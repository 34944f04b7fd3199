"""``mmshbm.backbone``: one entry point for every method."""

from __future__ import annotations

import dataclasses
import importlib
import logging
import platform
import time

import numpy as np

from . import _validate as check
from .continuation import ContinuationOptions, continue_branch
from .model import Model
from .results import Branch

__all__ = ["backbone", "METHODS", "make_problem"]

log = logging.getLogger(__name__)

#: method name -> "module:class" of its continuation problem
METHODS = {
    "mmshbm": "mmshbm.mms_hbm:MMSHBMProblem",
    "penalty": "mmshbm.baselines.penalty_hbm:PenaltyHBMProblem",
    "shooting": "mmshbm.baselines.shooting:ShootingProblem",
}

_CONTINUATION_FIELDS = {f.name for f in dataclasses.fields(ContinuationOptions)}


def make_problem(model: Model, method: str = "mmshbm", **options):
    """Build the continuation problem of ``method`` on ``model`` (``options`` go to its
    constructor)."""
    if not isinstance(method, str) or method not in METHODS:
        raise ValueError(f"unknown method {method!r}; choose one of {sorted(METHODS)}")
    module, cls = METHODS[method].split(":")
    try:
        problem_class = getattr(importlib.import_module(module), cls)
    except ImportError as err:  # pragma: no cover - a baseline not installed
        raise ValueError(f"method {method!r} is not available: {err}") from None
    return problem_class(model, **options)


def backbone(model: Model, harmonics: int = 5, method: str = "mmshbm", max_amplitude: float | None = None,
             *, start_amplitude: float | None = None, bounds: dict | None = None, verbose: bool = False,
             callback=None, **options) -> Branch:
    """Compute a nonlinear mode (backbone curve) of ``model``.

    Parameters
    ----------
    model : Model
        The structure, e.g. ``mmshbm.default_beam().model(21)``.
    harmonics : int
        Highest harmonic H of the Fourier ansatz (harmonic-balance methods).
    method : {"mmshbm", "penalty", "shooting"}
        MMS-HBM, or one of the baselines.
    max_amplitude : float, optional
        Stop at this amplitude (m) of the contact DOF; default 10 gaps.
    start_amplitude : float, optional
        Amplitude (m) of the first point, on the linear mode; default half the gap.
    bounds : dict, optional
        Further bounds on recorded quantities, e.g. ``{"frequency": (0, 60)}`` (Hz),
        ``{"energy": (0, 1.0)}`` (J).
    verbose : bool
        Show a progress bar (tqdm) with Ω, amplitude, ds and Newton iterations.
    callback : callable(u, record), optional
        Called with every converged point.
    **options
        Continuation options (:class:`ContinuationOptions`: ``ds``, ``ds_min``,
        ``ds_max``, ``max_steps``, ``newton_tol``, ``max_newton``, ...) and method options
        (MMS-HBM: ``n_samples``, ``r``, ``mode``, ``backend``; penalty:
        ``penalty_stiffness``; shooting: ``steps_per_period``).

    Returns
    -------
    Branch
        Every converged point, with ``status`` saying why the branch stopped.
    """
    if not isinstance(model, Model):
        raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
    gap = model.gap
    if max_amplitude is None:
        if gap == 0:
            raise ValueError("the model's gap is 0: pass max_amplitude (m)")
        max_amplitude = 10.0 * gap
    max_amplitude = check.positive("max_amplitude", max_amplitude)
    if start_amplitude is None:
        start_amplitude = 0.5 * gap if gap > 0 else 0.01 * max_amplitude
    start_amplitude = check.positive("start_amplitude", start_amplitude)
    if start_amplitude >= max_amplitude:
        raise ValueError(f"start_amplitude ({start_amplitude:g} m) must be below max_amplitude "
                         f"({max_amplitude:g} m)")
    cont = {k: options.pop(k) for k in list(options) if k in _CONTINUATION_FIELDS}
    all_bounds = {"amplitude": (0.0, max_amplitude)}
    for name, bound in dict(bounds or {}).items():
        all_bounds[name] = bound
    cont["bounds"] = {**all_bounds, **dict(cont.get("bounds", {}))}
    copts = ContinuationOptions(**cont)
    if method != "shooting":
        options["harmonics"] = harmonics
    problem = make_problem(model, method, **options)

    progress = None
    if verbose:
        from tqdm.auto import tqdm

        progress = tqdm(desc=f"{method} backbone", unit="pt", total=copts.max_steps + 1, leave=False)
    t0 = time.perf_counter()
    try:
        res = continue_branch(problem, problem.linear_point(start_amplitude), problem.initial_tangent(),
                              copts, callback=callback, progress=progress)
    finally:
        if progress is not None:
            progress.close()
    elapsed = time.perf_counter() - t0
    rec = res.records
    n = len(res.u)

    def column(name):
        return rec[name] if name in rec else np.full(n, np.nan)

    special = list(res.special_points)
    amp = column("amplitude")
    if gap > 0:
        above = np.flatnonzero(amp > gap * (1 + 1e-9))
        if len(above) and above[0] > 0:
            special.insert(1, ("grazing", int(above[0])))
    log.info("%s backbone: %d points, status %s, %.3f s", method, n, res.status, elapsed)
    return Branch(
        frequency=column("frequency"), amplitude=amp, energy=column("energy"),
        contact_force_max=column("contact_force_max"), newton_iterations=res.newton_iterations,
        step_size=res.step_size, states=res.u, status=res.status, method=method,
        harmonics=int(getattr(problem, "H", 0)), special_points=special,
        metadata={
            "model": model.description, "method": method, "harmonics": int(getattr(problem, "H", 0)),
            "n_samples": int(getattr(problem, "N", 0)), "max_amplitude": max_amplitude,
            "start_amplitude": start_amplitude, "method_options": _jsonable(options),
            "continuation": _jsonable(dataclasses.asdict(copts)), "elapsed_s": elapsed,
            "python": platform.python_version(), "numpy": np.__version__,
        },
        solver=problem, residual_histories=res.residual_histories)


def _jsonable(d: dict) -> dict:
    out = {}
    for k, v in d.items():
        if isinstance(v, dict):
            out[k] = _jsonable(v)
        elif isinstance(v, tuple | list):
            out[k] = [float(x) if isinstance(x, int | float | np.number) else x for x in v]
        elif isinstance(v, np.generic):
            out[k] = v.item()
        else:
            out[k] = v
    return out
