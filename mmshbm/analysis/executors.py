"""Where the runs of a study go: this process, a process pool, a Dask cluster, any executor.

:func:`run_specs` sends :class:`~mmshbm.analysis.studies.RunSpec` objects to workers in
*chunks*: one task runs ``chunksize`` specs one after the other and returns their branches,
so the per-task cost of an executor (pickling a task, a round trip through the pool's
queues or Dask's scheduler: of the order of 0.1–1 ms per task for a process pool, a few
ms for Dask) is paid once per chunk instead of once per backbone. Every spec is executed
by the same function whatever the executor and chunk, so the numbers are identical.

Specs go to the pool longest first (:func:`longest_first`, by an estimate of their cost
from H and the model's size): a study's wall time is set by its longest runs, and a long
run sent last keeps one worker busy while the others idle.
"""

from __future__ import annotations

import concurrent.futures as cf
import logging
import multiprocessing
import time

from .. import _validate as check
from .runspec import execute

__all__ = ["open_executor", "run_specs", "auto_chunksize", "estimated_cost", "longest_first"]

log = logging.getLogger(__name__)


def auto_chunksize(n_runs: int, workers: int) -> int:
    """Specs per task when ``chunksize="auto"``: about 16 tasks per worker (a straggling
    last chunk then costs a worker at most ~1/16 of its share), and one spec per task for
    small studies (fewer than 32 runs per worker), whose runs differ widely in cost."""
    return max(1, n_runs // (16 * max(1, workers)))


def estimated_cost(spec) -> float:
    """A relative cost of one run, for ordering only: harmonic-balance runs grow with
    H^2.5 (unknowns and samples grow with H, and higher H meets more internal resonances
    to jump over), shooting with the number of elements; either a little with the model's
    size (the condensation's modes)."""
    coords = getattr(spec, "coords", {}) or {}
    size = float(coords.get("elements", 21) or 21)
    if getattr(spec, "method", "mmshbm") == "shooting":
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
        pool = cf.ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"))
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


def execute_chunk(specs: list) -> tuple[list, float]:
    """Run the specs of one task in order (what a worker executes); returns their
    branches (without solvers) and the seconds the worker spent on them."""
    t0 = time.perf_counter()
    return [execute(spec) for spec in specs], time.perf_counter() - t0


def run_specs(specs: list, executor, workers: int, *, chunksize="auto", verbose: bool = False) -> tuple:
    """Run every spec and return the branches in spec order.

    Parameters
    ----------
    specs : list of RunSpec
        With ``index`` 0..n-1 (their position).
    executor, workers
        As in :func:`mmshbm.analysis.studies.run_study`.
    chunksize : int or "auto"
        Specs per task (:func:`auto_chunksize` for "auto"); ignored in this process.
    verbose : bool
        Progress bar (tqdm; hidden when not on a terminal).

    Returns
    -------
    (branches, description, info)
        ``info``: ``{"chunksize", "tasks", "open_s", "busy_s"}`` (``open_s``: seconds to
        open the executor, e.g. to start a Dask cluster; process pools start their
        workers lazily; ``busy_s``: seconds the workers spent inside the tasks, summed:
        busy_s / (workers × wall time) is the share of the workers' time spent on runs,
        whatever else loads the machine).
    """
    from tqdm.auto import tqdm

    workers = check.integer("workers", workers, minimum=1)
    if chunksize == "auto":
        chunksize = auto_chunksize(len(specs), workers)
    chunksize = check.integer("chunksize", chunksize, minimum=1)
    t0 = time.perf_counter()
    pool, close, kind = open_executor(executor, workers)
    info = {"chunksize": chunksize if pool is not None else 1, "open_s": time.perf_counter() - t0,
            "busy_s": 0.0}
    out: list = [None] * len(specs)
    bar = tqdm(total=len(specs), desc="study", unit="run", disable=None if verbose else True, leave=False)
    try:
        if pool is None:
            info["tasks"] = len(specs)
            for spec in specs:
                (out[spec.index],), busy = execute_chunk([spec])
                info["busy_s"] += busy
                _progress(bar, spec, out[spec.index])
        else:
            ordered = longest_first(specs)
            chunks = [ordered[i:i + chunksize] for i in range(0, len(ordered), chunksize)]
            info["tasks"] = len(chunks)
            futures = {pool.submit(execute_chunk, chunk): chunk for chunk in chunks}
            try:
                for fut in cf.as_completed(futures):
                    branches, busy = fut.result()
                    info["busy_s"] += busy
                    for spec, branch in zip(futures[fut], branches, strict=True):
                        out[spec.index] = branch
                        _progress(bar, spec, branch)
            except BaseException:
                for fut in futures:
                    fut.cancel()
                raise
    finally:
        bar.close()
        if close is not None:
            close()
    log.debug("%d runs in %d tasks of up to %d (%s)", len(specs), info["tasks"], chunksize, kind)
    return out, kind, info


def _progress(bar, spec, branch) -> None:
    log.debug("run %d %s: %r", spec.index, spec.coords, branch)
    bar.set_postfix_str(" ".join(f"{k}={v}" for k, v in spec.coords.items()), refresh=False)
    bar.update(1)


