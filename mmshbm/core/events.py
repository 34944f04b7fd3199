"""Event plug-ins of the continuation driver.

The path follower (:func:`mmshbm.core.continuation.continue_branch`) knows nothing of
what a branch means. Whatever watches the points for a reason to leave the path, and
takes the branch elsewhere, is an event plug-in with the protocol :class:`BranchEvents`:

* ``replay(records, special)``: a resumed run registers the points it holds (the same
  decisions as the run that made them);
* ``observe(index, record)``: a converged step's point, before the driver stores it (the
  plug-in may annotate the record); returns the reason to relocate after it, or None;
* ``at_bound(index, record)``: the same for a point refined onto a bound; a reason means
  the bound does not end the branch;
* ``at_ds_min()``: the step size fell below ``ds_min``; a reason means the branch is
  relocated instead of ending;
* ``relocate(problem, points, records, reason, index)``: the points where the branch goes
  on (:class:`Relocation`), ``index`` being the index the first of them gets; raises
  :class:`RelocationFailed`;
* ``register(index, record, first)``: each relocated point, before the driver stores it.

The driver accepts a relocation's points in order (the first one carries its special
point), goes on from the last one with the initial step, and ends the branch there if
the relocation says so. :class:`NoEvents` is plain path following; the family of a
nonlinear mode is followed by :class:`mmshbm.family.follower.FamilyFollower`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

from .special_points import SpecialPoint
from .status import Status

__all__ = ["BranchEvents", "NoEvents", "Relocation", "RelocationFailed"]


class RelocationFailed(ArithmeticError):
    """A plug-in could not relocate the branch (the message says why). ``kind``, when
    given, is the status kind that ends the branch instead of the caller's (e.g.
    ``Status.FAMILY_ENDED``); ``cause``, when given, the structured reason the message
    is built from (it becomes the final status's :attr:`~mmshbm.core.status.Status.cause`)."""

    def __init__(self, message: str = "", kind: str | None = None, cause: object = None):
        super().__init__(message)
        self.kind = kind
        self.cause = cause


@dataclass
class Relocation:
    """Where a branch goes on after an event.

    Attributes
    ----------
    points : list of tuple
        (u, Newton iterations, residual history, record, unit tangent) per point, in the
        order they join the branch; the branch goes on from the last.
    special : SpecialPoint
        The special point of the first one.
    terminal : Status or None
        The branch ends on the last point with this status.
    """

    points: list
    special: SpecialPoint
    terminal: Status | None = None


@runtime_checkable
class BranchEvents(Protocol):
    """What the driver asks of an event plug-in (see the module docstring)."""

    def replay(self, records: list, special: list) -> None: ...

    def observe(self, index: int, record: dict) -> str | None: ...

    def at_bound(self, index: int, record: dict) -> str | None: ...

    def at_ds_min(self) -> str | None: ...

    def relocate(self, problem, points: list, records: list, reason: str, index: int) -> Relocation: ...

    def register(self, index: int, record: dict, first: bool) -> None: ...


class NoEvents:
    """Plain path following: no event ever relocates the branch."""

    def replay(self, records: list, special: list) -> None:
        pass

    def observe(self, index: int, record: dict) -> str | None:
        return None

    def at_bound(self, index: int, record: dict) -> str | None:
        return None

    def at_ds_min(self) -> str | None:
        return None

    def relocate(self, problem, points: list, records: list, reason: str, index: int) -> Relocation:
        raise RelocationFailed("plain path following does not relocate")

    def register(self, index: int, record: dict, first: bool) -> None:
        pass
