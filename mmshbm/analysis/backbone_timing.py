"""Whole backbones as the benchmarks time them: a method's options applied to a model,
the fastest of several runs with its peak memory, and the frequency a branch reached at
an amplitude (:mod:`mmshbm.analysis.benchmarking`, :mod:`mmshbm.analysis.element_scaling`)."""

from __future__ import annotations

import math
import time
import tracemalloc

import numpy as np

__all__ = ["REACH_RTOL", "backbone_with", "measure", "reached_frequency"]


def backbone_with(model, method: str, amplitude: float, options: dict):
    """``mmshbm.backbone`` of ``model`` by ``method`` to ``amplitude`` (m) with the benchmark's
    ``options`` (``harmonics``, ``penalty_factor`` times the condensed contact stiffness,
    and any option of the method)."""
    import mmshbm

    opts = dict(options)
    harmonics = opts.pop("harmonics", 5)
    factor = opts.pop("penalty_factor", None)
    if factor is not None:
        from ..methods.penalty.defaults import _condensed_contact_stiffness

        opts["penalty_stiffness"] = factor * _condensed_contact_stiffness(model)
    return mmshbm.backbone(model, harmonics=harmonics, method=method, max_amplitude=amplitude, **opts)


#: a branch "reaches" an amplitude when it gets this close (relative): the continuation
#: refines its last point onto the amplitude bound only to a few 1e-9
REACH_RTOL = 1e-6


def reached_frequency(branch, amplitude: float) -> float:
    """Frequency (Hz) at ``amplitude`` if the branch reached it, else NaN.

    Within :data:`REACH_RTOL` of the amplitude (a bound refined to a few 1e-9, which
    ``Branch.frequency_at`` does not accept), the frequency of the point of largest
    amplitude (the error is the backbone's slope times that offset: far below any target).
    """
    if len(branch) == 0:
        return math.nan
    top = int(np.nanargmax(branch.amplitude))
    if not branch.amplitude[top] >= amplitude * (1 - REACH_RTOL):
        return math.nan
    import warnings

    from .._warnings import BranchWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BranchWarning)  # just past the end the top point answers
        f = float(branch.frequency_at(amplitude))
    return f if math.isfinite(f) else float(branch.frequency[top])


def measure(model, method, amplitude, options, repeats):
    """(fastest time (s) of ``repeats`` whole backbones, peak tracemalloc MiB, last branch)."""
    best, branch = math.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        branch = backbone_with(model, method, amplitude, options)
        best = min(best, time.perf_counter() - t0)
    tracemalloc.start()
    try:
        backbone_with(model, method, amplitude, options)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return best, peak / 2**20, branch
