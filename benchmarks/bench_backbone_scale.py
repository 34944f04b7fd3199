"""The whole backbone after the reduction against the size of the FE model (docs/scale.md).

* ``BackboneScale``: the default backbone (H = 5) on 21, 1000 and 10 000 elements, its
  reduction done (and cached) by the first call in ``setup``, to 1.9 gaps (31 points on
  every mesh) and to 2 gaps (33 points; from 1000 elements the family guard tries a jump
  over the 5:1 tongue at 1.97 gaps there: 13 pinned solves and ~980 residual evaluations
  that the 21-element run does not make).
* ``BackboneScaleRatios``: 10 000 / 21 elements of both, measured alternately in one
  process (goal <= 1.5 for the same points and the same work per point).
"""

from __future__ import annotations

import timeit

import numpy as np

#: beam sizes (elements)
SCALE_ELEMENTS = (21, 1000, 10000)


def _backbone_run(elements: int, gaps: float):
    """A callable running the default backbone to ``gaps`` (its reduction done here)."""
    import warnings

    import mmshbm

    model = mmshbm.default_beam().model(elements)

    def run():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", mmshbm.BranchWarning)
            return mmshbm.backbone(model, harmonics=5, max_amplitude=gaps * model.gap)

    run()
    return run


def _backbone_ratio(gaps: float) -> float:
    small, large = _backbone_run(21, gaps), _backbone_run(10000, gaps)
    t_small = t_large = np.inf
    for _ in range(7):  # alternated, fastest of each
        t_small = min(t_small, min(timeit.repeat(small, number=3, repeat=1)) / 3)
        t_large = min(t_large, min(timeit.repeat(large, number=3, repeat=1)) / 3)
    return t_large / t_small


class BackboneScale:
    """The whole default backbone (H = 5) on growing beams, after the reduction."""

    params = [SCALE_ELEMENTS, (1.9, 2.0)]
    param_names = ["elements", "gaps"]
    timeout = 300

    def setup(self, elements, gaps):
        from benchmarks.common import warm_up

        warm_up("mmshbm")
        self.run = _backbone_run(elements, gaps)

    def time_backbone(self, elements, gaps):
        self.run()

    def track_points(self, elements, gaps):
        return len(self.run())


class BackboneScaleRatios:
    """The whole backbone on 10 000 / 21 elements, in one process."""

    timeout = 600

    def setup(self):
        from benchmarks.common import warm_up

        warm_up("mmshbm")

    def track_backbone_10000_over_21(self):
        """To 1.9 gaps, the same 31 points on both (goal <= 1.5)."""
        return _backbone_ratio(1.9)

    track_backbone_10000_over_21.unit = "ratio"

    def track_backbone_2_gaps_10000_over_21(self):
        """To 2 gaps (the 10 000-element run also tries a family jump)."""
        return _backbone_ratio(2.0)

    track_backbone_2_gaps_10000_over_21.unit = "ratio"
