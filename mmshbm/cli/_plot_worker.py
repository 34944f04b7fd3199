"""Figures drawn by a child process that imports matplotlib while the parent computes.

Importing matplotlib and drawing the first figure of a process costs about as much as
everything else in ``mmshbm backbone`` once Numba's cache is warm (~0.3 s + ~0.1 s per
figure on the project's machine). The command starts :class:`PlotWorker` before it
computes: the child imports :mod:`mmshbm.plotting` (matplotlib) on the other core and
waits for its jobs on stdin; the parent sends the figures to draw, as
:class:`~mmshbm.plotting.data.BranchData` (no solver, no model: unpickling them
imports nothing heavy), and waits for the files.

``mmshbm study`` draws its two figures at once: the child draws one while the parent
draws the other (:meth:`PlotWorker.draw` with ``here``).

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

log = logging.getLogger(__name__)

#: seconds the parent waits for the child's figures before drawing them itself
TIMEOUT_S = 120.0
#: the modules of mmshbm.plotting the child imports before its jobs come (the backbone figures)
MODULES = ("backbones", "signals", "response")


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

    def __init__(self, start: bool | None = None, modules: tuple[str, ...] = MODULES):
        self._proc = None
        if not (enabled() if start is None else start):
            return
        # the child imports exactly as this process does: same interpreter, same sys.path
        code = ("import sys, json; sys.path[:] = json.loads(sys.argv[1]); "
                "from mmshbm.cli._plot_worker import _main; _main(json.loads(sys.argv[2]))")
        try:
            self._proc = subprocess.Popen([sys.executable, "-c", code, json.dumps(sys.path),
                                           json.dumps(list(modules))],
                                          stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                                          stderr=subprocess.PIPE)
        except OSError as err:  # pragma: no cover - no way to start a process
            log.info("plot worker not started (%s): drawing in this process", err)

    @property
    def running(self) -> bool:
        return self._proc is not None and self._proc.poll() is None

    def draw(self, jobs: list[tuple[str, tuple, dict]], here: list[tuple[str, tuple, dict]] = ()) -> bool:
        """Draw ``jobs``: (name of a function of :mod:`mmshbm.plotting`, args, kwargs with
        ``path``), in the child when it is running, else (or when it fails) here; and
        ``here`` (same form) in this process meanwhile. Returns True when the child drew
        ``jobs``."""
        if not jobs:
            self.close()
            _draw(here)
            return False
        if self._proc is not None:
            try:
                self._proc.stdin.write(pickle.dumps(jobs, protocol=pickle.HIGHEST_PROTOCOL))
                self._proc.stdin.flush()  # communicate() closes it
            except (OSError, ValueError, pickle.PicklingError) as err:
                log.info("plot worker failed (%s): drawing in this process", err)
            else:
                _draw(here)  # meanwhile (a plot that raises here ends the child on exit)
                here = ()
                try:
                    _, err = self._proc.communicate(timeout=TIMEOUT_S)
                    if self._proc.returncode == 0:
                        self._proc = None
                        return True
                    log.info("plot worker failed (exit %s): drawing in this process\n%s",
                             self._proc.returncode, err.decode(errors="replace").strip())
                except (OSError, ValueError, subprocess.TimeoutExpired) as err:
                    log.info("plot worker failed (%s): drawing in this process", err)
            self.close()
        _draw(here)
        _draw(jobs)
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


def _draw(jobs) -> None:
    """Draw ``jobs`` in this process."""
    if not jobs:
        return
    from .. import plotting

    for name, args, kwargs in jobs:
        getattr(plotting, name)(*args, **kwargs)


def _serve(modules=MODULES) -> int:
    """The child: import the plots, then draw the jobs read from stdin (none on EOF).
    One pickle is read, not up to EOF: processes forked by the parent after this child
    started hold the write end of its stdin too."""
    import importlib

    from .. import plotting

    for module in modules:  # matplotlib: the point of running ahead
        importlib.import_module(f"{plotting.__name__}.{module}")
    try:
        jobs = pickle.load(sys.stdin.buffer)
    except EOFError:
        return 0
    _draw(jobs)
    return 0


def _main(modules=MODULES) -> None:  # pragma: no cover - runs in the child
    import gc

    code = _serve(tuple(modules))
    gc.freeze()  # a fast exit, as the mmshbm program's
    sys.exit(code)
