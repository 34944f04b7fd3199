"""Observed convergence of a series of runs (in H or in the number of elements).

For a series x_0 < x_1 < ... (H or element counts) with frequencies f_i at one amplitude,
:class:`ConvergenceFit` reports what the numbers say and no more:

* ``steps``: the differences between successive runs, f_{i+1} − f_i (Hz) — their signs
  show whether the series is monotone, their sizes whether it contracts;
* ``spread``: max − min of the three finest runs with a value (Hz);
* ``local_rates``: the observed order p of every three consecutive runs, the root of
  (f_1 − f_0)/(f_2 − f_1) = (x_0^−p − x_1^−p)/(x_1^−p − x_2^−p), which holds exactly for
  f = f_∞ + C x^−p whatever the spacing of x (no reference run needed); NaN when the two
  steps differ in sign, do not shrink fast enough for any p > 0, or need p > 50;
* ``rate``: p only where it means something — the two finest local orders exist and
  agree within 25 % (the series is in its asymptotic range); then the finest local order,
  and ``error_estimate`` is the Richardson estimate |f_n − f_∞| of the finest run. Else
  NaN and ``rate_note`` says why (a sign change: the series oscillates, typical of harmonic
  balance on a contact problem; local orders that disagree; a NaN cell; too few runs).

``difference`` keeps |f − f_finest| for reference.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .._method_info import DEFAULT_METHOD

__all__ = ["ConvergenceFit", "local_order", "format_convergence"]

#: relative agreement of the two finest local orders for a reported rate
RATE_AGREEMENT = 0.25
#: largest local order solved for
MAX_ORDER = 50.0


def local_order(x, f) -> float:
    """Observed order p of three runs (x ascending, f finite) assuming f = f_∞ + C x^−p;
    NaN when the steps change sign or no p in (0, 50] fits."""
    x0, x1, x2 = (float(v) for v in x)
    d1, d2 = float(f[1]) - float(f[0]), float(f[2]) - float(f[1])
    if not (np.isfinite(d1) and np.isfinite(d2)) or d1 == 0 or d2 == 0 or (d1 > 0) != (d2 > 0):
        return math.nan
    r = d1 / d2

    def g(p):  # (x0^-p - x1^-p)/(x1^-p - x2^-p), written without underflow
        return math.expm1(p * math.log(x1 / x0)) / -math.expm1(-p * math.log(x2 / x1))

    lo, hi = 1e-9, MAX_ORDER
    if not g(lo) < r <= g(hi):
        return math.nan
    for _ in range(200):  # g increases with p: bisection
        mid = 0.5 * (lo + hi)
        if g(mid) < r:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-10 * hi:
            break
    return 0.5 * (lo + hi)


@dataclass
class ConvergenceFit:
    """Observed convergence of one series of runs at one amplitude (module docstring).

    Attributes
    ----------
    vary : {"harmonics", "elements"}
        The refined quantity.
    fixed : dict
        The other coordinates of the series.
    amplitude : float
        The amplitude (in ``unit``) the frequencies are taken at.
    unit : {"gap", "m"}
    values : ndarray, shape (n,)
        H or element counts, ascending.
    frequency : ndarray, shape (n,)
        Frequencies (Hz) at ``amplitude``; NaN where a run has none.
    difference : ndarray, shape (n,)
        |f − f_finest| (Hz); 0 for the finest run.
    steps : ndarray, shape (n − 1,)
        f_{i+1} − f_i (Hz).
    local_rates : ndarray, shape (n − 2,)
        Observed order of runs i, i+1, i+2.
    rate : float
        Observed order where the series is in its asymptotic range, else NaN.
    spread : float
        max − min (Hz) of the three finest runs with a value (NaN with fewer than two).
    error_estimate : float
        Richardson estimate of |f_finest − f_∞| (Hz) where ``rate`` is defined, else NaN.
    n_fit : int
        Runs behind ``rate`` (4: two local orders), 0 when it is NaN.
    rate_note : str
        Why ``rate`` is NaN ("" when it is not).
    note : str
        Why runs have no value (filled by the study).
    """

    vary: str
    fixed: dict
    amplitude: float
    unit: str
    values: np.ndarray
    frequency: np.ndarray
    difference: np.ndarray
    steps: np.ndarray
    local_rates: np.ndarray
    rate: float
    spread: float
    error_estimate: float
    n_fit: int
    rate_note: str = ""
    note: str = ""

    @classmethod
    def fit(cls, vary, fixed, amplitude, unit, values, frequency) -> ConvergenceFit:
        """The fit of one series (``values`` ascending, ``frequency`` in Hz with NaNs)."""
        values = np.asarray(values, dtype=float)
        frequency = np.asarray(frequency, dtype=float)
        n = len(values)
        if frequency.shape != (n,) or np.any(np.diff(values) <= 0):
            raise ValueError("values must be ascending and frequency of the same length")
        diff = np.abs(frequency - frequency[-1])
        steps = np.diff(frequency)
        local = np.array([local_order(values[i:i + 3], frequency[i:i + 3]) for i in range(max(n - 2, 0))])
        finite = np.flatnonzero(np.isfinite(frequency))
        tail = frequency[finite[-3:]]
        spread = float(np.ptp(tail)) if len(tail) >= 2 else math.nan
        rate, estimate, n_fit = math.nan, math.nan, 0
        symbol = "H" if vary == "harmonics" else "elements"
        if n < 4:
            note = "a rate needs 4 runs"
        elif not np.all(np.isfinite(frequency[-4:])):
            missing = [f"{v:g}" for v, f in zip(values, frequency, strict=True) if not np.isfinite(f)]
            note = f"no value at {symbol} = {', '.join(missing)}"
        else:
            s = steps[-3:]
            changes = [i for i in range(len(s) - 1) if (s[i] > 0) != (s[i + 1] > 0)]
            p1, p2 = local[-2], local[-1]
            if changes:
                i = len(steps) - 3 + changes[0]
                note = (f"oscillates: the step changes sign at {symbol} {values[i]:g}→{values[i + 1]:g}"
                        f"→{values[i + 2]:g}")
            elif not (np.isfinite(p1) and np.isfinite(p2)):
                note = "steps do not contract like a power of " + symbol
            elif abs(p2 - p1) > RATE_AGREEMENT * max(abs(p1), abs(p2)):
                note = f"local orders {p1:.2f} and {p2:.2f} disagree: not in the asymptotic range"
            else:
                note = ""
                rate, n_fit = float(p2), 4
                ratio = values[-1] / values[-2]
                estimate = float(abs(steps[-1]) / math.expm1(rate * math.log(ratio)))
        return cls(vary, dict(fixed), amplitude, unit, values, frequency, diff, steps, local, rate, spread,
                   estimate, n_fit, note)

    @property
    def reference(self) -> float:
        """The finest value of the series."""
        return float(self.values[-1])

    @property
    def monotone(self) -> bool:
        """All finite steps have one sign."""
        s = self.steps[np.isfinite(self.steps) & (self.steps != 0)]
        return bool(len(s) and (np.all(s > 0) or np.all(s < 0)))


def _num(x: float, fmt: str) -> str:
    return "-" if not np.isfinite(x) else format(x, fmt)


def format_convergence(fits: Sequence[ConvergenceFit]) -> str:
    """Text table of convergence fits: the series, successive differences, local orders,
    the rate where it means something, the spread of the three finest runs, and notes."""
    head = ("vary", "fixed", "A", "x", "f (Hz)", "steps f[i+1]-f[i] (Hz)", "local p", "p", "spread (Hz)",
            "|f_n - f_inf| est.", "note")
    rows = []
    for fit in fits:
        fixed = " ".join(f"{k}={v}" for k, v in fit.fixed.items() if k != "method" or v != DEFAULT_METHOD)
        unit = "gap" if fit.unit == "gap" else "m"
        note = "; ".join(n for n in (fit.rate_note, fit.note) if n)
        rows.append((fit.vary, fixed, f"{fit.amplitude:g} {unit}", ",".join(f"{v:g}" for v in fit.values),
                     ",".join(_num(f, ".3f") for f in fit.frequency),
                     ",".join(_num(d, "+.3g") for d in fit.steps),
                     ",".join(_num(p, ".2f") for p in fit.local_rates), _num(fit.rate, ".2f"),
                     _num(fit.spread, ".3g"), _num(fit.error_estimate, ".2g"), note))
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(head)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    title = ("Convergence: steps between successive runs, local orders p of three consecutive runs "
             "(f = f_inf + C x^-p), p only where the two finest local orders agree within "
             f"{RATE_AGREEMENT:.0%}, spread = max - min of the three finest runs")
    return "\n".join([title, fmt.format(*head).rstrip(), *(fmt.format(*r).rstrip() for r in rows)])
