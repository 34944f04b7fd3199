"""Finite elements of the beam: Timoshenko element, graded meshes, assembly, clamping, massless tip."""

from .beam import TimoshenkoBeam, default_beam
from .lap_joint import LapJoint, lap_joint

__all__ = ["LapJoint", "TimoshenkoBeam", "default_beam", "lap_joint"]
