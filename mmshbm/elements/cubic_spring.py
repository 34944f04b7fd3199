"""The cubic spring: φ(δ) = k₃ δ³ (geometric stiffening, the Duffing oscillator's law)."""

from __future__ import annotations

import numpy as np

from .. import _validate as check
from .base import Element, element_dofs

__all__ = ["CubicSpring"]


class CubicSpring(Element):
    """A cubic spring to ground (``dof=i``) or between two DOFs (``dofs=(i, j)``).

    Adds the restoring force k₃ δ³ on δ = q_i (or q_i − q_j); with k = 1 on a unit mass,
    x'' + x + k₃ x³ = 0 is the Duffing oscillator.

    Parameters
    ----------
    dof : int, optional
        The DOF (to ground).
    stiffness : float
        k₃ (N/m³; N·m/rad³ on a rotation), nonzero: > 0 hardens, < 0 softens.
    dofs : (int, int), optional
        The two DOFs (instead of ``dof``): the force k₃ δ³ on i, −k₃ δ³ on j.
    """

    kind = "cubic_spring"

    def __init__(self, dof: int | None = None, stiffness: float | None = None, *, dofs=None):
        if stiffness is None:
            raise TypeError("CubicSpring needs stiffness= (k3, N/m^3)")
        k3 = check.real_number("stiffness", stiffness)
        if k3 == 0:
            raise ValueError("stiffness of a CubicSpring must be nonzero (k3 = 0 is no element)")
        self._set(dofs=element_dofs(dof, dofs), stiffness=k3)

    def law(self, delta):
        delta = np.asarray(delta, dtype=float)
        d2 = delta * delta
        return self.stiffness * d2 * delta, 3.0 * self.stiffness * d2

    def potential(self, delta):
        d2 = np.square(np.asarray(delta, dtype=float))
        return 0.25 * self.stiffness * d2 * d2

    @property
    def degree(self) -> int:
        return 3

    def length_scale(self, stiffness: float) -> float:
        """√(k/|k₃|): where the cubic force equals the linear one."""
        return float(np.sqrt(abs(stiffness) / abs(self.stiffness)))

    def to_json(self) -> dict:
        return {"kind": self.kind, "dofs": list(self.dofs), "stiffness": self.stiffness}
