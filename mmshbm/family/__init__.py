"""The family of a nonlinear mode: which orbits belong to it and how a backbone stays on it.

Method-agnostic; it uses the continuation core (:mod:`mmshbm.core`) and nothing above it,
and core does not know it: the methods' runs pass its follower to the driver as an event
plug-in (:func:`mmshbm.family.follower.default_events`).

* :mod:`~mmshbm.family.definition`: the definition, a predicate on one orbit
  (docs/resonances.md);
* :mod:`~mmshbm.family.options`: :class:`~mmshbm.family.options.FamilyOptions`, every
  threshold of the decisions (the solvers' numerics, such as Newton's iteration counts or
  the deflation operator's exponent, are the solvers' own);
* :mod:`~mmshbm.family.guard`: which points of a branch are on the family, and when the
  branch has left it;
* :mod:`~mmshbm.family.follower`: the continuation driver's event plug-in (search beyond
  the frontier, backfill);
* :mod:`~mmshbm.family.deflation`: the one search beyond a frontier, deflated Newton at
  pinned amplitudes;
* :mod:`~mmshbm.family.end`: why a family ends, as a value
  (:class:`~mmshbm.family.end.FamilyEnd`).

Importing the package imports only the options and the definition.
"""

from .definition import FAMILY_RECORD, family_value, on_family
from .options import FamilyOptions

__all__ = ["FAMILY_RECORD", "FamilyOptions", "family_value", "on_family"]
