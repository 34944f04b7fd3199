"""Where the runs of a study go: this process, a process pool, a Dask cluster, any executor.

:func:`run_specs` sends :class:`~mmshbm.analysis.studies.RunSpec` objects to workers in
*chunks*: one task runs ``chunksize`` specs one after the other and returns their branches,
so the per-task cost of an executor (pickling a task, a round trip through the pool's
queues or Dask's scheduler: of the order of 0.1–1 ms per task for a process pool, a few
ms for Dask) is paid once per chunk instead of once per backbone. Every spec is executed
by the same function whatever the executor and chunk, so the numbers are identical.

A large study's chunks shrink as the study goes (:func:`plan_chunks`): few tasks, and
single runs at the end, where a long chunk would keep one worker busy while the others
idle. Specs go to the pool longest first (:func:`longest_first`, by an estimate of their cost
from H and the model's size): a study's wall time is set by its longest runs, and a long
run sent last keeps one worker busy while the others idle.

Process pools *fork* this process where that is safe (:func:`start_method`): the workers
then start with this process's imports in place (numpy, scipy, Numba and the modules a
run needs, imported here once by :func:`preload` instead of once per worker: ~0.8 s of
CPU per worker on the project's machine) and end with ``os._exit``, without the
interpreter finalisation that walks Numba's ~10⁵ objects (0.3–0.9 s per worker). Elsewhere
they are spawned, and end with those objects frozen out of the collector's reach
(:func:`_worker_init`). Fork changes no number: a worker runs the same code on the same
spec either way (the FFT plans are FFTW_ESTIMATE, made in the worker).
"""

from __future__ import annotations

import concurrent.futures as cf
import importlib
import logging
import multiprocessing
import os
import sys
import threading
import time

from .. import _validate as check
from .._method_info import DEFAULT_METHOD, is_harmonic_balance
from .runspec import execute

__all__ = ["open_executor", "run_specs", "auto_chunksize", "plan_chunks", "estimated_cost", "longest_first",
           "start_method", "process_pool", "preload"]

log = logging.getLogger(__name__)

#: the modules a run imports on first use (the continuation, MMS-HBM and its family
#: guard, Numba and the kernels' modules): imported by :func:`preload` before a fork
RUN_MODULES = ("mmshbm.methods.backbone", "mmshbm.methods.runner", "mmshbm.methods.mms.conservative",
               "mmshbm.methods.mms.family", "mmshbm.methods.mms.filtered", "mmshbm.core.continuation",
               "mmshbm.family.follower", "mmshbm.harmonic.condense", "mmshbm.results.coexisting")


def start_method() -> str:
    """How process pools start their workers: ``MMSHBM_START_METHOD`` when set ("fork",
    "spawn" or "forkserver"); else "fork" on Linux when no other Python thread runs in
    this process, "spawn" otherwise.

    A forked child inherits the locks of the parent's other threads in whatever state
    they were (Python 3.12 warns on fork with threads running), and macOS's system
    libraries are not fork-safe: there, and under Jupyter or any threaded host, the
    workers are spawned. The package's kernels are fork-safe: Numba kernels without
    ``parallel=True`` start no threading layer, FFTW plans are single-threaded
    (``threads=1``), and the ``mmshbm`` program runs BLAS on one thread."""
    chosen = os.environ.get("MMSHBM_START_METHOD", "").strip().lower()
    if chosen:
        if chosen not in multiprocessing.get_all_start_methods():
            raise ValueError(f"MMSHBM_START_METHOD must be one of {multiprocessing.get_all_start_methods()}, "
                             f"got {chosen!r}")
        return chosen
    if sys.platform.startswith("linux") and threading.active_count() == 1:
        return "fork"
    return "spawn"


def preload(modules=RUN_MODULES) -> None:
    """Import ``modules`` in this process (so that forked workers have them)."""
    for name in modules:
        importlib.import_module(name)


def _worker_init() -> None:
    """Initializer of spawned workers: at exit, move every object out of the garbage
    collector's reach (:func:`gc.freeze`), so that the interpreter's finalisation does
    not walk Numba's registries (as the ``mmshbm`` program does, :func:`mmshbm.cli.console`)."""
    import atexit
    import gc

    atexit.register(gc.freeze)


def process_pool(workers: int, method: str | None = None) -> cf.ProcessPoolExecutor:
    """A process pool of ``workers`` started by ``method`` (default :func:`start_method`);
    before a fork, this process imports :data:`RUN_MODULES` (:func:`preload`)."""
    method = method or start_method()
    if method == "fork":
        preload()
        return cf.ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("fork"))
    return cf.ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context(method),
                                  initializer=_worker_init)


#: studies with fewer runs per worker than this go one run per task ("auto")
SMALL_PER_WORKER = 32
#: "auto" chunks of a large study: each takes this share of the estimated cost not yet
#: handed out, divided by the workers
GUIDED_SHARE = 0.5


def auto_chunksize(n_runs: int, workers: int) -> int:
    """The typical specs per task of ``chunksize="auto"`` (for sizing a task's payload):
    one for small studies (fewer than :data:`SMALL_PER_WORKER` runs per worker), else the
    mean chunk of :func:`plan_chunks`'s guided plan for runs of equal cost."""
    workers = max(1, workers)
    if n_runs < SMALL_PER_WORKER * workers:
        return 1
    return max(1, round(n_runs / len(_guided([1.0] * n_runs, workers))))


def plan_chunks(specs: list, workers: int, chunksize="auto") -> list[list]:
    """The tasks of a pool: ``specs`` longest first (:func:`longest_first`), cut into chunks.

    An integer ``chunksize`` cuts chunks of that many specs. ``"auto"`` sends small
    studies (fewer than :data:`SMALL_PER_WORKER` runs per worker, whose runs differ widely
    in cost) one spec per task, and *guides* large ones: each chunk holds about
    ``GUIDED_SHARE / workers`` of the estimated cost not yet handed out, so chunks shrink
    from about n/(2·workers) specs to one. A large study then costs few tasks (about
    2·workers·ln(n/workers): the executor's per-task cost, a pickled round trip through
    the pool's queues, stays negligible however many workers there are) and ends with
    single specs (a worker waits at most about one run for the others at the end)."""
    ordered = longest_first(specs)
    if chunksize == "auto":
        if len(ordered) < SMALL_PER_WORKER * max(1, workers):
            sizes = [1] * len(ordered)
        else:
            sizes = _guided([estimated_cost(s) for s in ordered], workers)
    else:
        sizes = [chunksize] * -(-len(ordered) // chunksize)
    chunks, start = [], 0
    for size in sizes:
        if start >= len(ordered):
            break
        chunks.append(ordered[start:start + size])
        start += size
    return chunks


def _guided(costs: list[float], workers: int) -> list[int]:
    """Chunk sizes over ``costs`` (in order): each chunk's cost about GUIDED_SHARE/workers of
    the cost left, at least one item."""
    left = float(sum(costs))
    sizes, i = [], 0
    while i < len(costs):
        target = GUIDED_SHARE * left / max(1, workers) * (1 + 1e-9)  # equal costs: no rounding loss
        size, cost = 0, 0.0
        while i + size < len(costs) and (size == 0 or cost + costs[i + size] <= target):
            cost += costs[i + size]
            size += 1
        sizes.append(size)
        left -= cost
        i += size
    return sizes


def estimated_cost(spec) -> float:
    """A relative cost of one run, for ordering only: harmonic-balance runs grow with
    H^2.5 (unknowns and samples grow with H, and higher H meets more internal resonances
    to jump over), shooting with the number of elements; either a little with the model's
    size (the condensation's modes)."""
    coords = getattr(spec, "coords", {}) or {}
    size = float(coords.get("elements", 21) or 21)
    if not is_harmonic_balance(getattr(spec, "method", DEFAULT_METHOD)):
        return 50.0 * size
    return max(int(getattr(spec, "harmonics", 1) or 1), 1) ** 2.5 * (1.0 + size / 400.0)


def longest_first(specs: list) -> list:
    """``specs`` sorted by decreasing :func:`estimated_cost` (ties in their order)."""
    return sorted(specs, key=lambda spec: -estimated_cost(spec))


def open_executor(executor, workers: int):
    """(executor or None, closer or None, description) for the ``executor`` argument of
    :func:`mmshbm.analysis.studies.run_study`."""
    if executor is None or executor == "serial":
        return None, None, "serial"
    if executor == "process":
        pool = process_pool(workers)
        return pool, pool.shutdown, f"process pool ({workers} workers)"
    if executor == "dask":
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError:
            raise ValueError("executor='dask' needs dask: pip install 'mmshbm[dask]'") from None
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)

        def close():
            client.close()
            cluster.close()

        return client.get_executor(), close, f"dask local cluster ({workers} workers)"
    if isinstance(executor, cf.Executor):
        return executor, None, type(executor).__name__
    if hasattr(executor, "get_executor"):  # a dask.distributed.Client
        address = getattr(getattr(executor, "scheduler", None), "address", "")
        return executor.get_executor(), None, f"dask client {address}".strip()
    raise TypeError("executor must be 'process', 'serial', None, 'dask', a concurrent.futures.Executor "
                    f"or a dask Client, got {executor!r}")


def execute_chunk(specs: list, tabulate: tuple | None = None) -> tuple[list, float, list | None]:
    """Run the specs of one task in order (what a worker executes); returns their
    branches (without solvers), the seconds the worker spent on them, and with
    ``tabulate`` = (amplitudes, unit) their table rows
    (:func:`mmshbm.analysis.table_rows.tabulate`), else None."""
    t0 = time.perf_counter()
    branches = [execute(spec) for spec in specs]
    rows = None
    if tabulate is not None:
        from .table_rows import tabulate as tabulate_row

        rows = [tabulate_row(branch, *tabulate) for branch in branches]
    return branches, time.perf_counter() - t0, rows


def run_specs(specs: list, executor, workers: int, *, chunksize="auto", verbose: bool = False,
              tabulate: tuple | None = None, while_running=None) -> tuple:
    """Run every spec and return the branches in spec order.

    Parameters
    ----------
    specs : list of RunSpec
        With ``index`` 0..n-1 (their position).
    executor, workers
        As in :func:`mmshbm.analysis.studies.run_study`.
    chunksize : int or "auto"
        Specs per task, or "auto" (:func:`plan_chunks`); ignored in this process.
    verbose : bool
        Progress on stderr (a tqdm bar on a terminal, plain lines in a pipe or log).
    tabulate : (amplitudes, unit), optional
        Each task also computes its runs' table rows after them
        (:func:`mmshbm.analysis.table_rows.tabulate`).
    while_running : callable, optional
        Called without arguments in this process once the tasks are sent (before the
        first run in this process for ``executor=None``): work of the caller's that can
        overlap the runs (e.g. importing what it needs afterwards).

    Returns
    -------
    (branches, description, info)
        ``info``: ``{"chunksize", "tasks", "open_s", "busy_s"}`` (``open_s``: seconds to
        open the executor, e.g. to start a Dask cluster; process pools start their
        workers lazily; ``busy_s``: seconds the workers spent inside the tasks, summed:
        busy_s / (workers × wall time) is the share of the workers' time spent on runs,
        whatever else loads the machine), and with ``tabulate`` ``"rows"``: the table
        rows in spec order (None where a row raised).
    """
    workers = check.integer("workers", workers, minimum=1)
    if chunksize != "auto":
        chunksize = check.integer("chunksize", chunksize, minimum=1)
    t0 = time.perf_counter()
    pool, close, kind = open_executor(executor, workers)
    info = {"chunksize": 1, "open_s": time.perf_counter() - t0, "busy_s": 0.0}
    out: list = [None] * len(specs)
    rows: list = [None] * len(specs)
    bar = None
    try:
        if pool is None:
            if while_running is not None:
                while_running()
            bar = _bar(len(specs), verbose)
            info["tasks"] = len(specs)
            for spec in specs:
                (out[spec.index],), busy, chunk_rows = execute_chunk([spec], tabulate)
                info["busy_s"] += busy
                if chunk_rows is not None:
                    rows[spec.index] = chunk_rows[0]
                _progress(bar, spec, out[spec.index])
        else:
            chunks = plan_chunks(specs, workers, chunksize)
            info["tasks"] = len(chunks)
            info["chunksize"] = max(len(c) for c in chunks) if chunks else 1
            futures = {pool.submit(execute_chunk, chunk, tabulate): chunk for chunk in chunks}
            if while_running is not None:
                while_running()
            bar = _bar(len(specs), verbose)  # after the pool forked: tqdm starts a monitor thread
            try:
                for fut in cf.as_completed(futures):
                    branches, busy, chunk_rows = fut.result()
                    info["busy_s"] += busy
                    for k, (spec, branch) in enumerate(zip(futures[fut], branches, strict=True)):
                        out[spec.index] = branch
                        if chunk_rows is not None:
                            rows[spec.index] = chunk_rows[k]
                        _progress(bar, spec, branch)
            except BaseException:
                for fut in futures:
                    fut.cancel()
                raise
    finally:
        if bar is not None:
            bar.close()
        if close is not None:
            close()
    if tabulate is not None:
        info["rows"] = rows
    log.debug("%d runs in %d tasks of up to %d (%s)", len(specs), info["tasks"], info["chunksize"], kind)
    return out, kind, info


def _bar(total: int, verbose: bool):
    """With ``verbose`` a progress display (:func:`mmshbm._progress.progress_bar`: a tqdm
    bar on a terminal, plain lines in a pipe or log), else None."""
    if not verbose:
        return None
    from .._progress import progress_bar

    return progress_bar("study", unit="run", total=total)


def _progress(bar, spec, branch) -> None:
    log.debug("run %d %s: %r", spec.index, spec.coords, branch)
    if bar is None:
        return
    bar.set_postfix_str(" ".join(f"{k}={v}" for k, v in spec.coords.items()), refresh=False)
    bar.update(1)


