"""The functions of this layer that the results call (to rebuild a solver, redo a run,
give admissible signals), registered with :mod:`mmshbm.results.base` when the methods
package is imported.

Each is a thin wrapper that imports its module on first call, so that importing the
methods package stays cheap; the results layer, below this one, never imports it.
"""

from __future__ import annotations

from ..results.base import register_entry_point

__all__ = []


def _make_problem(*args, **kwargs):
    from .registry import make_problem

    return make_problem(*args, **kwargs)


def _backbone(*args, **kwargs):
    from .backbone import backbone

    return backbone(*args, **kwargs)


def _admissible_signals(*args, **kwargs):
    from ..contact.static import branch_signals

    return branch_signals(*args, **kwargs)


def _make_forced_problem(*args, **kwargs):
    from .frequency_response import make_forced_problem

    return make_forced_problem(*args, **kwargs)


def _held_frequency(*args, **kwargs):
    from .mms.held import _held_frequency

    return _held_frequency(*args, **kwargs)


register_entry_point("make_problem", _make_problem)
register_entry_point("backbone", _backbone)
register_entry_point("admissible_signals", _admissible_signals)
register_entry_point("make_forced_problem", _make_forced_problem)
register_entry_point("held_frequency", _held_frequency)
