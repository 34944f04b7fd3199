"""Finite elements of the beam: Timoshenko element, graded meshes, assembly, clamping, massless tip."""

from .beam import TimoshenkoBeam, default_beam

__all__ = ["TimoshenkoBeam", "default_beam"]
