"""How far a harmonic balance branch's frequency is from its limit in H, estimated by the branch.

A harmonic balance branch (MMS-HBM, penalty-HBM) truncates the Fourier series at H
harmonics; its frequency at an amplitude converges to a limit f_∞ as H grows, the
frequency of a genuine periodic orbit (for MMS-HBM with the exact projection: an exact
symmetric orbit of the piecewise-linear system). :func:`truncation_error` estimates
``|f_H − f_∞| / f_∞`` at one amplitude from re-solves of the *same* amplitude at larger H:

1. the branch's point at the amplitude (:func:`~mmshbm.results.family_points.family_point`,
   the point ``frequency_at`` returns) is the start;
2. the solver is rebuilt at H₁ = 2H and H₂ = 4H (``factors``) from what the branch stores
   (model, method and method options), the start's harmonics padded with zeros, and the
   point solved with the amplitude pinned (:func:`mmshbm.core.pinned.solve_at_amplitude`;
   the 4H solve starts from the 2H one; where Newton fails from the padded start, H is
   raised by ~20 % per pinned solve instead);
3. with d₁ = f(2H) − f(H) and d₂ = f(4H) − f(2H): where both have the same sign and
   ``|d₂| < |d₁|`` the series is taken as f = f_∞ + C·H^−p with the *measured* rate
   p = log₂(d₁/d₂) and extrapolated (Richardson): f_∞ = f(4H) + d₂/(2^p − 1), and the
   estimate is ``|f(H) − f_∞| / f_∞`` (``asymptotic`` True). Otherwise the series is not (yet)
   in an algebraic regime (it oscillates or does not contract: typical near an internal
   resonance, or when a larger H resolves another orbit); the estimate is then the larger
   of ``|d₁|`` and ``|f(4H) − f(H)|`` relative to f(H), times ``safety`` (``asymptotic`` False).
   With one factor (``factors=(2,)``), or where the 4H solve fails, the rate is assumed
   (``rate``, default 1: about the slowest rate measured on the test models, so that the
   estimate errs large).

Assumptions: the re-solves stay on the same orbit (the start is the branch's own point, and
Newton from the padded coefficients lands on the nearest solution: a larger H that
resolves a coexisting orbit shows up as a non-contracting series, reported as not
asymptotic); the error is dominated by truncation, not by the Newton tolerance (``tol``,
1e-10 relative, far below the errors this estimates).

Cost: two pinned solves at 2H and 4H on demand (a few Newton iterations each, plus
building the solvers); never part of a backbone run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["TruncationEstimate", "state_truncation_error", "truncation_error"]


@dataclass(frozen=True)
class TruncationEstimate:
    """The truncation error estimate of a branch at one amplitude.

    Attributes
    ----------
    amplitude : float
        The amplitude (m).
    harmonics : tuple of int
        H of the branch, then of each re-solve.
    frequency : tuple of float
        The frequency (Hz) at the amplitude for each entry of ``harmonics`` (NaN where a
        solve failed).
    error : float
        Estimated relative error ``|f_H − f_∞| / f_∞`` of the branch's frequency (NaN when the
        re-solves failed).
    rate : float
        The algebraic rate p used (measured, or assumed with one re-solve; NaN when none
        applies).
    limit : float
        The extrapolated frequency f_∞ (Hz; NaN when not asymptotic).
    asymptotic : bool
        Whether the series contracted algebraically (the extrapolation applies).
    note : str
        Why the series is not asymptotic, or which solve failed.
    """

    amplitude: float
    harmonics: tuple
    frequency: tuple
    error: float
    rate: float = math.nan
    limit: float = math.nan
    asymptotic: bool = False
    note: str = field(default="")

    def __float__(self) -> float:
        return float(self.error)


def truncation_error(branch, amplitude: float, *, factors=(2, 4), rate: float = 1.0, safety: float = 2.0,
                     tol: float = 1e-10) -> TruncationEstimate:
    """Estimated relative error of ``branch.frequency_at(amplitude)`` from truncating the
    Fourier series at the branch's H (module docstring for the method and assumptions).

    Parameters
    ----------
    branch : Branch
        A harmonic balance branch (method "mmshbm" or "penalty").
    amplitude : float
        Amplitude (m) inside the branch's family front.
    factors : sequence of int
        The re-solves' H as multiples of the branch's H (ascending, > 1; one or two).
    rate : float
        The algebraic rate assumed with a single re-solve.
    safety : float
        Factor on the spread of a series that is not asymptotic.
    tol : float
        Newton tolerance of every solve.

    Raises
    ------
    ValueError
        For a method without harmonics (shooting), or an amplitude where the branch has no
        point (``frequency_at`` is NaN there).
    """
    from .family_points import family_point

    a = float(amplitude)
    f0, u = family_point(branch, a, tol=tol)
    if u is None or not math.isfinite(f0):
        raise ValueError(f"the branch has no point at {a:.6g} m (frequency_at is NaN there)")
    return state_truncation_error(branch, a, f0, u, factors=factors, rate=rate, safety=safety, tol=tol)


def state_truncation_error(branch, amplitude: float, frequency: float, state: np.ndarray, *, factors=(2, 4),
                           rate: float = 1.0, safety: float = 2.0, tol: float = 1e-10) -> TruncationEstimate:
    """The estimate of :func:`truncation_error` for the solved orbit ``state`` (the
    branch's solver's unknowns) of frequency ``frequency`` (Hz) at ``amplitude`` (m): any
    orbit of the branch's equations there, not only the backbone's (e.g. one of
    :meth:`mmshbm.Branch.orbits_at`)."""
    from ..core.pinned import PinnedFailure, solve_at_amplitude

    factors = tuple(int(k) for k in np.atleast_1d(factors))
    if not 1 <= len(factors) <= 2 or any(k < 2 for k in factors) or list(factors) != sorted(set(factors)):
        raise ValueError(f"factors must be one or two ascending integers >= 2, got {factors!r}")
    H = int(branch.harmonics)
    if H < 1:
        raise ValueError(f"a {branch.method} branch has no harmonics to truncate")
    a, f0, u = float(amplitude), float(frequency), np.asarray(state, dtype=float)
    solver = branch._require_solver()
    if not (hasattr(solver, "unpack") and hasattr(solver, "pack")):
        raise ValueError(f"the {branch.method} solver does not expose its harmonics (unpack/pack)")
    options = {k: v for k, v in dict(branch.metadata.get("method_options", {})).items() if k != "n_samples"}
    model = branch.get_model()
    harmonics, freqs, note = [H], [float(f0)], ""
    def raised(solver, u, H2):
        """The pinned point at H2 from the point u of ``solver``: (solver, u)."""
        coef, omega = solver.unpack(u)
        padded = np.zeros((H2 + 1, coef.shape[1]))
        padded[:coef.shape[0]] = coef
        new = branch._build_solver(model, {**options, "harmonics": H2})
        u2, _, _, _ = solve_at_amplitude(new, new.pack(padded, omega), a, tol=tol, max_iter=40)
        return new, u2

    for k in factors:
        H2 = k * H
        harmonics.append(H2)
        if not math.isfinite(freqs[-1]):
            freqs.append(math.nan)
            continue
        try:
            try:
                solver, u = raised(solver, u, H2)
            except (PinnedFailure, ArithmeticError, ValueError):
                # the padded start is too far: raise H by ~20 % per solve instead
                while solver.H < H2:
                    solver, u = raised(solver, u, min(H2, max(solver.H + 1, math.ceil(1.2 * solver.H))))
            freqs.append(float(solver.monitor(u)["frequency"]))
        except (PinnedFailure, ArithmeticError, ValueError) as err:
            freqs.append(math.nan)
            note = f"the solve at H = {H2} failed: {err}"
    return _estimate(a, tuple(harmonics), tuple(freqs), rate, safety, note)


def _estimate(a: float, harmonics: tuple, f: tuple, rate: float, safety: float,
              note: str) -> TruncationEstimate:
    """The estimate from the frequencies at H and the larger harmonics (module docstring)."""
    if len(f) == 3 and all(math.isfinite(v) for v in f[:2]) and not math.isfinite(f[2]):
        two = _estimate(a, harmonics[:2], f[:2], rate, safety, "")
        return TruncationEstimate(a, harmonics, f, two.error, rate, two.limit, False, f"{note}; {two.note}")
    if not all(math.isfinite(v) for v in f):
        return TruncationEstimate(a, harmonics, f, math.nan, note=note or "a solve failed")
    if len(f) == 2:
        d = f[1] - f[0]
        q = (harmonics[1] / harmonics[0]) ** rate
        limit = f[1] + d / (q - 1)
        return TruncationEstimate(a, harmonics, f, abs(f[0] - limit) / abs(limit), rate, limit, False,
                                  f"rate {rate:g} assumed (one re-solve)")
    d1, d2 = f[1] - f[0], f[2] - f[1]
    ratio = harmonics[1] / harmonics[0]
    if d1 == 0.0 and d2 == 0.0:
        return TruncationEstimate(a, harmonics, f, 0.0, math.inf, f[0], True, "no change with H")
    if d1 != 0 and d2 != 0 and (d1 > 0) == (d2 > 0) and abs(d2) < abs(d1) \
            and math.isclose(harmonics[2] / harmonics[1], ratio):
        p = math.log(d1 / d2) / math.log(ratio)
        limit = f[2] + d2 / (ratio ** p - 1)
        return TruncationEstimate(a, harmonics, f, abs(f[0] - limit) / abs(limit), p, limit, True, "")
    why = ("the steps change sign" if (d1 > 0) != (d2 > 0) else "the steps do not contract")
    spread = max(abs(d1), abs(f[2] - f[0]))
    return TruncationEstimate(a, harmonics, f, safety * spread / abs(f[0]), math.nan, math.nan, False,
                              f"not asymptotic: {why} (H = {harmonics[0]}, {harmonics[1]}, {harmonics[2]})")
