"""Progress of a long run asked for with ``verbose=True``.

On a terminal (or in a notebook) it is a tqdm bar on stderr, redrawn in place. Anywhere
else (stderr piped into a log file, a batch job, ``2>&1 | tee``) a bar redrawn with
carriage returns is unreadable, and tqdm's default hides it: there :class:`LineProgress`
writes one plain line to stderr at the first update, then at most one every
:data:`LINE_INTERVAL_S` seconds, and one when the run ends, e.g.

    mmshbm backbone: 3.2/10 gap, 41 points, 58.3 Hz [12.0 s]

Both offer what the runs use of a tqdm bar: ``n``, ``total``, ``update``,
``set_postfix_str``, ``set_postfix``, ``refresh`` and ``close``.
"""

from __future__ import annotations

import sys
import time

__all__ = ["progress_bar", "LineProgress", "LINE_INTERVAL_S"]

#: seconds between two lines of :class:`LineProgress` (the first and last lines always come)
LINE_INTERVAL_S = 5.0


def progress_bar(desc: str, *, unit: str, total: float | None = None, bar_format: str | None = None,
                 file=None):
    """A progress display for ``verbose=True`` on ``file`` (default stderr): a tqdm bar
    when ``file`` is a terminal or the run is in a notebook, else a :class:`LineProgress`."""
    stream = sys.stderr if file is None else file
    from tqdm import autonotebook, std

    notebook = autonotebook.tqdm is not std.tqdm
    if notebook or _is_terminal(stream):
        from tqdm.auto import tqdm

        kwargs = {} if bar_format is None else {"bar_format": bar_format}
        return tqdm(desc=desc, unit=unit, total=total, leave=False, file=None if notebook else stream,
                    **kwargs)
    return LineProgress(desc, unit=unit, total=total, file=stream)


def _is_terminal(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False


class LineProgress:
    """Progress as plain lines (see the module docstring).

    Parameters
    ----------
    desc : str
        What runs ("mmshbm backbone").
    unit : str
        Unit of ``n`` and ``total`` ("gap", "pt").
    total : float, optional
        The end of the count, shown as ``n/total``.
    file : text stream, optional
        Where the lines go (default stderr, looked up at each line).
    interval : float, optional
        Seconds between lines (default :data:`LINE_INTERVAL_S`).
    """

    def __init__(self, desc: str, *, unit: str = "it", total: float | None = None, file=None,
                 interval: float | None = None):
        self.desc, self.unit, self.total = desc, unit, total
        self.n = 0
        self.postfix = ""
        self._file = file
        self._interval = LINE_INTERVAL_S if interval is None else float(interval)
        self._start = time.monotonic()
        self._last: float | None = None
        self._closed = False

    def update(self, n: float = 1) -> None:
        """Advance the count by ``n``; writes a line when one is due."""
        self.n += n
        self._tick()

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        """The text after the count; a line when ``refresh`` and one is due."""
        self.postfix = str(s)
        if refresh:
            self._tick()

    def set_postfix(self, ordered_dict=None, refresh: bool = True, **kwargs) -> None:
        """The text after the count from ``name=value`` pairs."""
        items = {**dict(ordered_dict or {}), **kwargs}
        self.set_postfix_str(", ".join(f"{k}={v}" for k, v in items.items()), refresh)

    def refresh(self) -> None:
        """Write a line when one is due (the count may have been set through ``n``)."""
        self._tick()

    def close(self) -> None:
        """Write the last line (once)."""
        if not self._closed:
            self._closed = True
            self._write("done")

    def _tick(self) -> None:
        now = time.monotonic()
        if self._closed or (self._last is not None and now - self._last < self._interval):
            return
        self._write()

    def _write(self, note: str = "") -> None:
        self._last = time.monotonic()
        count = f"{self.n:.3g}" + (f"/{self.total:.3g}" if self.total else "") + f" {self.unit}"
        parts = [count] + [p for p in (self.postfix, note) if p]
        stream = sys.stderr if self._file is None else self._file
        stream.write(f"{self.desc}: {', '.join(parts)} [{self._last - self._start:.1f} s]\n")
        stream.flush()
