"""Nonlinear elements a model can carry beside its stops and friction contacts.

``model.with_element(mmshbm.elements.CubicSpring(dof=0, stiffness=k3))`` adds one; the
protocol a law implements is :class:`Element` (:mod:`mmshbm.elements.base`). Each element
is one module and one entry of :data:`ELEMENTS`; the methods that take an element are
named in :data:`mmshbm.methods.registry.METHOD_ELEMENTS`.
"""

from __future__ import annotations

from .base import Element
from .compliant_stop import CompliantStop
from .cubic_spring import CubicSpring
from .polynomial_spring import PolynomialSpring

__all__ = ["ELEMENTS", "CompliantStop", "CubicSpring", "Element", "PolynomialSpring", "from_json"]

#: element kind (``Element.kind``, the JSON ``kind``) -> its class
ELEMENTS: dict[str, type[Element]] = {
    CubicSpring.kind: CubicSpring,
    PolynomialSpring.kind: PolynomialSpring,
    CompliantStop.kind: CompliantStop,
}


def from_json(record: dict) -> Element:
    """The element of a JSON record (:meth:`Element.to_json`).

    Raises
    ------
    ValueError
        An unknown ``kind`` or a malformed record.
    """
    if not isinstance(record, dict) or record.get("kind") not in ELEMENTS:
        kind = record.get("kind") if isinstance(record, dict) else record
        raise ValueError(f"unknown element kind {kind!r}; known: {sorted(ELEMENTS)}")
    args = {k: v for k, v in record.items() if k != "kind"}
    dofs = args.pop("dofs", None)
    try:
        return ELEMENTS[record["kind"]](dofs=dofs, **args)
    except TypeError as err:
        raise ValueError(f"malformed {record['kind']} record {record!r}: {err}") from None
