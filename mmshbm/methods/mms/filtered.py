"""Passing an internal resonance with the resonant harmonic filtered out.

Where harmonic k of the motion meets mode j (kΩ ≈ ω_j), the branch of the H-harmonic
problem turns into a tongue. The same problem with harmonic k removed — its residual
rows replaced by a_k = 0 — has no such resonance: harmonic balance filters the
interaction, as it filters all interactions with harmonics above H. Its branch is the
family with that harmonic missing. Continued from a family point before the resonance
until the frequency is past it, its end point differs from the H-harmonic family point
at the same amplitude only by the (small, non-resonant) harmonic-k content, so Newton on
the full problem with the amplitude pinned releases the filter there.

:class:`FilteredProblem` wraps a continuation problem; :func:`pass_resonance` does the
continuation and the release. Used by MMS-HBM's ``family_landing`` (a start of the
search beyond a frontier, :mod:`mmshbm.family.deflation`).
"""

from __future__ import annotations

import numpy as np

from ...core.continuation import ContinuationOptions, continue_branch
from ...core.pinned import PinnedFailure, amplitude_and_gradient, solve_at_amplitude
from ...core.problem import ContinuationProblemBase, as_problem
from ...core.status import Status
from ...family.definition import FAMILY_RECORD, family_value

__all__ = ["FilteredProblem", "pass_resonance"]


class FilteredProblem(ContinuationProblemBase):
    """``problem`` with the coefficients of the harmonics ``filtered`` held at zero.

    Parameters
    ----------
    problem : MMSHBMProblem
        Its ``harmonic_columns(k)`` name the unknowns of harmonic k.
    filtered : sequence of int
        Harmonics k >= 1 to remove.
    """

    def __init__(self, problem, filtered):
        self.problem = as_problem(problem)
        self.n_unknowns = problem.n_unknowns
        self.cols = np.concatenate([problem.harmonic_columns(k) for k in filtered])

    def residual(self, u: np.ndarray) -> np.ndarray:
        """The wrapped problem's residual with the rows of the filtered columns replaced
        by those unknowns (n_unknowns − 1,)."""
        R = self.problem.residual(u).copy()
        R[self.cols] = u[self.cols]
        return R

    def residual_and_jacobian(self, u: np.ndarray):
        """(R, J) of :meth:`residual`: J (n_unknowns − 1, n_unknowns), the filtered rows
        unit rows."""
        R, J = self.problem.residual_and_jacobian(u)
        R = R.copy()
        R[self.cols] = u[self.cols]
        J = J.copy()
        J[self.cols, :] = 0.0
        J[self.cols, self.cols] = 1.0
        return R, J

    def monitor(self, u: np.ndarray) -> dict:
        return self.problem.monitor(u)

    def amplitude_and_gradient(self, u: np.ndarray):
        return amplitude_and_gradient(self.problem, u)

    def amplitude_value(self, u: np.ndarray) -> float:
        if self.problem.amplitude_value is not None:
            return self.problem.amplitude_value(u)
        return amplitude_and_gradient(self.problem, u)[0]


def _resonant_harmonic(problem, u: np.ndarray, mode: int, exclude) -> int | None:
    """The harmonic k >= 1 (not in ``exclude``) of the largest energy share of a mode
    other than the starting one at the point ``u`` (``problem.modal_shares``)."""
    shares = np.asarray(problem.modal_shares(u), dtype=float).copy()
    shares[mode - 1, :] = -1.0
    shares[:, 0] = -1.0
    for k in exclude:
        shares[:, k] = -1.0
    j, k = np.unravel_index(int(np.argmax(shares)), shares.shape)
    return int(k) if shares[j, k] > 0 else None


def pass_resonance(problem, u_from: np.ndarray, amplitude_from: float, harmonic: int, f_resonance: float,
                   amplitude_max: float, *, amplitude_min: float = 0.0, newton_tol: float = 1e-10,
                   family_share: float = 0.5, window: float = 0.3, max_filtered: int = 8,
                   max_releases: int = 8):
    """Land on the H-harmonic family beyond the resonance of ``harmonic`` at
    ``f_resonance`` (Hz, = ω_j / (2π k)). ``problem`` is an MMS-HBM problem
    (:class:`~mmshbm.methods.mms.conservative.MMSHBMProblem`: its ``mode``,
    ``modal_shares`` and ``harmonic_columns``).

    Continues the branch with ``harmonic`` filtered out from ``u_from`` until the frequency
    exceeds ``f_resonance·(1 + window)`` (or the amplitude reaches ``amplitude_max``); a
    further resonance met on the way (the filtered branch leaves the family) adds its
    harmonic to the filter, up to ``max_filtered`` harmonics. The filter is then released
    by Newton, at fixed amplitude, from the points of the filtered branch beyond the
    resonance and above ``amplitude_min`` (the family's frontier) — the lowest amplitudes
    at least 1.5 % from every internal resonance kΩ = ω_j first
    (``problem.tracked_frequencies``), then the others farthest from one — until one
    lands on the family.

    Returns
    -------
    (u, amplitude) of the landing point (a solution of ``problem``).

    Raises
    ------
    PinnedFailure
        If the filtered branch cannot be continued or no release lands on the family.
    """
    mode = problem.mode
    filtered = [harmonic]
    filt = FilteredProblem(problem, filtered)
    u0 = np.array(u_from, dtype=float)
    u0[filt.cols] = 0.0
    u0, _, _, t0 = solve_at_amplitude(filt, u0, amplitude_from, tol=newton_tol, max_iter=30)
    f_stop = f_resonance * (1.0 + window)
    candidates = []  # (u, amplitude, frequency)
    while True:
        res = continue_branch(filt, u0, t0, ContinuationOptions(
            follow="path", max_steps=300, newton_tol=newton_tol,
            bounds={"amplitude": (0.0, amplitude_max), "frequency": (0.0, f_stop),
                    FAMILY_RECORD: (family_share, 2.0)}), catch_interrupt=False)
        if res.status.kind != Status.BOUND and len(res.u) < 2:
            raise PinnedFailure(f"the filtered branch stopped: {res.status}")
        A, f = res.records["amplitude"], res.records["frequency"]
        for i in range(1, len(res.u)):
            if f[i] > f_resonance * 1.01 and A[i] > amplitude_min * (1 + 1e-6):
                candidates.append((res.u[i], float(A[i]), float(f[i])))
        if res.status != Status.bound(FAMILY_RECORD):
            break
        # another resonance: filter its harmonic too and go on from the last family point
        k2 = _resonant_harmonic(problem, res.u[-1], mode, filtered)
        if k2 is None or len(filtered) >= max_filtered:
            break
        filtered.append(k2)
        filt = FilteredProblem(problem, filtered)
        u0 = np.array(res.u[-2], dtype=float)
        u0[filt.cols] = 0.0
        try:
            u0, _, _, t0 = solve_at_amplitude(filt, u0, float(A[-2]), tol=newton_tol, max_iter=30)
        except PinnedFailure:
            break
        if 2 * np.pi * f_stop <= filt.problem.unpack(u0)[1]:
            break
    if not candidates:
        raise PinnedFailure(f"the filtered branch did not pass the resonance of harmonic {harmonic}")
    tracked = problem.tracked_frequencies
    f_modes = np.asarray([] if tracked is None else tracked, dtype=float)
    others = np.delete(f_modes, mode - 1) if len(f_modes) >= mode else f_modes
    k = np.arange(1, problem.H + 1)

    def distance(freq):
        if not len(others):
            return 1.0
        return float(np.min(np.abs(np.outer(k, [freq]).ravel()[:, None] / others[None, :] - 1.0)))

    # release near the frontier where no resonance is close (1.5 % in kΩ/ω_j), else
    # wherever the resonances are farthest
    far = sorted((i for i in range(len(candidates)) if distance(candidates[i][2]) >= 0.015),
                 key=lambda i: candidates[i][1])
    near = sorted((i for i in range(len(candidates)) if distance(candidates[i][2]) < 0.015),
                  key=lambda i: -distance(candidates[i][2]))
    order = far + near
    last = "no release tried"
    for i in order[:max_releases]:
        u_c, A_c, f_c = candidates[i]
        try:
            u, _, _, _ = solve_at_amplitude(problem, u_c, A_c, tol=newton_tol, max_iter=30)
            rec = problem.monitor(u)
        except (PinnedFailure, ArithmeticError, ValueError) as err:
            last = f"release at {A_c:.4g} ({f_c:.4g} Hz, filtered {filtered}): {err}"
            continue
        share = family_value(rec)
        if share is not None and share < family_share:
            last = f"release at {A_c:.4g} landed off the family (fundamental share {share:.3f})"
        elif not abs(rec["frequency"] - f_c) <= 0.05 * f_c:
            last = f"release at {A_c:.4g} landed on another branch ({rec['frequency']:.4g} Hz)"
        else:
            return u, A_c
    raise PinnedFailure(f"passing the resonance of harmonic {harmonic}: {last}")
