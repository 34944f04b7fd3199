"""What a branch's checks report: the thresholds they use and the findings they make
(:mod:`mmshbm.results.diagnostics` runs them)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["CheckThresholds", "Finding", "where"]


@dataclass(frozen=True)
class CheckThresholds:
    """The tolerances of :func:`check_branch` (all dimensionless).

    Attributes
    ----------
    min_mode_share : float
        A point belongs to the family of its starting mode while that mode carries at
        least this share of the period-mean kinetic energy.
    penetration : float
        Allowed excursion of a contact DOF beyond its stop, in gaps (in amplitudes of the
        point when the gap is 0).
    negative_force : float
        Allowed tensile contact force, as a fraction of the point's peak force.
    force_floor : float
        Forces below this fraction of max(branch's largest contact force, k_c·gap) are
        round-off.
    n_samples : int
        Time samples per period for the signal checks and for shooting's coefficients.
    """

    min_mode_share: float = 0.5
    penetration: float = 0.05
    negative_force: float = 0.05
    force_floor: float = 1e-9
    n_samples: int = 256

    def __post_init__(self):
        for name in ("min_mode_share", "penetration", "negative_force", "force_floor"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and np.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
        if not isinstance(self.n_samples, int) or self.n_samples < 8:
            raise ValueError(f"n_samples must be an integer >= 8, got {self.n_samples!r}")


@dataclass(frozen=True)
class Finding:
    """One problem of a branch.

    Attributes
    ----------
    kind : str
        "left_family", "coexisting_orbits", "penetration", "negative_force" or
        "incomplete".
    message : str
        One line for a person.
    first, last : int
        The first and last branch point concerned (-1 when none, e.g. an empty branch).
    value : float
        The extreme value (lowest share, deepest penetration in gaps, most negative
        force ratio; NaN for "incomplete").
    """

    kind: str
    message: str
    first: int = -1
    last: int = -1
    value: float = float("nan")

    def to_dict(self) -> dict:
        """The fields as a dict (``asdict``'s, its fields being plain values), ``value``
        None when not finite."""
        value = self.value
        return {"kind": self.kind, "message": self.message, "first": self.first, "last": self.last,
                "value": None if not np.isfinite(value) else float(value)}

    @classmethod
    def from_dict(cls, d: dict) -> Finding:
        value = d.get("value")
        return cls(str(d["kind"]), str(d["message"]), int(d.get("first", -1)), int(d.get("last", -1)),
                   float("nan") if value is None else float(value))


def where(branch, i: int) -> str:
    gap = branch.gap
    amp = branch.amplitude[i]
    a = f"{amp / gap:.3g} gaps" if gap else f"{amp:.3g} m"
    return f"point {i}, {branch.frequency[i]:.4g} Hz, {a}"
