"""Contacts of a model: a DOF, a gap and the side of the rigid stop.

A :class:`Contact` puts a rigid stop at ``q[dof] = side * gap``: the DOF may move freely
on the other side of that position, and the stop pushes back with a force λ >= 0 when
it is reached,

    g_N = gap - side * q[dof] >= 0,    λ >= 0,    g_N λ = 0.

A model has one or several contacts. The same DOF may carry two contacts with opposite
sides (a clearance: stops at ``+gap₊`` and ``-gap₋``); two contacts on one DOF with the
same side are an error (the nearer stop makes the other one meaningless).

For a DOF with contacts, the admissible positions form an interval ``[lo, hi]``
(:func:`admissible_intervals`), with ``lo = -inf`` or ``hi = +inf`` on a side without a
stop; the methods write the contact law per DOF on that interval.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .. import _validate as check

__all__ = ["Contact", "contacts_from", "admissible_intervals"]


@dataclass(frozen=True)
class Contact:
    """One rigid stop facing one DOF.

    Attributes
    ----------
    dof : int
        Index of the DOF that meets the stop.
    gap : float
        Distance (m, or rad for a rotation) from the DOF's rest position to the stop, >= 0.
    side : {+1, -1}
        The stop is at ``q[dof] = side * gap``.
    """

    dof: int
    gap: float
    side: int

    @property
    def position(self) -> float:
        """Where the stop is: ``side * gap``."""
        return self.side * self.gap


def _as_list(name: str, value) -> tuple[list, bool]:
    """(list of entries, was a sequence) for a scalar or a 1-D sequence."""
    if isinstance(value, str | bytes):
        raise TypeError(f"{name} must be a number or a sequence of numbers, got {value!r}")
    if isinstance(value, np.ndarray):
        if value.ndim > 1:
            raise ValueError(f"{name} must be a scalar or 1-D, got an array of shape {value.shape}")
        return (value.tolist() if value.ndim == 1 else [value.item()]), value.ndim == 1
    if isinstance(value, Sequence):
        return list(value), True
    return [value], False


def contacts_from(contact_dof, gap, stop_side, n_dof: int) -> tuple[Contact, ...]:
    """Validate the contact data of :meth:`Model.from_matrices` and build the contacts.

    Parameters
    ----------
    contact_dof : int or sequence of int
    gap : float or sequence of float
        One gap for all contacts, or one per contact.
    stop_side : {+1, -1} or sequence of them
        One side for all contacts, or one per contact.
    n_dof : int
        Number of DOFs of the model.

    Raises
    ------
    ValueError, TypeError
        Naming the offending value: sequences of different lengths, an empty list, a DOF
        out of range or not an integer, a negative or non-finite gap, a side other than
        ±1, a DOF with two contacts on the same side.
    """
    dofs, dofs_seq = _as_list("contact_dof", contact_dof)
    gaps, gaps_seq = _as_list("gap", gap)
    sides, sides_seq = _as_list("stop_side", stop_side)
    if not dofs:
        raise ValueError("contact_dof is empty: a model needs at least one contact")
    n = len(dofs)
    lengths = {"contact_dof": len(dofs)}
    if gaps_seq:
        lengths["gap"] = len(gaps)
    if sides_seq:
        lengths["stop_side"] = len(sides)
    if len(set(lengths.values())) > 1:
        raise ValueError(f"contact_dof, gap and stop_side must have equal lengths (or be scalars), got "
                         f"lengths {lengths}")
    if not gaps_seq:
        gaps = gaps * n
    if not sides_seq:
        sides = sides * n
    contacts = []
    for i, (d, g, s) in enumerate(zip(dofs, gaps, sides, strict=True)):
        where = f"[{i}]" if n > 1 or dofs_seq else ""
        d = check.integer(f"contact_dof{where}", d)
        if not 0 <= d < n_dof:
            raise ValueError(f"contact_dof{where} must be in [0, {n_dof - 1}], got {d}")
        g = check.non_negative(f"gap{where}", g)
        if isinstance(s, bool) or not isinstance(s, numbers.Real) or s not in (1, -1):
            raise ValueError(f"stop_side{where} must be +1 or -1, got {s!r}")
        contacts.append(Contact(d, g, int(s)))
    seen = {}
    for i, c in enumerate(contacts):
        key = (c.dof, c.side)
        if key in seen:
            side = "+" if c.side > 0 else "-"
            raise ValueError(f"contacts {seen[key]} and {i} both put a stop on the {side} side of DOF "
                             f"{c.dof}: one stop per side of a DOF")
        seen[key] = i
    return tuple(contacts)


def admissible_intervals(contacts: Sequence[Contact]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The DOFs with contacts and the interval of positions their stops allow.

    Returns
    -------
    dofs : ndarray of int, shape (n,)
        The distinct contact DOFs, in order of first appearance.
    lo, hi : ndarray, shape (n,)
        Admissible positions ``lo <= q[dof] <= hi``; ``-inf`` / ``+inf`` where there is no
        stop on that side.

    Raises
    ------
    ValueError
        If the two stops of a clearance leave no room (``lo > hi``).
    """
    order: list[int] = []
    lo: dict[int, float] = {}
    hi: dict[int, float] = {}
    for c in contacts:
        if c.dof not in lo:
            order.append(c.dof)
            lo[c.dof], hi[c.dof] = -math.inf, math.inf
        if c.side > 0:
            hi[c.dof] = c.position
        else:
            lo[c.dof] = c.position
    for d in order:
        if lo[d] > hi[d]:
            raise ValueError(f"the stops of DOF {d} at {lo[d]:g} and {hi[d]:g} leave no room")
    return (np.array(order, dtype=int), np.array([lo[d] for d in order]), np.array([hi[d] for d in order]))
