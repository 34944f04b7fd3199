"""Starts of the search beyond a frontier of an MMS-HBM branch, from families with fewer
harmonics: the orbit continued in the harmonics (:meth:`LandingsMixin.harmonic_landing`)
and reached by a homotopy (:meth:`LandingsMixin.homotopy_landing`), with the low-harmonic
branches they start from (a mixin of :class:`~mmshbm.methods.mms.family.FamilyMixin`,
used by :mod:`mmshbm.methods.mms.family_starts`)."""

from __future__ import annotations

import numpy as np

__all__ = ["LandingsMixin"]


class LandingsMixin:
    """Low-harmonic families and the landings started from them (needs the attributes
    of ``MMSHBMProblem``)."""

    #: (problem, amplitudes, states) of the H_ref family (:meth:`reference_branch`); None until built
    _reference: tuple | None = None

    def harmonic_landing(self, amplitude: float, amplitude_max: float, *, tol: float, max_iter: int,
                         admissible=None, fundamental: bool = False) -> tuple[np.ndarray, float] | None:
        """The starting mode's orbit at ``amplitude`` (m) continued in the harmonics: a
        low-harmonic family solved with the amplitude pinned there, then solved again at
        H_ref + 2, H_ref + 4, ..., H harmonics, each from the one before (the new
        harmonics zero). Each rung adds a few harmonics to an orbit that has them small,
        so Newton stays on that orbit where a jump's predictors at H (taken from the
        family below a tongue) converge nowhere. The low-harmonic family is the auxiliary
        one of :meth:`reference_branch` (H_ref = 3) where it reaches ``amplitude``, else
        the fundamental alone (H_ref = 1), whose branch meets no internal resonance of a
        higher harmonic and reaches the bound where the H_ref = 3 branch ends in one.
        ``fundamental=True`` starts from the fundamental's family wherever it reaches
        ``amplitude``: the H_ref = 3 family carries harmonic 2 and can itself sit on a
        2:1 tongue's side up to the bound, below the starting mode's orbit above the
        tongue (docs/resonances.md).

        At high H an impacting orbit spreads its kinetic energy over many harmonics, and
        its fundamental's share can fall below the family's threshold while the orbit
        goes on (docs/resonances.md); an internal resonance instead moves the energy into
        one harmonic. So every rung must keep the fundamental the harmonic with the most
        kinetic energy (:meth:`harmonic_energies`).

        Returns
        -------
        (u, share_ref): the scaled unknowns at H and the fundamental's share of the
        kinetic energy of the H_ref orbit (:meth:`fundamental_share`), which says
        whether the ladder started on the family.
        None with ``fundamental=True`` where the default ladder starts from the
        fundamental's family already (H <= 3, or the H = 3 family does not reach
        ``amplitude``).

        Raises
        ------
        ValueError
            Without a low-harmonic branch that reaches ``amplitude``.
        PinnedFailure
            When a rung does not converge, leaves ``admissible`` (the trust region) or
            gives a harmonic above the fundamental more kinetic energy than it.
        """
        from ...core.pinned import PinnedFailure, solve_at_amplitude

        def reaches(branch) -> bool:
            # a branch that reaches the bound ends on it to round-off (its end refined onto it)
            return branch is not None and branch[1][0] <= amplitude <= branch[1][-1] * (1 + 1e-9)

        ref = self.reference_branch(amplitude_max)
        if fundamental:
            if not reaches(ref) or ref[0].H == 1:
                return None
            ref = self._fundamental_branch(amplitude_max)
        elif not reaches(ref):
            ref = self._fundamental_branch(amplitude_max)
        if not reaches(ref):
            raise ValueError("no low-harmonic branch reaches the amplitude")
        aux, A, U = ref
        u0 = np.array([np.interp(amplitude, A, U[:, i]) for i in range(U.shape[1])])
        u = solve_at_amplitude(aux, u0, amplitude, tol=tol, max_iter=max_iter, admissible=admissible)[0]
        share_ref = aux.fundamental_share(u)
        below = aux
        for h in list(range(aux.H + 2, self.H, 2)) + [self.H]:
            rung = self._rung(h)
            u = solve_at_amplitude(rung, _raised(below, u, rung), amplitude, tol=tol, max_iter=max_iter,
                                   admissible=admissible)[0]
            energies = rung.harmonic_energies(u)
            k = 2 + int(np.argmax(energies[2:]))
            if energies[k] > energies[1]:
                raise PinnedFailure(f"harmonic {k} holds more kinetic energy than the fundamental at H = {h}")
            below = rung
        return u, share_ref

    def homotopy_landing(self, amplitude: float, amplitude_max: float, *, tol: float, max_iter: int,
                         admissible=None) -> tuple[np.ndarray, float]:
        """The orbit at ``amplitude`` (m) reached from the family of the fundamental
        alone (H = 1, which meets no internal resonance of a higher harmonic): its orbit
        there, raised to H harmonics (the others zero), solved by the Newton homotopy
        (:func:`mmshbm.core.homotopy.pinned_homotopy`). Where the H-harmonic family
        resumes above a fold of the branch below, at a lower frequency (the branch below
        can stiffen past the family's limit, e.g. a light DOF rattling against its stop,
        or fold by its truncation), no predictor taken from the branch below converges
        to it, nor does Newton from the raised orbit, whose basin on the nonsmooth
        residual is small; the homotopy's curve does.

        Returns (u, f_start): the scaled unknowns at H and the frequency (Hz) of the
        fundamental family's orbit the homotopy started from. Raises ValueError without a
        fundamental family that reaches ``amplitude``, PinnedFailure when the homotopy
        or its final solve fails.
        """
        from ...core.homotopy import pinned_homotopy
        from ...core.pinned import solve_at_amplitude

        ref = self._fundamental_branch(amplitude_max)
        if ref is None or not ref[1][0] <= amplitude <= ref[1][-1] * (1 + 1e-9):  # as above
            raise ValueError("no fundamental family reaches the amplitude")
        aux, A, U = ref
        u0 = np.array([np.interp(amplitude, A, U[:, i]) for i in range(U.shape[1])])
        u = solve_at_amplitude(aux, u0, amplitude, tol=tol, max_iter=max_iter, admissible=admissible)[0]
        f_start = aux.frequency_of(u)
        u = pinned_homotopy(self, _raised(aux, u, self), amplitude, tol=tol, max_iter=max_iter,
                            admissible=admissible)[0]
        return u, f_start

    def _fundamental_branch(self, amplitude_max: float):
        """(problem, amplitudes ascending, scaled unknowns) of the family with the
        fundamental alone (H = 1), as :meth:`reference_branch` builds its own (cached)."""
        cached = self.__dict__.get("_fundamental")
        if cached is not None and cached[1][-1] >= amplitude_max * (1 - 1e-9):
            return cached
        if self.H == 1:
            return None
        front = _rising_front(self._rung(1), self.gap, amplitude_max)
        if front is None:
            return None
        self._fundamental = front
        return self._fundamental

    def _rung(self, h: int):
        """This problem with ``h`` harmonics (itself for h = H; built once per h)."""
        if h == self.H:
            return self
        rungs = self.__dict__.setdefault("_rungs", {})
        if h not in rungs:
            rungs[h] = type(self)(self.model, h, r=self.r_each, mode=self.mode, backend=self.cond.backend,
                                  projection=self.projection)
        return rungs[h]

    def reference_branch(self, amplitude_max: float):
        """(problem, amplitudes ascending, scaled unknowns) of the family at H_ref = 3 (1
        for H <= 3): the monotone front of an auxiliary backbone, continued once by plain
        path following up to ``amplitude_max`` (cached, also where the branch ends below
        it; recomputed for a larger one). With so few harmonics the branch meets no
        internal resonance with the higher modes that the H-harmonic branch meets. None
        when H_ref would not be below H or the branch has fewer than two points."""
        cached = self._reference  # (amplitude_max asked, front or None)
        if cached is not None and cached[0] >= amplitude_max * (1 - 1e-9):
            return cached[1]
        H_ref = 3 if self.H > 3 else 1
        if H_ref >= self.H:
            return None
        aux = type(self)(self.model, H_ref, r=self.r_each, mode=self.mode, backend=self.cond.backend,
                            projection=self.projection)
        aux._modal = self._modal
        self._reference = (amplitude_max, _rising_front(aux, self.gap, amplitude_max))
        return self._reference[1]

    # ------------------------------------------------------------------ modal energy


def _raised(low, u: np.ndarray, high) -> np.ndarray:
    """Scaled unknowns ``u`` of the MMS-HBM problem ``low`` as unknowns of ``high`` (more
    harmonics): the harmonics ``low`` has, the others zero; the pole unknowns of the pairs
    (k, j) both have carried over, the others at their value for (a, Ω)."""
    a_low, omega = low.unpack(u)
    a = np.zeros((high.H + 1, high.n_c))
    m = min(low.H, high.H) + 1
    a[:m] = a_low[:m]
    out = high.pack(a, omega)
    if low.n_poles and high.n_poles:
        eta = low.unpack_eta(u)
        index = {(int(k), int(j)): p for p, (k, j) in enumerate(low.pole_set.pairs)}
        n_a = (high.H + 1) * high.n_c
        for p, (k, j) in enumerate(high.pole_set.pairs):
            if (int(k), int(j)) in index:
                out[n_a + p] = eta[index[int(k), int(j)]] / high.eta_scale[p]
    return out


def _rising_front(aux, gap: float, amplitude_max: float):
    """(``aux``, amplitudes ascending, scaled unknowns) of the points of ``aux``'s branch,
    continued by plain path following from its linear mode at half a gap up to
    ``amplitude_max``, that each reach a new largest amplitude; None with fewer than two."""
    from ...core.continuation import ContinuationOptions, continue_branch

    start = 0.5 * gap if gap > 0 else 0.01 * amplitude_max
    res = continue_branch(aux, aux.linear_mode_point(start), aux.initial_tangent(),
                          ContinuationOptions(bounds={"amplitude": (0.0, amplitude_max)}, follow="path",
                                              max_steps=400), catch_interrupt=False)
    A = res.records.get("amplitude", np.empty(0))
    keep, best = [], -np.inf
    for i, a in enumerate(A):
        if a > best:
            keep.append(i)
            best = a
    if len(keep) < 2:
        return None
    return aux, A[keep], res.u[keep]
