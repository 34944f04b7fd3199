"""Whole backbones from half a gap up to 2 gaps: time and peak memory.

MMS-HBM and penalty-HBM over H on the one-DOF oscillator and the default beam (8 and 21
elements), shooting over its time steps per period, and the cost against the number of
elements (8, 21, 100, 1000) for the harmonic-balance methods. Kernels are compiled in
``setup`` (a short backbone of the oscillator), so no sample contains compilation."""

from __future__ import annotations

from benchmarks.common import ELEMENTS, HARMONICS, MODELS, STEPS, backbone, beam_name, check_feasible, warm_up


class _Backbone:
    number = 1
    repeat = (1, 5, 30.0)
    warmup_time = 0.0
    timeout = 600


class HBMBackbone(_Backbone):
    """MMS-HBM and penalty-HBM on the small models, over H."""

    params = [("mmshbm", "penalty"), MODELS, HARMONICS]
    param_names = ["method", "model", "H"]

    def setup(self, method, name, H):
        check_feasible(name, method, H)
        warm_up(method)

    def time_backbone(self, method, name, H):
        backbone(name, method, H)

    def peakmem_backbone(self, method, name, H):
        backbone(name, method, H)


class ShootingBackbone(_Backbone):
    """Shooting on the small models, over the time steps per period."""

    params = [MODELS, STEPS]
    param_names = ["model", "steps"]

    def setup(self, name, steps):
        check_feasible(name, "shooting")
        warm_up("shooting")

    def time_backbone(self, name, steps):
        backbone(name, "shooting", steps=steps)

    def peakmem_backbone(self, name, steps):
        backbone(name, "shooting", steps=steps)


class ElementScaling(_Backbone):
    """Cost against the number of beam elements (MMS-HBM: about linear; see
    ``mmshbm.analysis.benchmarking.element_scaling`` for the fitted exponent)."""

    params = [("mmshbm", "penalty"), ELEMENTS, HARMONICS]
    param_names = ["method", "elements", "H"]

    def setup(self, method, elements, H):
        check_feasible(beam_name(elements), method, H)
        warm_up(method)

    def time_backbone(self, method, elements, H):
        backbone(beam_name(elements), method, H)

    def peakmem_backbone(self, method, elements, H):
        backbone(beam_name(elements), method, H)
