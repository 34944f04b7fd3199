"""Figures drawn by a child process that imports matplotlib while the parent computes.

Importing matplotlib and drawing the first figure of a process costs about as much as
everything else in ``mmshbm backbone`` once Numba's cache is warm (~0.3 s + ~0.1 s per
figure on the project's machine). The command starts :class:`PlotWorker` before it
computes: the child imports :mod:`mmshbm.plotting` (matplotlib) on the other core and
waits for its jobs on stdin; the parent sends the figures to draw, as
:class:`~mmshbm.plotting.data.BranchData` (no solver, no model: unpickling them
imports nothing heavy), and waits for the files.

``mmshbm study`` draws its two figures at once, one in a child forked after the runs
(:func:`draw_forked`: it has matplotlib and the study already, nothing to import or send)
and one in the parent.

The figures are the same as drawn in the parent (same code, same matplotlib and
matplotlibrc). Whatever goes wrong in the child (it cannot start, dies, times out,
a plot raises) makes the parent draw the figures itself, so the result never depends
on the child; a plot that raises then raises in the parent with its usual message.
By default the child is used when about a core is idle (one-minute load average);
``MMSHBM_PLOT_WORKER=1`` always uses it (on more than one core), ``MMSHBM_PLOT_WORKER=0``
never.
"""

from __future__ import annotations

import json
import logging
import os
import pickle
import subprocess
import sys
import threading
import warnings

log = logging.getLogger(__name__)

#: seconds the parent waits for the child's figures before drawing them itself
TIMEOUT_S = 120.0


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def _idle_cores() -> float:
    """Cores not busy on average over the last minute (cores − load average)."""
    try:
        return _cores() - os.getloadavg()[0]
    except (AttributeError, OSError):  # pragma: no cover - no load average (Windows)
        return _cores() - 1.0


def enabled() -> bool:
    """Draw in a child process? ``MMSHBM_PLOT_WORKER=1`` always, ``0`` never; by default
    when about a core is idle (the child costs ~0.25 s of CPU of its own: on a busy
    machine it slows the command down instead)."""
    flag = os.environ.get("MMSHBM_PLOT_WORKER", "").strip().lower()
    if flag in ("0", "no", "false", "off"):
        return False
    if flag in ("1", "yes", "true", "on"):
        return _cores() > 1
    return _cores() > 1 and _idle_cores() >= 0.8


class PlotWorker:
    """A child process ready to draw figures of :mod:`mmshbm.plotting`.

    Use as a context manager (the child is ended on exit, also on errors)::

        with PlotWorker() as worker:
            ...compute...
            worker.draw([("plot_backbone", (data,), {"path": "out/b.png"})])
    """

    def __init__(self, start: bool | None = None):
        self._proc = None
        if not (enabled() if start is None else start):
            return
        # the child imports exactly as this process does: same interpreter, same sys.path
        code = ("import sys, json; sys.path[:] = json.loads(sys.argv[1]); "
                "from mmshbm.cli._plot_worker import _main; _main()")
        try:
            self._proc = subprocess.Popen([sys.executable, "-c", code, json.dumps(sys.path)],
                                          stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                                          stderr=subprocess.PIPE)
        except OSError as err:  # pragma: no cover - no way to start a process
            log.info("plot worker not started (%s): drawing in this process", err)

    @property
    def running(self) -> bool:
        return self._proc is not None and self._proc.poll() is None

    def draw(self, jobs: list[tuple[str, tuple, dict]]) -> bool:
        """Draw ``jobs``: (name of a function of :mod:`mmshbm.plotting`, args, kwargs with
        ``path``), in the child when it is running, else (or when it fails) here. Returns
        True when the child drew them."""
        if not jobs:
            self.close()
            return False
        if self._proc is not None:
            try:
                _, err = self._proc.communicate(pickle.dumps(jobs, protocol=pickle.HIGHEST_PROTOCOL),
                                                timeout=TIMEOUT_S)
                if self._proc.returncode == 0:
                    self._proc = None
                    return True
                log.info("plot worker failed (exit %s): drawing in this process\n%s", self._proc.returncode,
                         err.decode(errors="replace").strip())
            except (OSError, ValueError, pickle.PicklingError, subprocess.TimeoutExpired) as err:
                log.info("plot worker failed (%s): drawing in this process", err)
            self.close()
        from .. import plotting

        for name, args, kwargs in jobs:
            getattr(plotting, name)(*args, **kwargs)
        return False

    def close(self) -> None:
        """End the child (if it still runs)."""
        proc, self._proc = self._proc, None
        if proc is None:
            return
        if proc.poll() is None:
            proc.kill()
        proc.communicate()

    def __enter__(self) -> PlotWorker:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def fork_enabled() -> bool:
    """Can :func:`draw_forked` fork? On Linux with more than one core, when no other
    Python thread runs (a forked child would inherit the locks they hold)."""
    return (sys.platform.startswith("linux") and hasattr(os, "fork") and _cores() > 1
            and threading.active_count() == 1)


def draw_forked(jobs: list[tuple[str, tuple, dict]], here=()) -> bool:
    """Draw ``jobs`` (as :meth:`PlotWorker.draw` takes them) in a child forked from this
    process while this process draws ``here`` (jobs too) or calls it (a callable). The
    child starts with everything this process imported and computed (matplotlib, the
    study): nothing to import, nothing to send. The warnings the child's figures raise
    are issued again here. When the child cannot be forked (:func:`fork_enabled`) or
    fails, ``jobs`` are drawn here. Returns True when the child drew them."""
    if not jobs or not fork_enabled():
        _here(here)
        _draw(jobs)
        return False
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        code = 1
        try:
            os.close(read)
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                _draw(jobs)
            raised = [(str(w.message), w.category, w.filename, w.lineno) for w in caught]
            with os.fdopen(write, "wb") as pipe:
                pickle.dump(raised, pipe)
            code = 0
        finally:
            os._exit(code)
    os.close(write)
    try:
        _here(here)
    finally:
        with os.fdopen(read, "rb") as pipe:
            data = pipe.read()
        _, status = os.waitpid(pid, 0)
    if os.waitstatus_to_exitcode(status) == 0 and data:
        for message, category, filename, lineno in pickle.loads(data):
            warnings.warn_explicit(message, category, filename, lineno)
        return True
    log.info("forked plot child failed (exit %s): drawing in this process", os.waitstatus_to_exitcode(status))
    _draw(jobs)
    return False


def _here(here) -> None:
    if callable(here):
        here()
    else:
        _draw(here)


def _draw(jobs) -> None:
    """Draw ``jobs`` in this process."""
    from .. import plotting

    for name, args, kwargs in jobs:
        getattr(plotting, name)(*args, **kwargs)


def _serve() -> int:
    """The child: import the plots, then draw the jobs read from stdin (none on EOF)."""
    import importlib

    from .. import plotting

    for module in ("backbones", "signals", "response"):  # matplotlib: the point of running ahead
        importlib.import_module(f"{plotting.__name__}.{module}")

    data = sys.stdin.buffer.read()
    if not data:
        return 0
    for name, args, kwargs in pickle.loads(data):
        getattr(plotting, name)(*args, **kwargs)
    return 0


def _main() -> None:  # pragma: no cover - runs in the child
    import gc

    code = _serve()
    gc.freeze()  # a fast exit, as the mmshbm program's
    sys.exit(code)
