"""How an MMS-HBM branch stays on its family: modal energy shares per point, and the
landings of the jumps over internal-resonance tongues (a mixin of
:class:`~mmshbm.methods.mms_hbm.MMSHBMProblem`, used by :mod:`mmshbm.core.family`)."""

from __future__ import annotations

import numpy as np

from ..core.modal_energy import kinetic_energy_shares

__all__ = ["FamilyMixin"]


class FamilyMixin:
    """Family bookkeeping of an MMS-HBM problem (needs the attributes of ``MMSHBMProblem``)."""

    # ------------------------------------------------------------------ jumps
    def family_predictor(self, u_from: np.ndarray, amplitude_from: float, amplitude_to: float,
                         amplitude_max: float) -> np.ndarray:
        """Predicted unknowns on the starting mode's family at ``amplitude_to``, from the
        family point ``u_from`` at ``amplitude_from``: ``u_from`` plus the change along
        the auxiliary low-harmonic branch (:meth:`reference_branch`)."""
        ref = self.reference_branch(amplitude_max)
        if ref is None:
            raise ValueError("no reference branch")
        _, A, U = ref
        if not (A[0] <= amplitude_from <= A[-1] and A[0] <= amplitude_to <= A[-1]):
            raise ValueError("the reference branch does not cover the jump")

        def at(a):
            return np.array([np.interp(a, A, U[:, i]) for i in range(U.shape[1])])

        aux = ref[0]
        n_ref = (aux.H + 1) * self.n_c
        delta = at(amplitude_to) - at(amplitude_from)
        a, omega = self.unpack(u_from)
        da = (delta[:n_ref] * aux.colscale[:n_ref]).reshape(aux.H + 1, self.n_c)
        a = a.copy()
        a[: aux.H + 1] += da
        return self.pack(a, omega + delta[-1] * aux.colscale[-1])

    def family_landing(self, u_from: np.ndarray, rec_from: dict, excursion: list, amplitude_max: float,
                       amplitude_min: float = 0.0):
        """Land on the family beyond the internal resonance the branch met after the family
        point ``u_from`` (record ``rec_from``): the resonant pair (harmonic k, mode j) is
        the one whose energy share peaked over the ``excursion`` records; the branch is
        continued with harmonic k filtered out past kΩ = ω_j and released there
        (:func:`mmshbm.methods.filtered.pass_resonance`). Returns (u, amplitude). Used by
        the jumps of :mod:`mmshbm.core.family`; the landing lies above ``amplitude_min``."""
        from .filtered import pass_resonance

        freqs = self.tracked_frequencies
        best, pair = -1.0, None
        for rec in excursion:
            shares = np.asarray(rec.get("modal_shares"))
            if shares.ndim != 2:
                continue
            shares = shares.copy()
            shares[self.mode - 1, :] = -1.0
            shares[:, 0] = -1.0
            j, k = np.unravel_index(int(np.argmax(shares)), shares.shape)
            if shares[j, k] > best:
                best, pair = float(shares[j, k]), (int(j), int(k))
        if pair is None:
            raise ValueError("no internal resonance identified in the excursion")
        j, k = pair
        return pass_resonance(self, u_from, float(rec_from["amplitude"]), k, float(freqs[j]) / k,
                              amplitude_max, amplitude_min=amplitude_min)

    def reference_branch(self, amplitude_max: float):
        """(problem, amplitudes ascending, scaled unknowns) of the family at H_ref = 3 (1
        for H <= 3): the monotone front of an auxiliary backbone, continued once by plain
        path following up to ``amplitude_max`` (cached; recomputed for a larger one).
        With so few harmonics the branch meets no internal resonance with the higher
        modes that the H-harmonic branch meets. None when H_ref would not be below H."""
        cached = getattr(self, "_reference", None)
        if cached is not None and cached[1][-1] >= amplitude_max * (1 - 1e-9):
            return cached
        from ..core.continuation import ContinuationOptions, continue_branch

        H_ref = 3 if self.H > 3 else 1
        if H_ref >= self.H:
            return None
        aux = type(self)(self.model, H_ref, r=self.r_each, mode=self.mode, backend=self.cond.backend,
                            projection=self.projection)
        aux._modal = self._modal
        start = 0.5 * self.gap if self.gap > 0 else 0.01 * amplitude_max
        res = continue_branch(aux, aux.linear_point(start), aux.initial_tangent(),
                              ContinuationOptions(bounds={"amplitude": (0.0, amplitude_max)}, follow="path",
                                                  max_steps=400))
        A = res.records.get("amplitude", np.empty(0))
        keep, best = [], -np.inf
        for i, a in enumerate(A):
            if a > best:
                keep.append(i)
                best = a
        if len(keep) < 2:
            return None
        self._reference = (aux, A[keep], res.u[keep])
        return self._reference

    # ------------------------------------------------------------------ modal energy
    def _modal_basis(self):
        """Open-contact modes tracked for the energy shares: those below (H + 1) times the
        first clamped-contact frequency (an upper bound of Ω on the backbone), at least the
        starting mode and the next, at most 30."""
        if self._modal is None:
            model = self.model
            n_l = len(model.l)
            f_track = (self.H + 1) * self._upper_frequency()
            n = min(n_l, 30, max(self.mode + 1, 2))
            freqs, _ = model.linear_modes(min(n_l, 30))
            n = max(n, int(np.searchsorted(freqs, f_track)))
            n = min(n, n_l, 30)
            freqs, modes = model.linear_modes(n)
            Phi = modes[model.l]
            M_ll = model.blocks["M_ll"]
            self._modal = (freqs, Phi, np.ascontiguousarray((M_ll @ Phi).T), M_ll)
        return self._modal

    def _upper_frequency(self) -> float:
        """First eigenfrequency (Hz) of the structure with its massless DOFs clamped."""
        import scipy.linalg as la

        b = self.model.blocks
        if len(self.model.l) <= 600:
            w2 = la.eigh(b["K_ll"].toarray(), b["M_ll"].toarray(), eigvals_only=True, subset_by_index=(0, 0))
            return float(np.sqrt(max(w2[0], 0.0)) / (2 * np.pi))
        import scipy.sparse.linalg as spla

        w2 = spla.eigsh(b["K_ll"], k=1, M=b["M_ll"], sigma=0.0, which="LM", v0=np.ones(len(self.model.l)))[0]
        return float(np.sqrt(max(w2[0], 0.0)) / (2 * np.pi))

    @property
    def tracked_frequencies(self) -> np.ndarray:
        """Open-contact linear frequencies (Hz) of the modes in ``records["modal_shares"]``."""
        return self._modal_basis()[0]

    def modal_shares(self, u: np.ndarray) -> np.ndarray:
        """Period-mean kinetic energy share of each tracked open-contact mode j (rows) in
        each harmonic k (columns), shape (n_tracked, H+1)
        (:func:`~mmshbm.core.modal_energy.kinetic_energy_shares`)."""
        a, omega = self.unpack(u)
        freqs, Phi, MPhiT, M_ll = self._modal_basis()
        Ql = self._recover(a, omega, self.unpack_eta(u))
        shares, _ = kinetic_energy_shares(Phi, MPhiT, Ql, omega, M_ll)
        return shares
