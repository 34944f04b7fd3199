"""Tracked accuracy and effort of whole backbones (up to 2 gaps).

``track_frequency_error``: relative error of the frequency at 2 gaps against the closed
form (one-DOF oscillator) or, on the beam, against MMS-HBM at the same H with 1024
samples (the beam has no converged exact or high-H reference at 2 gaps: see
``benchmarks/common.py``). NaN when the branch does not reach 2 gaps. Also the total
Newton iterations and the continuation steps of the branch."""

from __future__ import annotations

import math

from .common import (
    AMPLITUDE_GAPS,
    HARMONICS,
    MODELS,
    STEPS,
    backbone,
    check_feasible,
    model,
    reference_frequency,
)


def _accuracy_setup(self, name, method, harmonics=None, steps=None):
    from mmshbm.benchmarking import _reached_frequency

    check_feasible(name, method, harmonics)
    m = model(name)
    self.branch = backbone(name, method, harmonics, steps)
    f = _reached_frequency(self.branch, AMPLITUDE_GAPS * m.gap)
    ref = reference_frequency(name, harmonics or 5)
    self.error = abs(f - ref) / ref if math.isfinite(f) and math.isfinite(ref) else math.nan


class HBMAccuracy:
    params = [("mmshbm", "penalty"), MODELS, HARMONICS]
    param_names = ["method", "model", "H"]
    timeout = 600

    def setup(self, method, name, H):
        _accuracy_setup(self, name, method, harmonics=H)

    def track_frequency_error(self, method, name, H):
        return self.error

    track_frequency_error.unit = "relative error"

    def track_newton_iterations(self, method, name, H):
        return int(self.branch.newton_iterations.sum())

    track_newton_iterations.unit = "iterations"

    def track_continuation_steps(self, method, name, H):
        return len(self.branch) - 1

    track_continuation_steps.unit = "steps"


class ShootingAccuracy:
    """Shooting's error on the beam is measured against the H = 5 MMS-HBM number: it is
    the difference between the models (harmonic truncation), not a time-step error."""

    params = [MODELS, STEPS]
    param_names = ["model", "steps"]
    timeout = 600

    def setup(self, name, steps):
        _accuracy_setup(self, name, "shooting", steps=steps)

    def track_frequency_error(self, name, steps):
        return self.error

    track_frequency_error.unit = "relative error"

    def track_newton_iterations(self, name, steps):
        return int(self.branch.newton_iterations.sum())

    track_newton_iterations.unit = "iterations"

    def track_continuation_steps(self, name, steps):
        return len(self.branch) - 1

    track_continuation_steps.unit = "steps"
