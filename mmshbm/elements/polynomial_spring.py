"""The polynomial spring: φ(δ) = Σ_p c_p δ^p over powers p >= 2 (the linear part is in K)."""

from __future__ import annotations

import numbers

import numpy as np

from .. import _validate as check
from .base import Element, element_dofs

__all__ = ["PolynomialSpring"]


class PolynomialSpring(Element):
    """A polynomial spring to ground (``dof=i``) or between two DOFs (``dofs=(i, j)``).

    Parameters
    ----------
    dof : int, optional
        The DOF (to ground).
    coefficients : dict int -> float
        {p: c_p}: the restoring force Σ c_p δ^p (c_p in N/m^p), powers p >= 2 (the linear
        stiffness belongs in the model's K), at least one c_p nonzero.
    dofs : (int, int), optional
        The two DOFs (instead of ``dof``).
    """

    kind = "polynomial_spring"

    def __init__(self, dof: int | None = None, coefficients: dict | None = None, *, dofs=None):
        if not isinstance(coefficients, dict) or not coefficients:
            raise TypeError(f"coefficients must be a non-empty dict power -> coefficient, e.g. "
                            f"{{2: k2, 3: k3}}, got {coefficients!r}")
        terms = {}
        for p, c in coefficients.items():
            if isinstance(p, str) and p.isdigit():  # the JSON form's keys
                p = int(p)
            if isinstance(p, bool) or not isinstance(p, numbers.Integral) or p < 2:
                raise ValueError(f"the powers of a PolynomialSpring must be integers >= 2 (the linear "
                                 f"stiffness belongs in K), got {p!r}")
            value = check.real_number(f"coefficients[{int(p)}]", c)
            if value != 0:
                terms[int(p)] = value
        if not terms:
            raise ValueError(f"every coefficient of the PolynomialSpring is zero: {coefficients!r}")
        self._set(dofs=element_dofs(dof, dofs), coefficients=dict(sorted(terms.items())))

    def law(self, delta):
        delta = np.asarray(delta, dtype=float)
        phi = np.zeros_like(delta)
        dphi = np.zeros_like(delta)
        for p, c in self.coefficients.items():
            lower = delta ** (p - 1)
            phi += c * lower * delta
            dphi += p * c * lower
        return phi, dphi

    def potential(self, delta):
        delta = np.asarray(delta, dtype=float)
        return sum(c * delta ** (p + 1) / (p + 1) for p, c in self.coefficients.items())

    @property
    def degree(self) -> int:
        return max(self.coefficients)

    def length_scale(self, stiffness: float) -> float:
        """The smallest |δ| at which one term's force equals the linear one, (k/|c_p|)^(1/(p−1))."""
        return float(min((abs(stiffness) / abs(c)) ** (1.0 / (p - 1)) for p, c in self.coefficients.items()))

    def to_json(self) -> dict:
        return {"kind": self.kind, "dofs": list(self.dofs),
                "coefficients": {str(p): c for p, c in self.coefficients.items()}}
