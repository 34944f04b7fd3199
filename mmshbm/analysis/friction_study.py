"""The "optimal normal load" study of a friction damper: resonance amplitude against N.

For each normal load N the largest amplitude of the forced response over a frequency band
is found by MMS-HBM at fixed frequencies (:meth:`FrictionForcedProblem.solve_at`): a
sweep over a geometric frequency grid, each solve started from the previous one, then a
bounded scalar search (Brent) for the maximum on the two grid intervals beside the
sweep's largest point. No arclength continuation is involved: a friction response with a
constant normal load has one amplitude per frequency on the band (no fold was seen on the
beam's tip damper), and the peak is what the curve needs. Where a sweep point does not
converge from its neighbour it is restarted from the free-slip and stuck linear responses
(:meth:`~mmshbm.methods.mms.friction_forced.FrictionForcedProblem.start_point`).

The loads run in ascending order in chunks, one chunk per worker process (``workers``),
so each sweep is warm-started from the previous load's sweep at the same frequencies.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field

import numpy as np

__all__ = ["NormalLoadStudy", "normal_load_study", "resonance_peak"]


@dataclass
class NormalLoadStudy:
    """Resonance amplitude against normal load.

    Attributes
    ----------
    normal_load : ndarray (n,)
        Normal loads N (N), ascending.
    peak_amplitude : ndarray (n,)
        Largest amplitude of the amplitude DOF over the band (m).
    peak_frequency : ndarray (n,)
        Frequency of that maximum (Hz).
    slip_fraction : ndarray (n,)
        Largest fraction of the period any friction node slips, at the peak.
    converged : ndarray (n,) of bool
        Every solve of the load's sweep and search converged.
    harmonics : int
    band : (float, float)
        Frequency band searched (Hz).
    seconds : float
        Wall time of the whole study (s), workers included.
    """

    normal_load: np.ndarray
    peak_amplitude: np.ndarray
    peak_frequency: np.ndarray
    slip_fraction: np.ndarray
    converged: np.ndarray
    harmonics: int
    band: tuple[float, float]
    seconds: float = 0.0
    meta: dict = field(default_factory=dict)

    @property
    def optimum(self) -> tuple[float, float]:
        """(N, amplitude) at the smallest resonance amplitude: a parabola in (log N, log
        amplitude) through the smallest sampled point and its neighbours, its vertex where
        it lies between them; the sampled point otherwise (at an end of the range, next to
        N = 0, or where one of the three has its largest amplitude at a band edge)."""
        i = int(np.argmin(self.peak_amplitude))
        inner = 0 < i < len(self.normal_load) - 1
        if inner and self.normal_load[i - 1] > 0 and not self.at_band_edge[i - 1:i + 2].any():
            x = np.log(self.normal_load[i - 1:i + 2])
            c2, c1, c0 = np.polyfit(x, np.log(self.peak_amplitude[i - 1:i + 2]), 2)
            if c2 > 0 and x[0] <= -c1 / (2 * c2) <= x[2]:
                xm = -c1 / (2 * c2)
                return float(np.exp(xm)), float(np.exp(c0 + c1 * xm + c2 * xm * xm))
        return float(self.normal_load[i]), float(self.peak_amplitude[i])

    @property
    def at_band_edge(self) -> np.ndarray:
        """(n,) bool: the largest amplitude lies at an end of the band (no resonance peak
        inside it: the value depends on the band)."""
        return np.isin(self.peak_frequency, self.band)

    def to_text(self) -> str:
        """A table of the study and its optimum."""
        lines = [f"resonance amplitude against normal load (H = {self.harmonics}, "
                 f"band {self.band[0]:g}-{self.band[1]:g} Hz, {self.seconds:.2f} s)",
                 f"{'N (N)':>10} {'amplitude (m)':>14} {'f (Hz)':>9} {'slip':>7} conv"]
        for row in zip(self.normal_load, self.peak_amplitude, self.peak_frequency, self.slip_fraction,
                       self.converged, strict=True):
            conv = "yes" if row[4] else "NO"
            conv += "  (band edge)" if row[2] in self.band else ""
            lines.append(f"{row[0]:10.4g} {row[1]:14.5e} {row[2]:9.3f} {row[3]:7.4f} {conv}")
        n_opt, a_opt = self.optimum
        lines.append(f"optimum: N = {n_opt:.4g} N, resonance amplitude {a_opt:.5e} m")
        return "\n".join(lines)


def resonance_peak(problem, grid: np.ndarray, guesses: list | None = None, xtol: float = 1e-5,
                   tol: float = 1e-11, max_iter: int = 50):
    """Largest amplitude of ``problem`` (a FrictionForcedProblem) over the frequencies of
    ``grid`` (Hz, ascending) and between them; ``tol`` is the Newton tolerance on the
    scaled residual, ``xtol`` the relative frequency tolerance of the search, ``max_iter``
    the Newton iterations of each solve (a point that needs more is restarted from the
    linear responses, then left out).

    Returns (amplitude (m), frequency (Hz), slip fraction, all converged, the sweep's
    scaled unknowns per grid point, None where the solve did not converge (to
    warm-start the next load)). Points whose solve did not converge are left out of the
    maximum; NaN when none converged.
    """
    from scipy.optimize import minimize_scalar

    sols, amps, ok_all = [], [], True
    u = None
    for j, f in enumerate(grid):
        # the previous load at this frequency, the previous frequency, the linear responses
        starts = [g for g in ((guesses[j] if guesses is not None else None), u) if g is not None]
        ok = False
        for start in starts:
            u_new, ok = problem.solve_at(f, start, max_iter, tol)
            if ok:
                break
        if not ok:
            u_new, ok = problem.solve_at(f, problem.start_point(f, max_iter, tol), max_iter, tol)
        ok_all &= ok
        if ok:  # a point that did not converge neither counts nor starts the next
            u = u_new
        sols.append(u_new if ok else None)
        amps.append(_amplitude(problem, u_new) if ok else -np.inf)
    amps = np.array(amps)
    if not np.isfinite(amps).any():
        return np.nan, np.nan, np.nan, False, sols
    i = int(np.argmax(amps))
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]
    cache = {"u": sols[i]}

    def neg(f):
        u, ok = problem.solve_at(f, cache["u"], max_iter, tol)
        if not ok:
            u, ok = problem.solve_at(f, problem.start_point(f, max_iter, tol), max_iter, tol)
        if not ok:  # counts as no amplitude (finite: the search's parabolas stay defined)
            cache["ok"] = False
            return 0.0
        cache["u"] = u
        return -_amplitude(problem, u)

    if i in (0, len(grid) - 1):  # the largest amplitude at an end of the band
        x, om = problem.unpack(sols[i])
        slip = problem.friction_records(x, om)["slip_fraction"]
        return float(amps[i]), float(grid[i]), float(slip), bool(ok_all), sols
    best = minimize_scalar(neg, bounds=(lo, hi), method="bounded", options={"xatol": xtol * grid[i]})
    f_pk, a_pk = float(best.x), float(-best.fun)
    if amps[i] > a_pk:  # the grid point itself
        f_pk, a_pk = float(grid[i]), float(amps[i])
        cache["u"] = sols[i]
    x, om = problem.unpack(cache["u"])
    slip = problem.friction_records(x, om)["slip_fraction"]
    return a_pk, f_pk, float(slip), bool(ok_all and cache.get("ok", True)), sols


def _amplitude(problem, u) -> float:
    x, om = problem.unpack(u)
    Q = problem._coefficients(x, om, 1.0)
    return float(problem.amplitude(Q[problem.amplitude_dof]))


def _chunk(make_model: Callable, loads, force, grid, harmonics, tol):
    from ..methods.mms.friction_forced import FrictionForcedProblem

    out, guesses = [], None
    for N in loads:
        problem = FrictionForcedProblem(make_model(normal_load=float(N)), force, harmonics=harmonics)
        a, f, slip, ok, guesses = resonance_peak(problem, grid, guesses, tol=tol)
        out.append((a, f, slip, ok))
    return out


def normal_load_study(make_model: Callable, normal_loads: Sequence[float], force, band: tuple[float, float],
                      harmonics: int = 7, n_grid: int = 30, workers: int = 1,
                      tol: float = 1e-9) -> NormalLoadStudy:
    """Resonance amplitude against normal load.

    Parameters
    ----------
    make_model : callable(normal_load=N) -> Model
        The model with normal load N (N) on its friction contact, called with the keyword
        ``normal_load``, e.g. ``functools.partial(mmshbm.tip_damper_model, at=0.5)``. Must
        be picklable when ``workers > 1`` (a module-level function or a
        ``functools.partial`` of one).
    normal_loads : sequence of float
        Normal loads >= 0 (N); sorted ascending.
    force : array_like (n_dof,)
        Harmonic force amplitude (N) on DOFs with mass.
    band : (float, float)
        Frequencies searched (Hz), 0 < f_lo < f_hi.
    harmonics : int
        H of MMS-HBM.
    n_grid : int
        Points of the geometric frequency grid of each sweep (>= 3): the spacing must be
        below the half-power width of the sharpest peak (ratio (f_hi/f_lo)^(1/(n_grid−1))).
    workers : int
        Processes (1: in this process).
    tol : float
        Newton tolerance on the scaled residual of every solve (1e-9 moved the peak
        amplitude of the beam's tip damper by 6.5e-7 relative against 1e-11).
    """
    loads = np.sort(np.asarray(normal_loads, dtype=float))
    if loads.ndim != 1 or len(loads) == 0 or np.any(loads < 0) or not np.all(np.isfinite(loads)):
        raise ValueError("normal_loads must be a non-empty sequence of finite loads >= 0")
    f_lo, f_hi = (float(b) for b in band)
    if not 0 < f_lo < f_hi:
        raise ValueError(f"band must be (f_lo, f_hi) with 0 < f_lo < f_hi, got {band!r}")
    if int(n_grid) < 3:
        raise ValueError(f"n_grid must be >= 3, got {n_grid!r}")
    grid = np.geomspace(f_lo, f_hi, int(n_grid))
    force = np.asarray(force)
    t0 = time.perf_counter()
    workers = max(1, min(int(workers), len(loads)))
    chunks = [c for c in np.array_split(loads, workers) if len(c)]
    if workers == 1:
        rows = _chunk(make_model, loads, force, grid, harmonics, tol)
    else:
        with ProcessPoolExecutor(workers) as pool:
            futures = [pool.submit(_chunk, make_model, c, force, grid, harmonics, tol) for c in chunks]
            rows = [r for fut in futures for r in fut.result()]
    seconds = time.perf_counter() - t0
    a, f, slip, ok = (np.array(v) for v in zip(*rows, strict=True))
    return NormalLoadStudy(loads, a, f, slip, ok.astype(bool), int(harmonics), (f_lo, f_hi), seconds,
                           {"n_grid": int(n_grid), "workers": workers})
