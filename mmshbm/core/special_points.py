"""Named points of a branch: start, grazing, folds, branch points, internal resonances,
jumps, bound hits, the endpoint.

A :class:`SpecialPoint` is a pair ``(kind, index)`` (it unpacks and compares like the
tuples of mmshbm 0.1) that also carries a dict :attr:`~SpecialPoint.data` of facts about
the point, e.g. for an internal resonance the harmonic ``k``, the mode ``j`` and the
frequency ratio ``kΩ/ω_j``; for a jump the skipped amplitude interval.

Kinds used by the package:

``"start"``, ``"endpoint"``
    First and last point.
``"grazing"``
    First point where a stop carries force (``contact_force_max`` > 0; where the force
    is not recorded, whose amplitude exceeds the gap): :func:`mmshbm.methods.runner.mark_grazing`.
``"fold"``
    The frequency turns back (the tangent's Ω-component changes sign).
``"branch_point"``
    The bordered Jacobian's determinant changes sign: another branch crosses.
``"internal_resonance"``
    Harmonic ``k`` of the motion meets mode ``j`` (kΩ ≈ ω_j, energy in mode j peaks).
``"jump"``
    The continuation left the starting mode's family and was restarted beyond the tongue.
    The point is the first one after the jump. ``data``: ``reason``; ``amplitude_frontier``
    (m), the largest amplitude reached on the family before the jump, and ``amplitude_to``
    (m), this point's: the family is not sampled between them (can be an empty
    interval when the tongue splits the backbone in frequency only); ``from_index`` and
    ``amplitude_from``, the family point the predictor was extrapolated from;
    ``landing_amplitude`` (m), where the pinned solve landed (points between
    ``amplitude_to`` and it were filled back down from the landing); ``frequency_from``,
    ``frequency_to`` (Hz).
``"bound:<name>"``
    The branch stopped on a bound of a monitored quantity.
"""

from __future__ import annotations

__all__ = ["SpecialPoint", "special_to_json", "special_from_json"]


class SpecialPoint(tuple):
    """``(kind, index)`` with extra facts in :attr:`data`.

    Parameters
    ----------
    kind : str
        What the point is (see the module docstring).
    index : int
        Its position on the branch.
    **data
        JSON-serialisable facts (numbers, strings, lists).
    """

    def __new__(cls, kind: str, index: int, **data):
        self = super().__new__(cls, (str(kind), int(index)))
        self.data = dict(data)
        return self

    @property
    def kind(self) -> str:
        return self[0]

    @property
    def index(self) -> int:
        return self[1]

    def __repr__(self) -> str:
        extra = "".join(f", {k}={v!r}" for k, v in self.data.items())
        return f"SpecialPoint({self[0]!r}, {self[1]}{extra})"

    def __getnewargs_ex__(self):  # pickling (process pools)
        return (self[0], self[1]), dict(self.data)


def special_to_json(points) -> list:
    """Special points as JSON lists ``[kind, index]`` or ``[kind, index, data]``."""
    out = []
    for p in points:
        data = getattr(p, "data", None)
        out.append([str(p[0]), int(p[1])] + ([_plain(data)] if data else []))
    return out


def special_from_json(items) -> list[SpecialPoint]:
    """Inverse of :func:`special_to_json` (also reads the pairs of format 1)."""
    return [SpecialPoint(item[0], item[1], **(item[2] if len(item) > 2 else {})) for item in items]


def _plain(x):
    import numpy as np

    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_plain(v) for v in x]
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    return x
