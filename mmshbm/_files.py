"""File helpers shared by the writers: permissions as ``open`` would give them."""

from __future__ import annotations

import os
import threading

__all__ = ["umask", "apply_umask"]

_lock = threading.Lock()


def umask() -> int:
    """The process's umask (read from /proc where possible, else set and restored under a lock)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    with _lock:
        mask = os.umask(0o022)
        os.umask(mask)
    return mask


def apply_umask(fd: int) -> None:
    """Give the file open on ``fd`` the mode a newly created file gets (0o666 less the
    umask); ``tempfile.mkstemp`` creates its files 0o600, which would leave results and
    checkpoints unreadable to the user's group."""
    os.fchmod(fd, 0o666 & ~umask())
