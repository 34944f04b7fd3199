"""Exceptions of the numerical core shared by its modules (no imports: any core module may
raise them without an import cycle)."""

from __future__ import annotations

__all__ = ["SingularDynamicStiffness"]


class SingularDynamicStiffness(ArithmeticError):
    """K_ll − (kΩ)² M_ll is singular: kΩ hits an eigenfrequency of the clamped-contact structure."""
