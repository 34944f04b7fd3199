"""The compliant stop: a unilateral spring of finite stiffness behind a gap,
φ(δ) = s k (s δ − g)₊ (piecewise linear: one kink, at the gap)."""

from __future__ import annotations

import numpy as np

from .. import _validate as check
from .base import Element, element_dofs

__all__ = ["CompliantStop"]


class CompliantStop(Element):
    """A stop that yields: a spring of ``stiffness`` that engages beyond ``gap``.

    With ``side = +1`` the spring touches when δ = q_i (or q_i − q_j) exceeds ``gap`` and
    pushes back with k (δ − gap); ``side = -1`` mirrors it (engages below −gap). A rigid
    stop is the limit k → ∞ (the model's contacts, :meth:`mmshbm.Model.from_matrices`).

    Parameters
    ----------
    dof : int, optional
        The DOF (to ground).
    gap : float
        g >= 0 (m): the clearance before the spring engages.
    stiffness : float
        k > 0 (N/m).
    side : {+1, -1}
        Which way the stop faces.
    dofs : (int, int), optional
        Two DOFs (instead of ``dof``): a stop on their relative displacement.
    """

    kind = "compliant_stop"

    def __init__(self, dof: int | None = None, gap: float | None = None, stiffness: float | None = None,
                 side: int = 1, *, dofs=None):
        if gap is None or stiffness is None:
            raise TypeError("CompliantStop needs gap= (m) and stiffness= (N/m)")
        if side not in (1, -1) or isinstance(side, bool):
            raise ValueError(f"side must be +1 or -1, got {side!r}")
        self._set(dofs=element_dofs(dof, dofs), gap=check.non_negative("gap", gap),
                  stiffness=check.positive("stiffness", stiffness), side=int(side))

    def law(self, delta):
        overlap = self.side * np.asarray(delta, dtype=float) - self.gap
        touching = overlap > 0
        force = (self.side * self.stiffness) * np.where(touching, overlap, 0.0)
        return force, np.where(touching, self.stiffness, 0.0)

    def potential(self, delta):
        overlap = np.maximum(self.side * np.asarray(delta, dtype=float) - self.gap, 0.0)
        return 0.5 * self.stiffness * overlap * overlap

    def length_scale(self, stiffness: float) -> float:
        """The gap (1 m at zero gap: a bilinear spring has no length of its own)."""
        return self.gap if self.gap > 0 else 1.0

    def to_json(self) -> dict:
        return {"kind": self.kind, "dofs": list(self.dofs), "gap": self.gap, "stiffness": self.stiffness,
                "side": self.side}
