"""The structure: mass and stiffness, massless contact DOFs, the rigid stop (the bottom
layer; it imports nothing else of mmshbm)."""

from .model import Model

__all__ = ["Model"]
