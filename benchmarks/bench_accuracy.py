"""Tracked accuracy and effort of whole backbones (up to 2 gaps).

``track_frequency_error``: relative error of the frequency at 2 gaps against the closed
form (one-DOF oscillator) or, on the beam, against MMS-HBM at the same H with 1024
samples (the beam has no converged exact or high-H reference at 2 gaps: see
``benchmarks/common.py``). NaN (n/a) when the branch does not reach 2 gaps. Also the
total Newton iterations and the continuation steps of the branch.

Every backbone of a class is computed once, in ``setup_cache`` (one process), and the
three ``track_*`` read the numbers.
"""

from __future__ import annotations

import itertools
import math

from benchmarks.common import (
    AMPLITUDE_GAPS,
    HARMONICS,
    MODELS,
    STEPS,
    available,
    backbone,
    model,
    reference_frequency,
)

_METHODS = ("mmshbm", "penalty")


def _numbers(name, method, harmonics=None, steps=None) -> dict:
    from mmshbm.analysis.benchmarking import _reached_frequency

    m = model(name)
    branch = backbone(name, method, harmonics, steps)
    f = _reached_frequency(branch, AMPLITUDE_GAPS * m.gap)
    ref = reference_frequency(name, harmonics or 5)
    error = abs(f - ref) / ref if math.isfinite(f) and math.isfinite(ref) else math.nan
    return {"error": error, "newton_iterations": int(branch.newton_iterations.sum()),
            "continuation_steps": len(branch) - 1}


def _get(cache, key, what):
    if key not in cache:
        raise NotImplementedError(f"{key} not computed (method not available)")
    return cache[key][what]


class HBMAccuracy:
    params = [_METHODS, MODELS, HARMONICS]
    param_names = ["method", "model", "H"]
    timeout = 900

    def setup_cache(self):
        return {(method, name, H): _numbers(name, method, harmonics=H)
                for method, name, H in itertools.product(_METHODS, MODELS, HARMONICS)}

    def track_frequency_error(self, cache, method, name, H):
        return _get(cache, (method, name, H), "error")

    track_frequency_error.unit = "relative error"

    def track_newton_iterations(self, cache, method, name, H):
        return _get(cache, (method, name, H), "newton_iterations")

    track_newton_iterations.unit = "iterations"

    def track_continuation_steps(self, cache, method, name, H):
        return _get(cache, (method, name, H), "continuation_steps")

    track_continuation_steps.unit = "steps"


class ShootingAccuracy:
    """Shooting's error on the beam is measured against the H = 5 MMS-HBM number: it is
    the difference between the models (harmonic truncation), not a time-step error."""

    params = [MODELS, STEPS]
    param_names = ["model", "steps"]
    timeout = 900

    def setup_cache(self):
        if not available("shooting"):
            return {}
        return {(name, steps): _numbers(name, "shooting", steps=steps)
                for name, steps in itertools.product(MODELS, STEPS)}

    def track_frequency_error(self, cache, name, steps):
        return _get(cache, (name, steps), "error")

    track_frequency_error.unit = "relative error"

    def track_newton_iterations(self, cache, name, steps):
        return _get(cache, (name, steps), "newton_iterations")

    track_newton_iterations.unit = "iterations"

    def track_continuation_steps(self, cache, name, steps):
        return _get(cache, (name, steps), "continuation_steps")

    track_continuation_steps.unit = "steps"
