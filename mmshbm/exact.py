"""Exact periodic orbits of piecewise-linear models: the public home of the exact references.

``mmshbm.exact`` (``import mmshbm.exact`` or ``from mmshbm import exact``) gives the
event-driven solutions of :mod:`mmshbm.methods.exact`, where they are implemented and
documented: :func:`periodic_orbit`, :func:`backbone`, :func:`friction_orbit`, :func:`integrate`
and the classes they return.
"""

from __future__ import annotations

from .methods.exact import (
    Backbone,
    Event,
    FrictionOrbit,
    FrictionSystem,
    PeriodicOrbit,
    Phase,
    PiecewiseLinearSystem,
    Trajectory,
    backbone,
    friction_orbit,
    integrate,
    periodic_orbit,
)

__all__ = ["Event", "Phase", "PiecewiseLinearSystem", "Trajectory", "PeriodicOrbit", "Backbone", "integrate",
           "periodic_orbit", "backbone", "FrictionSystem", "FrictionOrbit", "friction_orbit"]
