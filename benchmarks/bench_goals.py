"""The figures of the speed goals, tracked per commit.

* ``DefaultBackbone``: the README's main job, the default beam (21 elements, H = 5) to
  10 gaps, warm: time, residual + Jacobian evaluations per point, the branch checks.
* ``WholeProcess``: ``mmshbm backbone`` as a subprocess, warm (Numba's cache in place)
  and cold (a fresh ``NUMBA_CACHE_DIR``: every kernel compiled, or, as after an
  installation, seeded from the kernels the package carries), figures drawn in a child
  process or not.
* ``EqualAccuracy``: ``mmshbm bench`` (:func:`mmshbm.analysis.benchmarking.compare_methods`)
  on the one-DOF oscillator (2 gaps, closed-form reference: equal accuracy) and on the
  default beam (1.5 gaps, equal H): every column of its table as a ``track_``.

The study throughput (1000 backbones) is tracked in ``bench_studies.py``. The benchmark
tables of docs/validation.md and docs/benchmarks.md are generated from one recorded run of this
suite: ``python -m validation tables`` prints them, ``python -m validation tables --update
docs/validation.md docs/benchmarks.md`` rewrites them from the run recorded in
``benchmarks/results`` (docs/benchmarks.md, "Record the tables").
"""

from __future__ import annotations

import math
import os
import time

from benchmarks.common import model, warm_up

#: the README's main job
MAIN_JOB = {"name": "beam21", "harmonics": 5, "max_amplitude_gaps": 10.0}


def _main_job():
    import warnings

    import mmshbm

    m = model(MAIN_JOB["name"])
    with warnings.catch_warnings():  # its findings (BranchWarning) are known; keep asv's log readable
        warnings.simplefilter("ignore", mmshbm.BranchWarning)
        return mmshbm.backbone(m, harmonics=MAIN_JOB["harmonics"],
                               max_amplitude=MAIN_JOB["max_amplitude_gaps"] * m.gap)


def count_evaluations(run):
    """(branch, residual evaluations) of ``run()``: the count the problem keeps
    (``solver.evaluations``, the compiled corrector's included) when it has one, else
    the calls of the problem's ``evaluate`` (residual, with or without the Jacobian)."""
    from mmshbm.methods.mms.conservative import MMSHBMProblem

    original = MMSHBMProblem.evaluate
    calls = [0]

    def counted(self, *args, **kwargs):
        calls[0] += 1
        return original(self, *args, **kwargs)

    MMSHBMProblem.evaluate = counted
    try:
        branch = run()
    finally:
        MMSHBMProblem.evaluate = original
    kept = getattr(branch.solver, "evaluations", None)
    return branch, int(calls[0] if kept is None else kept)


class DefaultBackbone:
    """Default beam, 21 elements, H = 5, from half a gap to 10 gaps, kernels compiled."""

    number = 1
    repeat = (5, 20, 20.0)
    warmup_time = 0.0
    timeout = 300

    def setup(self):
        warm_up("mmshbm")
        self.branch = _main_job()

    def time_backbone_to_10_gaps(self):
        _main_job()

    def track_evaluations_per_point(self):
        _, n = count_evaluations(_main_job)
        return n / len(self.branch)

    track_evaluations_per_point.unit = "evaluations/point"

    def track_points(self):
        return len(self.branch)

    track_points.unit = "points"

    def time_branch_checks(self):
        self.branch.check(warn=False)


class WholeProcess:
    """``mmshbm backbone`` (the README's main job: CSV, npz, two PNGs) as a whole
    process; ``plot_worker`` is ``MMSHBM_PLOT_WORKER`` (1: figures drawn by a child that
    imports matplotlib meanwhile, 0: in the process)."""

    params = [["1", "0"]]
    param_names = ["plot_worker"]
    timeout = 600

    def setup(self, plot_worker):
        from benchmarks.profile_startup import whole_process

        self.env = dict(os.environ, OPENBLAS_NUM_THREADS="1", MMSHBM_PLOT_WORKER=plot_worker)
        whole_process([], 1, cold=False, env=self.env)  # Numba's cache in place

    def track_warm_s(self, plot_worker):
        from benchmarks.profile_startup import whole_process

        return min(whole_process([], 3, cold=False, env=self.env))

    track_warm_s.unit = "s"

    def track_cold_s(self, plot_worker):
        """A fresh NUMBA_CACHE_DIR, not seeded: every kernel of the main job compiles."""
        from benchmarks.profile_startup import whole_process

        return min(whole_process([], 1, cold=True, env=self.env))

    track_cold_s.unit = "s"

    def track_first_run_s(self, plot_worker):
        """The first run after an installation: a fresh NUMBA_CACHE_DIR, seeded from the
        kernels that the installed package carries compiled (its build step, setup.py)."""
        from benchmarks.profile_startup import whole_process

        return min(whole_process([], 1, cold=True, env=self.env, seed=True))

    track_first_run_s.unit = "s"


#: the models and methods of ``mmshbm bench`` tracked here
BENCH_MODELS = ("oscillator", "beam21")
BENCH_METHODS = ("mmshbm", "penalty", "shooting")


class EqualAccuracy:
    """``mmshbm bench``: each method tuned to 1e-4 relative frequency error (the oscillator
    against its closed form at 2 gaps; the beam at equal H against MMS-HBM with N = 1024
    at 1.5 gaps), then its whole backbone timed (fastest of 3). The tuning runs once, in
    ``setup_cache``; every column of the table is a ``track_``."""

    params = [list(BENCH_MODELS), list(BENCH_METHODS)]
    param_names = ["model", "method"]
    timeout = 120

    def setup_cache(self):
        import warnings

        from mmshbm.analysis.benchmarking import compare_methods

        started = time.perf_counter()
        out = {}
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            for name in BENCH_MODELS:
                out[name] = {r["method"]: r for r in compare_methods(name, methods=BENCH_METHODS)}
        out["_seconds"] = time.perf_counter() - started
        return out

    setup_cache.timeout = 3600

    def _row(self, rows, name, method):
        row = rows[name].get(method)
        if row is None:
            raise NotImplementedError(f"{method} did not run on {name}")
        return row

    def track_time_ms(self, rows, name, method):
        return 1e3 * self._row(rows, name, method)["time_s"]

    track_time_ms.unit = "ms"

    def track_time_ratio(self, rows, name, method):
        """Time over MMS-HBM's time in the same run."""
        return self._row(rows, name, method)["time_ratio"]

    track_time_ratio.unit = "x MMS-HBM"

    def track_rel_error(self, rows, name, method):
        return self._row(rows, name, method)["error"]

    track_rel_error.unit = "relative"

    def track_target_met(self, rows, name, method):
        return float(self._row(rows, name, method)["target_met"])

    track_target_met.unit = "1 = yes"

    def track_frequency_hz(self, rows, name, method):
        return self._row(rows, name, method)["frequency_hz"]

    track_frequency_hz.unit = "Hz"

    def track_reference_hz(self, rows, name, method):
        return self._row(rows, name, method)["reference_hz"]

    track_reference_hz.unit = "Hz"

    def track_amplitude_gaps(self, rows, name, method):
        return self._row(rows, name, method)["amplitude_gaps"]

    track_amplitude_gaps.unit = "gaps"

    def track_newton_iterations(self, rows, name, method):
        return self._row(rows, name, method)["newton_iterations"]

    track_newton_iterations.unit = "iterations"

    def track_unknowns(self, rows, name, method):
        return self._row(rows, name, method)["unknowns"]

    track_unknowns.unit = "unknowns"

    def track_peak_memory_mib(self, rows, name, method):
        return self._row(rows, name, method)["peak_memory_mib"]

    track_peak_memory_mib.unit = "MiB"

    def track_harmonics(self, rows, name, method):
        """The chosen setting: H (0 for shooting)."""
        return self._row(rows, name, method)["harmonics"]

    track_harmonics.unit = "H"

    def track_penalty_factor(self, rows, name, method):
        """The chosen setting: k_p / k_c (NaN but for penalty-HBM)."""
        value = self._row(rows, name, method)["penalty_factor"]
        return value if value is not None and math.isfinite(value) else math.nan

    track_penalty_factor.unit = "k_p/k_c"

    def track_samples(self, rows, name, method):
        """The chosen setting: N of MMS-HBM when tuned in N (0: the default), shooting's
        steps per period."""
        row = self._row(rows, name, method)
        if method == "shooting":
            return row["steps_per_period"]
        return row.get("n_samples", 0)

    track_samples.unit = "N"
