"""Study throughput: backbones per second and parallel efficiency of a Monte-Carlo study.

:func:`measure_throughput` runs ``n`` backbones of a cheap model (the default beam with a
few elements and harmonics, gap, E and ρ drawn by :func:`~mmshbm.analysis.studies.monte_carlo`)
in this process (the serial reference), through a process pool and through a local Dask
cluster, and reports for each executor the wall time, backbones per second and the
parallel efficiency

    efficiency = serial time / (workers × parallel time),

both *cold* (the executor is opened inside the timing: worker processes start, import
mmshbm and load the compiled kernels from numba's cache) and *warm* (the executor was
opened and every worker ran one backbone before the timing, as a long-lived pool or
cluster is). It checks that every executor gives the serial numbers bit for bit, and
measures the overheads that belong to the study layer: the pickled size of a task and of
a result, and the time to pickle and unpickle one result.

Absolute figures depend on the machine and its load (``os.getloadavg()`` is recorded):
quote the ratios.
"""

from __future__ import annotations

import json
import logging
import os
import pickle
import time
import warnings
from dataclasses import asdict, dataclass, field
from pathlib import Path

from mmshbm import _validate as check

__all__ = ["ThroughputRun", "Throughput", "measure_throughput", "machine_ceiling", "DEFAULT_RANGES"]

log = logging.getLogger(__name__)

#: parameter ranges of the Monte-Carlo study (SI): gap 0.5–2 mm, E and ρ ±5 % around steel
DEFAULT_RANGES = {"gap": (0.5e-3, 2.0e-3), "E": (1.9e11, 2.1e11), "rho": (7.4e3, 8.2e3)}


@dataclass
class ThroughputRun:
    """One timed study.

    Attributes
    ----------
    executor : str
        "serial", "process" or "dask".
    warm : bool
        The executor was opened and its workers had run a backbone before the timing.
    workers, chunksize, tasks : int
    wall_s : float
        Wall time of :func:`~mmshbm.analysis.studies.run_study` (s), including opening
        the executor when cold.
    open_s : float
        Of which opening the executor (s; a Dask cluster's start; process pools start
        their workers lazily, so this is small and the start-up shows in ``wall_s``).
    identical : bool
        Every branch equals the serial one bit for bit (states, frequencies, status).
    backbones_per_s, efficiency : float
        n / wall_s, and serial_s / (workers × wall_s) (1 for the serial run).
    busy : float
        Share of the workers' time inside the tasks, busy_s / (workers × wall_s): what
        the executor leaves idle (start-up, scheduling, stragglers) is 1 − busy. Unlike
        the efficiency it does not fall when other processes share the cores (the tasks
        then take longer too).
    """

    executor: str
    warm: bool
    workers: int
    chunksize: int
    tasks: int
    wall_s: float
    open_s: float
    identical: bool
    backbones_per_s: float = 0.0
    efficiency: float = 1.0
    busy: float = 1.0


@dataclass
class Throughput:
    """The figures of :func:`measure_throughput`.

    Attributes
    ----------
    n : int
        Backbones per study.
    setup : dict
        Model, H, amplitude, parameter ranges, seed.
    serial_s : float
        Wall time of the serial study (s).
    runs : list of ThroughputRun
    overheads : dict
        ``task_bytes`` (pickled specs of one task), ``result_bytes`` (pickled branches of
        one task), ``pickle_ms_per_backbone`` (dumps + loads of one result in this process),
        ``per_backbone_ms`` (serial time / n).
    machine : dict
        ``cpu_count``, ``loadavg_before``/``_after`` (1, 5, 15 min) and
        ``ceiling_before``/``_after`` (:func:`machine_ceiling`).
    """

    n: int
    setup: dict
    serial_s: float
    runs: list = field(default_factory=list)
    overheads: dict = field(default_factory=dict)
    machine: dict = field(default_factory=dict)

    def to_text(self) -> str:
        """A table of the runs and a line of overheads."""
        s = self.setup
        varied = ", ".join(f"{k} in [{lo:g}, {hi:g}]" for k, (lo, hi) in s["ranges"].items())
        lines = [f"{self.n} backbones: default beam, {s['elements']} elements, H = {s['harmonics']}, up to "
                 f"{s['max_amplitude']} gaps, {varied} (Latin hypercube, seed {s['seed']})",
                 f"{'executor':<8} {'state':<5} {'workers':>7} {'chunk':>5} {'tasks':>5} {'wall (s)':>9} "
                 f"{'open (s)':>8} {'backbones/s':>11} {'efficiency':>10} {'busy':>5} identical"]
        for r in self.runs:
            lines.append(f"{r.executor:<8} {'warm' if r.warm else 'cold':<5} {r.workers:>7} {r.chunksize:>5} "
                         f"{r.tasks:>5} {r.wall_s:>9.2f} {r.open_s:>8.2f} {r.backbones_per_s:>11.1f} "
                         f"{r.efficiency:>10.0%} {r.busy:>5.0%} {'yes' if r.identical else 'NO'}")
        o = self.overheads
        lines.append(f"serial cost {o['per_backbone_ms']:.1f} ms per backbone; per task "
                     f"{o['task_bytes'] / 1e3:.1f} kB sent, {o['result_bytes'] / 1e3:.0f} kB returned; "
                     f"pickling a result {o['pickle_ms_per_backbone']:.2f} ms per backbone")
        lines.append("efficiency = serial time / (workers x wall); busy = time in tasks / (workers x wall)")
        m = self.machine
        lines.append(f"machine: {m['cpu_count']} CPUs, load average {m['loadavg_before'][0]:.2f} before, "
                     f"{m['loadavg_after'][0]:.2f} after (1 min); efficiency it gives "
                     f"{self.runs[-1].workers} processes of perfectly parallel work: "
                     f"{m['ceiling_before']:.0%} before, {m['ceiling_after']:.0%} after "
                     "(the ceiling of the efficiencies above)")
        return "\n".join(lines)

    def to_json(self, path) -> Path:
        """Write every figure as JSON."""
        path = Path(path)
        path.write_text(json.dumps(asdict(self), indent=1) + "\n")
        return path


def _warm_worker(spec, pause: float = 0.0):
    """Run one backbone (loads the kernels), then wait ``pause`` s so that concurrent
    warm-up tasks land on different pool workers."""
    from mmshbm.analysis.runspec import execute

    execute(spec)
    time.sleep(pause)
    return os.getpid()


def _spin(n: int) -> float:
    """A fixed amount of pure-Python arithmetic (no I/O, no memory traffic); returns its
    wall time in the process that runs it."""
    t0 = time.perf_counter()
    x = 0.0
    for i in range(n):
        x += (i % 7) * 0.5
    return time.perf_counter() - t0


def machine_ceiling(workers: int = 2, seconds: float = 0.3) -> float:
    """The parallel efficiency this machine gives right now to ``workers`` processes of
    perfectly parallel work: t(one copy alone) / t(``workers`` copies at once in a warm
    process pool). 1 on idle cores; about 2/3 when one other busy process shares two
    cores. An upper bound for the efficiency of any study measured at the same time."""
    from mmshbm.analysis.executors import process_pool

    n = max(1, int(seconds * 2e7))
    with process_pool(workers) as pool:
        list(pool.map(_spin, [1000] * workers))  # start the workers
        alone = min(_spin(n) for _ in range(2))
        t0 = time.perf_counter()
        list(pool.map(_spin, [n] * workers))
        together = time.perf_counter() - t0
    return alone / together


def _same(a, b) -> bool:
    return len(a) == len(b) and all(
        x.states.tobytes() == y.states.tobytes() and x.frequency.tobytes() == y.frequency.tobytes()
        and x.status == y.status for x, y in zip(a, b, strict=True))


def measure_throughput(n: int = 1000, *, harmonics: int = 3, elements: int = 8, max_amplitude: float = 10.0,
                       ranges: dict | None = None, seed: int = 0, workers: int = 2,
                       executors=("process", "dask"), chunksize="auto", cold: bool = True, warm: bool = True,
                       verbose: bool = False) -> Throughput:
    """Time a Monte-Carlo study of ``n`` backbones on each executor (module docstring).

    Parameters
    ----------
    n : int
        Backbones per study.
    harmonics, elements : int
        H and element count of the default beam (the defaults give ~10–20 ms per backbone).
    max_amplitude : float
        Gaps.
    ranges : dict, optional
        Parameter ranges of :func:`~mmshbm.analysis.studies.monte_carlo` (default
        :data:`DEFAULT_RANGES`).
    seed : int
    workers : int
        Processes of the pool and the Dask cluster.
    executors : sequence of {"process", "dask"}
        Parallel executors to time ("dask" is left out when dask is not installed).
    chunksize : int or "auto"
        Backbones per task.
    cold, warm : bool
        Time the executor opened inside the timing, and/or already warm.
    verbose : bool
        Log each run.

    Returns
    -------
    Throughput
    """
    from mmshbm import BranchWarning
    from mmshbm.analysis.executors import auto_chunksize, process_pool
    from mmshbm.analysis.runspec import execute
    from mmshbm.analysis.studies import grid_specs, monte_carlo
    from mmshbm.analysis.studies import run_study as _run_study

    def run_study(**kwargs):  # the branch checks' warnings are not the point here (they are in metadata)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", BranchWarning)
            return _run_study(**kwargs)

    n = check.integer("n", n, minimum=1)
    workers = check.integer("workers", workers, minimum=1)
    ranges = dict(DEFAULT_RANGES if ranges is None else ranges)
    for name in executors:
        if name not in ("process", "dask"):
            raise ValueError(f"executors must be 'process' or 'dask', got {name!r}")
    if "dask" in executors:
        try:
            import dask.distributed  # noqa: F401
        except ImportError:
            log.warning("dask is not installed: the Dask cluster is not timed")
            executors = [e for e in executors if e != "dask"]
    samples = monte_carlo(n, ranges, seed)
    grid = {"harmonics": (harmonics,), "elements": (elements,), "samples": samples,
            "max_amplitude": max_amplitude, "unit": "gap"}
    specs = grid_specs(**grid)
    machine = {"cpu_count": os.cpu_count(), "loadavg_before": list(os.getloadavg()),
               "ceiling_before": machine_ceiling(workers) if executors else 1.0}

    execute(specs[0])  # compile or load the kernels in this process
    t0 = time.perf_counter()
    serial = run_study(executor="serial", **grid)
    serial_s = time.perf_counter() - t0
    result = Throughput(n=n, setup={"model": "default beam", "elements": elements, "harmonics": harmonics,
                                    "max_amplitude": max_amplitude, "ranges": ranges, "seed": seed},
                        serial_s=serial_s)
    result.runs.append(ThroughputRun("serial", True, 1, 1, n, serial_s, 0.0, True, n / serial_s, 1.0,
                                     serial.metadata["busy_s"] / serial_s))
    if verbose:
        log.info("serial: %.2f s", serial_s)

    if chunksize == "auto":
        chunk = auto_chunksize(n, workers)
    else:
        chunk = chunksize = check.integer("chunksize", chunksize, minimum=1)
    task = specs[:chunk]
    t = time.perf_counter()
    blob = pickle.dumps(serial.branches[:chunk])
    pickle.loads(blob)
    result.overheads = {"task_bytes": len(pickle.dumps(task)), "result_bytes": len(blob),
                        "pickle_ms_per_backbone": (time.perf_counter() - t) / chunk * 1e3,
                        "per_backbone_ms": serial_s / n * 1e3}

    def record(name, is_warm, study):
        wall = study.metadata["elapsed_s"]
        meta = study.metadata
        run = ThroughputRun(name, is_warm, workers, meta["chunksize"], meta["tasks"], wall, meta["open_s"],
                            _same(serial.branches, study.branches), n / wall, serial_s / (workers * wall),
                            meta["busy_s"] / (workers * wall))
        result.runs.append(run)
        if verbose:
            log.info("%s", run)

    for name in executors:
        if cold:
            record(name, False, run_study(executor=name, workers=workers, chunksize=chunksize, **grid))
        if warm:
            if name == "process":
                pool = process_pool(workers)
                try:
                    list(pool.map(_warm_worker, [specs[0]] * workers, [0.5] * workers))
                    record(name, True, run_study(executor=pool, workers=workers, chunksize=chunksize, **grid))
                finally:
                    pool.shutdown()
            else:
                from dask.distributed import Client, LocalCluster

                with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, Client(cluster) as client:
                    client.run(_warm_worker, specs[0])
                    study = run_study(executor=client, workers=workers, chunksize=chunksize, **grid)
                    record(name, True, study)
    machine["loadavg_after"] = list(os.getloadavg())
    machine["ceiling_after"] = machine_ceiling(workers) if executors else 1.0
    result.machine = machine
    return result


