"""Functions of a higher layer that a lower one calls, by name.

The results (:mod:`mmshbm.results`) rebuild the solver that computed them and redo their
run with functions of the methods layer above them. Instead of importing upward, they look
the functions up here; the methods package registers them when it is imported
(:mod:`mmshbm.methods.entry_points`), and the package's root adds a loader that imports it
when a name is missing (a result loaded from a file before any method ran). This module
imports nothing.
"""

from __future__ import annotations

from collections.abc import Callable

__all__ = ["register", "lookup", "add_loader"]

_REGISTRY: dict[str, Callable] = {}
_LOADERS: list[Callable[[], object]] = []


def register(name: str, function: Callable) -> None:
    """Make ``function`` the entry point ``name``."""
    _REGISTRY[name] = function


def add_loader(loader: Callable[[], object]) -> None:
    """Call ``loader()`` (which imports the registering modules) when a name is missing."""
    _LOADERS.append(loader)


def lookup(name: str) -> Callable:
    """The function registered as ``name``, running the loaders first if it is missing.

    Raises
    ------
    LookupError
        When no loader registers it.
    """
    if name not in _REGISTRY:
        for loader in list(_LOADERS):
            loader()
    try:
        return _REGISTRY[name]
    except KeyError:
        raise LookupError(f"no entry point {name!r} is registered (registered: {sorted(_REGISTRY)})") \
            from None
