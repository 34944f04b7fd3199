"""Small models with closed-form answers, for tests, benchmarks and teaching.

:class:`OneDofOscillator` is the one-DOF analogue of the beam with impact: a mass ``m`` on
a spring ``k1`` to ground, a massless node joined to the mass by a spring ``k2``, and a
rigid stop ``gap`` away on the positive side of the node. DOFs: ``q = [x_mass, x_node]``.
Its backbone is known in closed form (``period``), which is the project's sharpest
ground truth for the harmonic-balance and shooting solvers. :class:`ClearanceOscillator`
is the same oscillator with stops on both sides of the node (a clearance ±g), the
closed-form ground truth for several contacts.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import _validate as check
from ..model.model import Model

__all__ = ["OneDofOscillator", "ClearanceOscillator", "one_dof_oscillator"]


@dataclass(frozen=True)
class OneDofOscillator:
    """Mass–spring oscillator whose massless node hits a stop.

    Parameters
    ----------
    m : float
        Mass (kg).
    k1 : float
        Spring from the mass to ground (N/m).
    k2 : float
        Spring from the mass to the massless contact node (N/m).
    gap : float
        Distance (m) from the node's rest position to the stop, on the + side.
    """

    m: float = 1.0
    k1: float = 1.0
    k2: float = 4.0
    gap: float = 1.0

    def __post_init__(self):
        for name in ("m", "k1", "k2"):
            check.positive(name, getattr(self, name))
        check.non_negative("gap", self.gap)

    @property
    def omega_open(self) -> float:
        """ω1 = √(k1/m), rad/s: the contact open."""
        return float(np.sqrt(self.k1 / self.m))

    @property
    def omega_closed(self) -> float:
        """ω2 = √((k1+k2)/m), rad/s: the node held at the stop."""
        return float(np.sqrt((self.k1 + self.k2) / self.m))

    @property
    def contact_stiffness(self) -> float:
        """Static stiffness seen at the node (N/m): k1 k2 / (k1 + k2)."""
        return self.k1 * self.k2 / (self.k1 + self.k2)

    def model(self) -> Model:
        """The oscillator as a :class:`Model` built with ``Model.from_matrices``."""
        M = np.array([[self.m, 0.0], [0.0, 0.0]])
        K = np.array([[self.k1 + self.k2, -self.k2], [-self.k2, self.k2]])
        return Model.from_matrices(M, K, contact_dof=1, gap=self.gap, stop_side=+1,
                                   description={"kind": "OneDofOscillator", "m": self.m, "k1": self.k1,
                                                "k2": self.k2, "gap": self.gap})

    def period(self, amplitude) -> np.ndarray:
        """Closed-form period (s) of the free motion of largest excursion ``amplitude`` (m)
        away from the stop (docs/design.md §5).

        T = (2/ω1) arccos(−g0/A) + (2/ω2) arccos(k1 g0 / ((k1+k2) B)) for A > g0,
        B = √((k1 g0/(k1+k2))² + (ω1/ω2)² (A² − g0²)); T = 2π/ω1 for A <= g0.
        """
        A = np.asarray(amplitude, dtype=float)
        if np.any(~np.isfinite(A)) or np.any(A < 0):
            raise ValueError(f"amplitude must be finite and >= 0, got {amplitude!r}")
        w1, w2, g0 = self.omega_open, self.omega_closed, self.gap
        k1, k2 = self.k1, self.k2
        T_lin = 2 * np.pi / w1
        with np.errstate(invalid="ignore", divide="ignore"):
            Ac = np.maximum(A, g0)
            B = np.sqrt((k1 * g0 / (k1 + k2)) ** 2 + (w1 / w2) ** 2 * (Ac**2 - g0**2))
            ratio = np.where(B > 0, k1 * g0 / ((k1 + k2) * np.where(B > 0, B, 1.0)), 1.0)
            T = 2 / w1 * np.arccos(np.clip(-g0 / np.where(Ac > 0, Ac, 1.0), -1, 1)) \
                + 2 / w2 * np.arccos(np.clip(ratio, -1, 1))
        return np.where(A > g0, T, T_lin)

    def frequency(self, amplitude) -> np.ndarray:
        """Closed-form backbone: frequency (Hz) at ``amplitude`` (m)."""
        return 1.0 / self.period(amplitude)

    def zero_gap_frequency(self) -> float:
        """Limit of the backbone for amplitude → ∞ (Hz): 1 / (π/ω1 + π/ω2)."""
        return 1.0 / (np.pi / self.omega_open + np.pi / self.omega_closed)


@dataclass(frozen=True)
class ClearanceOscillator:
    """Mass–spring oscillator whose massless node moves in a symmetric clearance ±gap.

    A mass ``m`` on a spring ``k1`` to ground, a massless node joined to the mass by a
    spring ``k2``, and two rigid stops at ``±gap`` facing the node. DOFs
    ``q = [x (mass), y (node)]``; two contacts on the node, ``(1, gap, +1)`` and
    ``(1, gap, −1)``; the amplitude is measured at the mass (``amplitude_dof = 0``): the
    node never passes ±gap, so its largest excursion says nothing above the gap.

    Closed-form period (derivation)
    -------------------------------
    The node is massless, so it is in static equilibrium at every instant.

    * *Open* (|y| < gap): the node's equation k2 (y − x) = 0 gives y = x, so the phase
      holds while |x| < gap and the mass obeys x'' + ω1² x = 0, ω1 = √(k1/m).
    * *In contact with +gap*: y = gap and the stop's force λ = k2 (x − gap) must be
      >= 0, so the phase holds while x >= gap; the mass obeys
      m x'' + k1 x + k2 (x − gap) = 0, i.e. x'' + ω2² (x − x*) = 0 with
      ω2 = √((k1+k2)/m) about the shifted centre x* = k2 gap / (k1 + k2).
      The stop at −gap mirrors it (x <= −gap, centre −x*).

    Positions and velocities are continuous at the switches (no impact: the node has no
    mass). The system is odd-symmetric, so the periodic orbit of amplitude A = max|x| > gap
    is quarter-wave symmetric: from the turning point x = A (in contact, the contact arc
    x − x* = (A − x*) cos ω2 t) the mass reaches x = gap after

        t2 = arccos((gap − x*) / (A − x*)) / ω2,

    (gap − x* = k1 gap/(k1 + k2) > 0), with speed v = ω2 √((A − x*)² − (gap − x*)²); the
    open arc from gap to 0 is a sine of amplitude X = √(gap² + v²/ω1²) (energy
    ½ v² + ½ ω1² x² of the open phase), traversed in

        t1 = arcsin(gap / X) / ω1.

    The period is T(A) = 4 (t1 + t2); for A <= gap the motion is linear, T = 2π/ω1.
    Checks: A → gap⁺ gives t2 → 0, X → gap, T → 2π/ω1 (continuous at grazing); A → ∞ gives
    t1 → 0, t2 → π/(2 ω2), T → 2π/ω2 (the contact spring k2 always engaged).

    Parameters
    ----------
    m : float
        Mass (kg).
    k1 : float
        Spring from the mass to ground (N/m).
    k2 : float
        Spring from the mass to the massless node (N/m).
    gap : float
        Distance (m) from the node's rest position to each stop, > 0.
    """

    m: float = 1.0
    k1: float = 1.0
    k2: float = 4.0
    gap: float = 1.0

    def __post_init__(self):
        for name in ("m", "k1", "k2", "gap"):
            check.positive(name, getattr(self, name))

    @property
    def omega_open(self) -> float:
        """ω1 = √(k1/m), rad/s: the node between the stops."""
        return float(np.sqrt(self.k1 / self.m))

    @property
    def omega_closed(self) -> float:
        """ω2 = √((k1+k2)/m), rad/s: the node held at a stop."""
        return float(np.sqrt((self.k1 + self.k2) / self.m))

    @property
    def centre(self) -> float:
        """x* = k2 gap / (k1 + k2) (m): the centre of the contact arcs at +gap."""
        return self.k2 * self.gap / (self.k1 + self.k2)

    @property
    def contact_stiffness(self) -> float:
        """Static stiffness seen at the node (N/m): k1 k2 / (k1 + k2)."""
        return self.k1 * self.k2 / (self.k1 + self.k2)

    def model(self) -> Model:
        """The oscillator as a :class:`Model`: two contacts on the node (DOF 1), the
        amplitude at the mass (DOF 0)."""
        M = np.array([[self.m, 0.0], [0.0, 0.0]])
        K = np.array([[self.k1 + self.k2, -self.k2], [-self.k2, self.k2]])
        return Model.from_matrices(M, K, contact_dof=[1, 1], gap=self.gap, stop_side=[1, -1],
                                   amplitude_dof=0,
                                   description={"kind": "ClearanceOscillator", "m": self.m, "k1": self.k1,
                                                "k2": self.k2, "gap": self.gap})

    def period(self, amplitude) -> np.ndarray:
        """Closed-form period (s) of the free motion whose mass swings ``amplitude`` (m)
        = max|x| (see the class docstring); T = 2π/ω1 for amplitude <= gap."""
        A = np.asarray(amplitude, dtype=float)
        if np.any(~np.isfinite(A)) or np.any(A < 0):
            raise ValueError(f"amplitude must be finite and >= 0, got {amplitude!r}")
        w1, w2, g, xs = self.omega_open, self.omega_closed, self.gap, self.centre
        Ac = np.maximum(A, g)
        B = Ac - xs
        v2 = w2**2 * np.maximum(B**2 - (g - xs) ** 2, 0.0)
        X = np.sqrt(g**2 + v2 / w1**2)
        t2 = np.arccos(np.clip((g - xs) / B, -1.0, 1.0)) / w2
        t1 = np.arcsin(np.clip(g / X, -1.0, 1.0)) / w1
        return np.where(A > g, 4.0 * (t1 + t2), 2 * np.pi / w1)

    def frequency(self, amplitude) -> np.ndarray:
        """Closed-form backbone: frequency (Hz) at ``amplitude`` (m, of the mass)."""
        return 1.0 / self.period(amplitude)


def one_dof_oscillator(m: float = 1.0, k1: float = 1.0, k2: float = 4.0, gap: float = 1.0) -> Model:
    """Shorthand for ``OneDofOscillator(m, k1, k2, gap).model()``."""
    return OneDofOscillator(m, k1, k2, gap).model()
