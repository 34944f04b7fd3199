"""MMS-HBM's proximal parameter: the default (static) r against ``r="residual"``.

A one-DOF oscillator whose massless contact node sits on a spring 887 times stiffer than
the structure (mass 2.0027 kg on 38.071 N/m, node spring 33749.83 N/m, stop 1 cm away):
the contact lasts ~2 % of the period, where the truncation of the series dominates.
``track_frequency_error`` is the relative error of ``frequency_at(1.3 gaps)`` against the
exact orbit (:func:`mmshbm.exact.periodic_orbit`, event-driven closed form);
``time_backbone`` the cost of the backbone to 1.56 gaps. Both rules solve the same
equations at the same H: the error per second compares them directly.
"""

from __future__ import annotations

import math

_RULES = ("static", "residual")
_HARMONICS = (15, 31, 62)


def _model():
    import numpy as np

    import mmshbm

    m, k, kc = 2.0027, 38.071, 33749.83
    return mmshbm.Model.from_matrices(np.diag([m, 0.0]), np.array([[k + kc, -kc], [-kc, kc]]), 1, 0.01, 1)


def _backbone(model, rule, H):
    import warnings

    import mmshbm

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return mmshbm.backbone(model, harmonics=H, max_amplitude=1.56 * model.gap, r=rule)


class ProximalParameter:
    params = [_RULES, _HARMONICS]
    param_names = ["r", "H"]
    timeout = 600

    def setup_cache(self):
        from mmshbm import exact

        model = _model()
        A = 1.3 * model.gap
        f_exact = float(exact.periodic_orbit(model, A).frequency)
        out = {}
        for rule in _RULES:
            for H in _HARMONICS:
                try:
                    f = float(_backbone(model, rule, H).frequency_at(A))
                except (TypeError, ValueError):  # a version without the rule
                    continue
                out[(rule, H)] = abs(f / f_exact - 1) if math.isfinite(f) else math.nan
        return out

    def setup(self, cache, rule, H):
        if (rule, H) not in cache:
            raise NotImplementedError(f"r={rule!r} is not available")
        self.model = _model()

    def track_frequency_error(self, cache, rule, H):
        return cache[(rule, H)]

    track_frequency_error.unit = "relative error"

    def time_backbone(self, cache, rule, H):
        _backbone(self.model, rule, H)
