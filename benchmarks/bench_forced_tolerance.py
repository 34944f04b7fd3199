"""Forced responses and damped modes to a tolerance against a fixed H.

* ``ForcedTolerance``: the forced impact oscillator (k2/k1 = 4, ζ = 2 %, F = 0.1 N,
  0.1–0.3 Hz) with ``tol`` = 1e-3 and 1e-4 against fixed H = 8 (the start H) and H = 32;
  tracked: the largest true amplitude error, at the points whose frequency was pinned,
  against the exact event-driven forced orbit.
* ``DampedModeTolerance``: the damped mode (EPMC) of that oscillator to 4 gaps, ``tol`` =
  1e-4 against fixed H = 8.
"""

from __future__ import annotations

import functools
import warnings

import numpy as np

F = (0.1, 0.0)
RANGE = (0.1, 0.3)


@functools.cache
def oscillator():
    import mmshbm

    return mmshbm.OneDofOscillator(1, 1, 4, 1).model().with_damping(modal_ratio=0.02)


def _response(**kwargs):
    import mmshbm

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return mmshbm.frequency_response(oscillator(), np.array(F), RANGE, **kwargs)


class ForcedTolerance:
    params = [["tol=1e-3", "tol=1e-4", "H=8", "H=32"]]
    param_names = ["accuracy"]
    timeout = 600

    def setup(self, accuracy):
        _response(harmonics=8)  # compiled kernels

    def _kwargs(self, accuracy):
        name, value = accuracy.split("=")
        return {"tol": float(value)} if name == "tol" else {"harmonics": int(value)}

    def time_response(self, accuracy):
        _response(**self._kwargs(accuracy))

    def track_true_amplitude_error(self, accuracy):
        from mmshbm.methods.exact.forced import forced_orbit

        resp = _response(**self._kwargs(accuracy))
        pinned = resp.records.get("error_pinned", np.zeros(len(resp), dtype=np.int8))
        worst = 0.0
        for i in np.flatnonzero(pinned == 0):
            Q = resp.solver.coefficients(resp.states[i])
            H = (Q.shape[1] - 1) // 2
            omega = 2 * np.pi * resp.frequency[i]
            guess = np.array([Q[0, 0] + Q[0, 1::2].sum(), omega * (np.arange(1, H + 1) * Q[0, 2::2]).sum()])
            o = forced_orbit(oscillator(), np.array(F), resp.frequency[i], guess=guess)
            if o.converged:
                worst = max(worst, abs(resp.amplitude[i] / o.amplitude() - 1))
        return worst

    track_true_amplitude_error.unit = "relative"


class DampedModeTolerance:
    params = [["tol=1e-4", "H=8"]]
    param_names = ["accuracy"]
    timeout = 600

    def time_backbone(self, accuracy):
        import mmshbm

        name, value = accuracy.split("=")
        kwargs = {"tol": float(value)} if name == "tol" else {"harmonics": int(value)}
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            mmshbm.backbone(oscillator(), max_amplitude=4.0, **kwargs)
