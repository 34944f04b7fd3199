"""The mesh (discretisation) error of a result from runs on successive meshes: Richardson
extrapolation in the element count where the observed order allows it.

A quantity computed on meshes of n_1 < n_2 < n_3 < ... elements (the frequency at a
given amplitude, a linear frequency) behaves, in the asymptotic range, as

    f(n) = f_∞ + C · n^−p,

the element size h ∝ 1/n. Three successive meshes give the observed order p: with the
differences d_1 = f(n_2) − f(n_1), d_2 = f(n_3) − f(n_2), p solves

    d_1 / d_2 = (n_1^−p − n_2^−p) / (n_2^−p − n_3^−p)

(ln(d_1/d_2) / ln r for a constant refinement ratio r = n_2/n_1 = n_3/n_2), and the
extrapolated value and the finest run's error are

    f_∞ = f(n_3) + d_2 · n_3^−p / (n_2^−p − n_3^−p),     error = |f(n_3) − f_∞| / |f_∞|.

It is reported only where the series is in its asymptotic range, judged by
:class:`MeshCriteria`; otherwise the result says why not:

- ``"not monotone"``: the differences change sign (the error oscillates with n; no
  algebraic model fits);
- ``"not contracting"``: |d_2| >= |d_1| (the finer pair moves as much as the coarser);
- ``"order out of range"``: the observed order lies outside ``order_range``;
- ``"order inconsistent"``: with four or more meshes, the orders of successive triples
  differ by more than ``order_tolerance`` (relative): the range is not yet asymptotic;
- ``"converged"``: the last differences are at round-off (relative ``flat``): the finest
  run's error is below that, reported as such;
- ``"too few meshes"``: fewer than three.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

__all__ = ["MeshCriteria", "MeshError", "mesh_error", "observed_order"]


@dataclass(frozen=True)
class MeshCriteria:
    """When a mesh series is taken as asymptotic (module docstring).

    Attributes
    ----------
    order_range : (float, float)
        The observed orders accepted: below 0.5 the series is too slow to extrapolate
        reliably (a singularity, a mesh not refined where it matters), above 8 faster than
        any element order (the differences are dominated by something else).
    order_tolerance : float
        With four meshes or more: the largest relative difference between the orders of
        successive triples (0.25: orders 2.0 and 2.4 agree, 2.0 and 2.6 do not).
    flat : float
        Relative differences below this are round-off: the series is converged.
    """

    order_range: tuple = (0.5, 8.0)
    order_tolerance: float = 0.25
    flat: float = 1e-12

    def __post_init__(self):
        lo, hi = self.order_range
        if not 0 < lo < hi:
            raise ValueError(f"order_range must be (lo, hi) with 0 < lo < hi, got {self.order_range!r}")
        if not self.order_tolerance > 0:
            raise ValueError(f"order_tolerance must be positive, got {self.order_tolerance!r}")


@dataclass(frozen=True)
class MeshError:
    """The mesh error of the finest run of a series.

    Attributes
    ----------
    elements : tuple of int
        The element counts (increasing).
    values : tuple of float
        The quantity on each mesh.
    extrapolated : float
        f_∞ (NaN where not asymptotic).
    error : float
        Relative error of the finest run, |f(n_last) − f_∞| / |f_∞| (NaN where not
        asymptotic; below ``flat`` where converged).
    order : float
        The observed order of the last triple (NaN where none).
    orders : tuple of float
        The observed order of every successive triple.
    reason : str
        "asymptotic", or why not (module docstring).
    """

    elements: tuple
    values: tuple
    extrapolated: float
    error: float
    order: float
    orders: tuple
    reason: str

    @property
    def asymptotic(self) -> bool:
        """Whether the extrapolation was made."""
        return self.reason == "asymptotic"

    def describe(self) -> str:
        """One line for a person."""
        n = ", ".join(str(e) for e in self.elements)
        if self.asymptotic:
            return (f"mesh error of the {self.elements[-1]}-element run {self.error:.2g} (Richardson, "
                    f"observed order {self.order:.2f} from {n} elements; extrapolated "
                    f"{self.extrapolated:.8g})")
        if self.reason == "converged":
            return f"mesh converged to round-off over {n} elements"
        orders = ", ".join(f"{p:.2f}" for p in self.orders if math.isfinite(p))
        return f"no mesh error over {n} elements: {self.reason}" + (f" (observed orders {orders})" if orders
                                                                     else "")


def observed_order(elements: Sequence[int], values: Sequence[float]) -> float:
    """The observed order p of three runs (module docstring); NaN where the differences
    do not contract monotonically (no positive p fits)."""
    n1, n2, n3 = (float(n) for n in elements)
    f1, f2, f3 = (float(v) for v in values)
    d1, d2 = f2 - f1, f3 - f2
    if d1 == 0 or d2 == 0 or d1 * d2 < 0 or abs(d2) >= abs(d1):
        return math.nan
    target = d1 / d2

    def g(p):
        return (n1 ** -p - n2 ** -p) / (n2 ** -p - n3 ** -p) - target

    lo, hi = 1e-6, 50.0
    if g(lo) * g(hi) > 0:
        return math.nan
    return float(brentq(g, lo, hi, xtol=1e-12))


def mesh_error(elements: Sequence[int], values: Sequence[float],
               criteria: MeshCriteria | None = None) -> MeshError:
    """Richardson extrapolation in the element count (module docstring).

    Parameters
    ----------
    elements : sequence of int
        Element counts of the runs, strictly increasing.
    values : sequence of float
        The quantity of each run (same length; NaN entries are dropped with their mesh).
    criteria : MeshCriteria, optional

    Raises
    ------
    ValueError
        Lengths differ, or the element counts do not increase.
    """
    criteria = criteria or MeshCriteria()
    n = np.asarray(elements, dtype=float)
    f = np.asarray(values, dtype=float)
    if n.shape != f.shape or n.ndim != 1:
        raise ValueError(f"elements and values must be sequences of the same length, got {n.shape} and "
                         f"{f.shape}")
    if np.any(np.diff(n) <= 0) or np.any(n <= 0):
        raise ValueError(f"elements must be positive and strictly increasing, got {list(elements)}")
    keep = np.isfinite(f)
    n, f = n[keep], f[keep]
    els, vals = tuple(int(x) for x in n), tuple(float(x) for x in f)

    def out(reason, ext=math.nan, err=math.nan, order=math.nan, orders=()):
        return MeshError(els, vals, float(ext), float(err), float(order), tuple(orders), reason)

    if len(n) < 3:
        return out("too few meshes")
    scale = max(np.max(np.abs(f)), 1e-300)
    d = np.diff(f)
    if np.all(np.abs(d[-2:]) <= criteria.flat * scale):
        return out("converged", f[-1], criteria.flat, math.nan)
    orders = [observed_order(n[i:i + 3], f[i:i + 3]) for i in range(len(n) - 2)]
    if np.any(d[-2:] == 0) or d[-2] * d[-1] < 0 or (len(d) > 2 and np.any(np.sign(d) != np.sign(d[-1]))):
        return out("not monotone", orders=orders)
    if abs(d[-1]) >= abs(d[-2]):
        return out("not contracting", orders=orders)
    p = orders[-1]
    lo, hi = criteria.order_range
    if not (math.isfinite(p) and lo <= p <= hi):
        return out("order out of range", order=p, orders=orders)
    if len(orders) > 1:
        q = orders[-2]
        if not (math.isfinite(q) and abs(p - q) <= criteria.order_tolerance * max(p, q)):
            return out("order inconsistent", order=p, orders=orders)
    n2, n3 = n[-2], n[-1]
    ext = f[-1] + d[-1] * n3 ** -p / (n2 ** -p - n3 ** -p)
    return out("asymptotic", ext, abs(f[-1] - ext) / abs(ext), p, orders)
