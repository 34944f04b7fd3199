"""Studies: the convergence grid in H and elements and the study throughput.

- :class:`ReducedGrid`: the time of a small grid (H 5, 7 x 8, 21 elements to 10 gaps, in
  this process): the cost of backbones through internal-resonance tongues.
- :class:`ConvergenceGrid`: the whole grid of ``mmshbm study -H 1 3 5 7 9 11 15
  --elements 8 21 40 100 200`` (to 10 gaps), computed once in ``setup_cache`` through a
  process pool of 2 workers; tracks its wall time and, per cell, points, jumps, the
  amplitude the family front skips and f at 10 gaps (the numbers docs/validation.md quotes).
- :class:`StudyThroughput`: a Monte-Carlo study of 200 backbones (8 elements, H = 3, gap,
  E and ρ drawn) serially and through a warm process pool and Dask cluster of 2 workers:
  backbones per second, parallel efficiency serial / (workers x parallel) and the share
  of the workers' time spent inside tasks. ``python -m validation throughput 1000`` gives the
  issue's full figure.

Wall-clock figures depend on the machine's load; compare ratios within one run.
"""

from __future__ import annotations

import warnings

from benchmarks.common import warm_up

#: the convergence grid: H x elements
GRID_H = (1, 3, 5, 7, 9, 11, 15)
GRID_ELEMENTS = (8, 21, 40, 100, 200)


def _quiet():
    from mmshbm import BranchWarning

    warnings.simplefilter("ignore", BranchWarning)


class ReducedGrid:
    """H 5, 7 x 8, 21 elements to 10 gaps, serial (each H >= 5 run passes the 5:2 tongue,
    H 7 also the 6:2 one)."""

    number = 1
    repeat = (1, 3, 60.0)
    warmup_time = 0.0
    timeout = 300

    def setup(self):
        _quiet()
        warm_up("mmshbm")

    def time_reduced_grid(self):
        from mmshbm.analysis import studies

        studies.run_study(harmonics=(5, 7), elements=(8, 21), max_amplitude=10.0, unit="gap",
                          executor="serial")


class ConvergenceGrid:
    """The convergence grid, once per asv run (about 20-40 s on 2 cores)."""

    params = [GRID_H, GRID_ELEMENTS]
    param_names = ["H", "elements"]
    timeout = 900

    def setup_cache(self):
        from mmshbm.analysis import studies
        from mmshbm.analysis.skips import cell_summary

        _quiet()
        study = studies.run_study(harmonics=GRID_H, elements=GRID_ELEMENTS, max_amplitude=10.0, unit="gap",
                                  executor="process", workers=2)
        cells = {}
        for r, b in study:
            c = cell_summary(b)
            cells[(r["harmonics"], r["elements"])] = {
                "points": c["points"], "jumps": c["jumps"], "skipped": c["skipped_total"],
                "f10": b.frequency_at(10.0 * b.gap), "completed": b.completed}
        return {"wall_s": study.metadata["elapsed_s"], "cells": cells}

    def track_grid_wall_time(self, cache, H, elements):
        return cache["wall_s"]

    track_grid_wall_time.unit = "s (whole grid, 2 workers)"

    def track_points(self, cache, H, elements):
        return cache["cells"][(H, elements)]["points"]

    track_points.unit = "points"

    def track_jumps(self, cache, H, elements):
        return cache["cells"][(H, elements)]["jumps"]

    track_jumps.unit = "jumps"

    def track_skipped_gaps(self, cache, H, elements):
        return cache["cells"][(H, elements)]["skipped"]

    track_skipped_gaps.unit = "gaps skipped by the family front"

    def track_frequency_at_10_gaps(self, cache, H, elements):
        return cache["cells"][(H, elements)]["f10"]

    track_frequency_at_10_gaps.unit = "Hz"


class StudyThroughput:
    """200 Monte-Carlo backbones (8 elements, H = 3, to 10 gaps) on 2 workers, warm executors."""

    params = [("serial", "process", "dask")]
    param_names = ["executor"]
    timeout = 900

    def setup_cache(self):
        from validation.throughput import measure_throughput

        _quiet()
        try:
            import dask.distributed  # noqa: F401

            executors = ("process", "dask")
        except ImportError:
            executors = ("process",)
        result = measure_throughput(200, harmonics=3, elements=8, workers=2, executors=executors, cold=False)
        return {r.executor: (r.backbones_per_s, r.efficiency, r.busy, r.identical) for r in result.runs}

    def setup(self, cache, executor):
        if executor not in cache:
            raise NotImplementedError(f"{executor} is not available (pip install 'mmshbm[dask]')")

    def track_backbones_per_second(self, cache, executor):
        return cache[executor][0]

    track_backbones_per_second.unit = "backbones/s"

    def track_parallel_efficiency(self, cache, executor):
        return cache[executor][1]

    track_parallel_efficiency.unit = "serial / (workers x parallel)"

    def track_busy_share(self, cache, executor):
        return cache[executor][2]

    track_busy_share.unit = "time in tasks / (workers x wall)"

    def track_identical_numbers(self, cache, executor):
        return float(cache[executor][3])

    track_identical_numbers.unit = "1 = bit-identical to serial"
