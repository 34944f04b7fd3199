"""The element protocol: what a smooth (or piecewise-smooth) nonlinear law gives the methods.

An element acts on one DOF against ground or between two DOFs of a model. Its law is a
scalar force φ(δ) of the relative displacement

    δ = wᵀ q_e,    w = (1,) on one DOF, (1, −1) between DOFs (i, j),

and it adds the restoring force w φ(δ) to the left-hand side of the equations of motion,

    M q'' + C q' + K q + Σ_elements w φ(wᵀ q_e) = f(t).

That is all a harmonic-balance method with alternating frequency–time (AFT) needs: the law
and its derivative φ'(δ) sampled in time (the force on the element's DOFs, w φ, and its
Jacobian, w wᵀ φ'), plus its potential V(δ) (V' = φ) for the energy of a point. A law
supplies :meth:`Element.law` and :meth:`Element.potential`; everything else (the DOFs,
the direction w, the sampled force and Jacobian, validation, JSON) is here.

The laws are *displacement* laws: no rate dependence, so a conservative structure with
elements stays conservative and time-reversible (the cosine-only ansatz of the MMS-HBM
backbone applies).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import ClassVar

import numpy as np

from .. import _validate as check

__all__ = ["Element", "element_dofs"]


def element_dofs(dof, dofs) -> tuple[int, ...]:
    """The DOFs of an element from its ``dof=`` or ``dofs=`` argument: ``(i,)`` or ``(i, j)``.

    Raises
    ------
    ValueError, TypeError
        Neither or both given, not one or two integers >= 0, or twice the same DOF.
    """
    if (dof is None) == (dofs is None):
        raise ValueError("give exactly one of dof= (an element to ground) and dofs=(i, j) (between two DOFs)")
    if dof is not None:
        return (check.integer("dof", dof, minimum=0),)
    if isinstance(dofs, int | np.integer):
        return (check.integer("dofs", dofs, minimum=0),)
    try:
        out = tuple(check.integer("dofs", d, minimum=0) for d in dofs)
    except TypeError:
        raise TypeError(f"dofs must be one DOF or a pair (i, j) of DOFs, got {dofs!r}") from None
    if len(out) not in (1, 2):
        raise ValueError(f"dofs must be one DOF or a pair (i, j) of DOFs, got {len(out)}: {dofs!r}")
    if len(out) == 2 and out[0] == out[1]:
        raise ValueError(f"dofs must be two different DOFs, got {dofs!r}")
    return out


class Element(ABC):
    """A nonlinear element: a scalar law φ(δ) on δ = wᵀ q_e (module docstring).

    Subclasses set (with :meth:`_set`, in their ``__init__``) the attribute ``dofs`` (tuple
    of one or two DOF indices) and their parameters, define a class attribute ``kind``
    (the name they are registered under in :data:`mmshbm.elements.ELEMENTS`) and the
    methods :meth:`law`, :meth:`potential` and :meth:`to_json`; they may override
    :attr:`degree` and :meth:`length_scale`.
    """

    #: the registered name of the element (JSON ``kind``, the registry's element names)
    kind: ClassVar[str] = ""
    dofs: tuple[int, ...]

    # elements are values: immutable, equal when their JSON forms are
    def __setattr__(self, name, value):
        raise AttributeError(f"{type(self).__name__} is immutable: build a new one")

    def _set(self, **values) -> None:
        """Set the attributes of a new element (its ``__init__`` only)."""
        for name, value in values.items():
            object.__setattr__(self, name, value)

    def __eq__(self, other) -> bool:
        return type(other) is type(self) and other.to_json() == self.to_json()

    def __hash__(self) -> int:
        return hash(repr(self))

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.to_json().items() if k != "kind")
        return f"{type(self).__name__}({args})"

    # ------------------------------------------------------------------ the law
    @abstractmethod
    def law(self, delta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(φ(δ), φ'(δ)) at the samples ``delta`` (any shape, m or rad): the restoring force
        (N, N·m) and its derivative (N/m), arrays of ``delta``'s shape."""

    @abstractmethod
    def potential(self, delta: np.ndarray) -> np.ndarray:
        """V(δ) (J) with V(0) = 0 and V' = φ, at the samples ``delta``."""

    @property
    def degree(self) -> int | None:
        """The degree of φ when it is a polynomial (AFT on N >= (degree + 1) H + 1 samples
        is then exact), None for a law with kinks."""
        return None

    def length_scale(self, stiffness: float) -> float:
        """The displacement (m) at which the element's force is comparable with that of a
        linear spring of ``stiffness`` (N/m): what the methods scale the unknowns by."""
        return 1.0

    @abstractmethod
    def to_json(self) -> dict:
        """JSON-able form, ``{"kind": ..., "dofs": [...], **parameters}``
        (:func:`mmshbm.elements.from_json` inverts it)."""

    # ------------------------------------------------------------------ geometry
    @property
    def direction(self) -> np.ndarray:
        """w (len(dofs),): δ = wᵀ q[dofs]; (1,) to ground, (1, −1) between two DOFs."""
        return np.array([1.0]) if len(self.dofs) == 1 else np.array([1.0, -1.0])

    def check_model(self, n_dof: int) -> None:
        """ValueError unless every DOF of the element is a DOF of a model with ``n_dof`` DOFs."""
        bad = [d for d in self.dofs if not 0 <= d < n_dof]
        if bad:
            raise ValueError(f"{type(self).__name__} acts on DOF{'s' if len(bad) > 1 else ''} {bad}, "
                             f"outside the model's DOFs 0..{n_dof - 1}")

    def relative(self, q: np.ndarray) -> np.ndarray:
        """δ = wᵀ q_e from samples ``q`` (len(dofs), ...) of the element's DOFs."""
        q = np.asarray(q, dtype=float)
        return q[0] if len(self.dofs) == 1 else q[0] - q[1]

    def sampled(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The force on the element's DOFs and its Jacobian, sampled in time.

        Parameters
        ----------
        q : ndarray, shape (n_e, N)
            Displacements of the element's DOFs (``dofs`` order) at N instants, n_e =
            len(dofs).

        Returns
        -------
        f : ndarray, shape (n_e, N)
            w φ(δ) (N): the restoring force on each DOF.
        df : ndarray, shape (n_e, n_e, N)
            ∂f/∂q = w wᵀ φ'(δ) (N/m).
        """
        phi, dphi = self.law(self.relative(q))
        w = self.direction
        return w[:, None] * phi[None, :], (w[:, None] * w[None, :])[:, :, None] * dphi[None, None, :]
