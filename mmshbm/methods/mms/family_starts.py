"""MMS-HBM's starts of the deflated search beyond a frontier
(:mod:`mmshbm.family.deflation`), supplied by composition: the problem's
``family_starts()`` returns a :class:`MMSHBMStarts`."""

from __future__ import annotations

import logging

import numpy as np

from ...family.deflation import BranchStarts
from ...family.guard import FamilyGuard

__all__ = ["MMSHBMStarts"]

log = logging.getLogger(__name__)

#: homotopies from the fundamental's family per search (each a curve of up to a few
#: hundred steps), at its first targets, where the other starts found no family orbit at
#: any
HOMOTOPIES = 4


class MMSHBMStarts(BranchStarts):
    """The branch's starts (:class:`~mmshbm.family.deflation.BranchStarts`) and MMS-HBM's:
    the resonance passed with its harmonic filtered out (``family_landing``, a start that
    picks its own amplitude, and the state interpolated between the frontier and it at
    the targets below), the orbit along the auxiliary low-harmonic branch
    (``family_predictor``) and the orbit scaled to the target (``scaled_state``: far above
    the gap the system is nearly homogeneous)."""

    def __init__(self, problem):
        super().__init__(problem)
        self._homotopies: dict[float, int] = {}  # homotopies run per frontier amplitude

    def before(self, us: list, recs: list, guard: FamilyGuard,
               amplitude: float) -> list[tuple[str, np.ndarray]]:
        i = guard.frontier_index
        A_f = float(recs[i]["amplitude"])
        out = self._ladders(guard, amplitude)
        out += self._low_orbits(guard, amplitude, [u for _, u in out])
        for u_l, A_l in self._landed:
            if A_f < amplitude < A_l:
                s = (amplitude - A_f) / (A_l - A_f)
                out.append(("toward the filtered landing", (1.0 - s) * us[i] + s * u_l))
        return out

    def _low_orbits(self, guard: FamilyGuard, amplitude: float,
                    exclude: list[np.ndarray]) -> list[tuple[str, np.ndarray]]:
        """The orbits at ``amplitude`` of the problem with few harmonics (H_low = 3, or H
        where H <= 3) that Newton reaches from the fundamental's orbit there raised to
        H_low, each found one deflated (:func:`~mmshbm.family.deflation.deflated_solve`,
        at most ``depth`` solves), then continued in the harmonics to H (a pinned solve
        at H_low + 2, H_low + 4, ..., H, each from the one before): a family that
        coexists with the branch's, apart from it in frequency, has its orbit near the
        fundamental's at low H, where no start taken from the branch comes. Only those
        whose share at H_low is at least the family's are continued; those within
        round-off of one in ``exclude`` (the ladders') are left out."""
        from ...core.pinned import PinnedFailure, solve_at_amplitude
        from ...family.deflation import _same, deflated_solve
        from .landings import _raised

        p, out = self.problem, []
        tol, max_iter, admissible = self.solver
        ref = p._fundamental_branch(self.amplitude_max) if p.H > 1 else None
        if ref is None or not ref[1][0] <= amplitude <= ref[1][-1] * (1 + 1e-9):
            return out
        aux, A, U = ref
        low = p._rung(min(3, p.H))
        try:
            u0 = np.array([np.interp(amplitude, A, U[:, i]) for i in range(U.shape[1])])
            start = _raised(aux, solve_at_amplitude(aux, u0, amplitude, tol=tol, max_iter=max_iter)[0], low)
        except (PinnedFailure, ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError):
            return out
        known = []
        for _ in range(self.depth):
            try:
                known.append(deflated_solve(low, start, amplitude, known, tol=tol, max_iter=max_iter,
                                            admissible=None)[0])
            except (PinnedFailure, ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError):
                break
        for k, u in enumerate(known):
            if low.fundamental_share(u) < guard.family_share:
                continue
            below = low
            try:
                for h in list(range(low.H + 2, p.H, 2)) + ([p.H] if low.H < p.H else []):
                    rung = p._rung(h)
                    u = solve_at_amplitude(rung, _raised(below, u, rung), amplitude, tol=tol,
                                           max_iter=max_iter, admissible=admissible)[0]
                    below = rung
            except (PinnedFailure, ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError):
                continue
            if admissible is not None and not admissible(u) or any(_same(u, v) for v in exclude):
                continue
            out.append((f"low-harmonic orbit {k + 1} continued in the harmonics", u))
        return out

    def _ladders(self, guard: FamilyGuard, amplitude: float) -> list[tuple[str, np.ndarray]]:
        """The starting mode's orbit at ``amplitude`` continued in the harmonics from the
        low-harmonic families (``harmonic_landing``, from the auxiliary H = 3 family and
        from the fundamental's), where that family's orbit is on the family."""
        p, out = self.problem, []
        tol, max_iter, admissible = self.solver
        for fundamental in (False, True):
            try:
                start = p.harmonic_landing(amplitude, self.amplitude_max, tol=tol, max_iter=max_iter,
                                           admissible=admissible, fundamental=fundamental)
            except (ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError):
                continue
            if start is not None and start[1] >= guard.family_share:
                out.append(("harmonic ladder" + (" from the fundamental" if fundamental else ""), start[0]))
        return out

    def last_resort(self, us: list, recs: list, guard: FamilyGuard, amplitude: float,
                    amplitude_max: float) -> list[tuple[str, np.ndarray]]:
        """The orbit at ``amplitude`` reached by a Newton homotopy from the fundamental's
        family's (``homotopy_landing``: where the family resumes above a fold of the
        branch, at another frequency, and no start taken from the branch converges to it),
        at the first :data:`HOMOTOPIES` targets of a search."""
        frontier = float(recs[guard.frontier_index]["amplitude"])
        done = self._homotopies.get(frontier, 0)
        if done >= HOMOTOPIES:
            return []
        self._homotopies[frontier] = done + 1
        tol, max_iter, admissible = self.solver
        try:
            u, _ = self.problem.homotopy_landing(amplitude, amplitude_max, tol=tol, max_iter=max_iter,
                                                 admissible=admissible)
        except (ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError):
            return []
        return [("homotopy from the fundamental's family", u)]
