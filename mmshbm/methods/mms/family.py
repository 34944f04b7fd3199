"""How an MMS-HBM branch stays on its family: modal energy shares per point, and the
starts of the search beyond a frontier (a mixin of
:class:`~mmshbm.methods.mms.conservative.MMSHBMProblem`, used by :mod:`mmshbm.family`;
the starts from low-harmonic families: :mod:`mmshbm.methods.mms.landings`)."""

from __future__ import annotations

import weakref

import numpy as np

from ...harmonic.modal_energy import kinetic_energy_shares
from ._family_kernels import family_records, harmonic_energies
from .corrector_kernels import _start_mode_share
from .held import _held_frequency
from .landings import LandingsMixin

__all__ = ["FamilyMixin"]

#: model -> {(H, mode): modal basis of the energy shares} (the model is immutable)
_BASES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


class FamilyMixin(LandingsMixin):
    """Family bookkeeping of an MMS-HBM problem (needs the attributes of ``MMSHBMProblem``)."""

    #: the starting mode's projections of :meth:`_share_setup`; None until built
    _share_data: tuple | None = None

    def _fast_setup(self):
        """Data of the compiled corrector, or False: none by default (the host overrides)."""
        return False

    # ------------------------------------------------------------------ jumps
    def frequency_of(self, u: np.ndarray) -> float:
        """Ω/2π (Hz) of the scaled unknowns ``u`` (no evaluation: the trust region of the
        jumps' Newton iterates)."""
        return float(u[-1] * self.colscale[-1] / (2 * np.pi))

    def family_frequency_limit(self) -> float:
        """The highest frequency (Hz) the starting mode's backbone can reach: the zero-gap
        limit of a single one-sided contact, else the frequency with every contact DOF
        held at its stop (rigid stops stiffen the structure at most that far)."""
        return float(self._omega_range()[1] / (2 * np.pi))

    def family_frequency_ceiling(self) -> float:
        """The highest frequency (Hz) a landing on the starting mode's family may have:
        the linear mode's with every contact DOF held at its stop, or
        :meth:`family_frequency_limit` if higher. The zero-gap limit of one one-sided
        contact, 2/(1/f_open + 1/f_held), is exact for one DOF only: on chains of two to
        seven masses the exact first-mode orbit above a 2:1 tongue lies 25–31 % above it
        at 10 gaps (and below the held frequency)."""
        top = _held_frequency(self.model, self.contact_dofs, self.mode)
        return float(max(top, self.family_frequency_limit()))

    def open_amplitude(self) -> float:
        """The amplitude (m) of the linear mode at which its first contact reaches its stop
        (above it the linear mode is no solution): min over the contacts of gap / |φ_c|,
        φ normalised to a unit swing of the amplitude DOF."""
        shape = self.mode_shape_c
        c_list = self.model.c.tolist()
        out = np.inf
        for ct in self.model.contacts:
            motion = abs(float(shape[c_list.index(ct.dof)]))
            if motion > 0 and ct.gap > 0:
                out = min(out, ct.gap / motion)
        return float(out)

    def leads_fundamental(self, u: np.ndarray) -> bool:
        """Whether the starting mode holds the largest share of the fundamental harmonic's
        kinetic energy among the tracked open-contact modes (:meth:`modal_shares`): the
        fundamental's shape is the starting mode's, moved toward its closed-contact form,
        not another mode's backbone."""
        fundamental = self.modal_shares(u)[:, 1]
        return bool(fundamental[self.mode - 1] >= fundamental.max())

    def mode_leads(self, u: np.ndarray, omega: float) -> float:
        """The definition's third condition at the orbit ``u`` of angular frequency
        ``omega`` (rad/s): 1.0 where the starting mode holds the largest share of the
        fundamental harmonic's kinetic energy among the tracked open-contact modes
        (:meth:`leads_fundamental`), 0.0 where another mode does, NaN where Ω lies at or
        below the next open-contact mode's frequency (there no other mode's orbit has a
        dominant fundamental at Ω: the condition is void, and not evaluated)."""
        freqs = self._modal_basis()[0]
        if len(freqs) <= self.mode or omega <= 2 * np.pi * float(freqs[self.mode]):
            return float("nan")
        return 1.0 if self.leads_fundamental(u) else 0.0

    def family_starts(self):
        """The starts of the deflated search beyond a frontier
        (:class:`~mmshbm.methods.mms.family_starts.MMSHBMStarts`, a new one per call)."""
        from .family_starts import MMSHBMStarts

        return MMSHBMStarts(self)

    def scaled_state(self, u: np.ndarray, factor: float) -> np.ndarray:
        """``u`` with every displacement coefficient (and pole unknown) times ``factor``,
        Ω kept: far above the gap a piecewise-linear system is nearly homogeneous, so
        this predicts the family at ``factor`` times the amplitude of ``u``."""
        out = np.array(u, dtype=float)
        out[:-1] *= factor
        return out

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
                       amplitude_min: float = 0.0, *, family_share: float):
        """Land on the family beyond the internal resonance the branch met after the family
        point ``u_from`` (record ``rec_from``): the resonant pair (harmonic k, mode j) is
        the one whose energy share peaked over the ``excursion`` states; the branch is
        continued with harmonic k filtered out past kΩ = ω_j and released there
        (:func:`mmshbm.methods.mms.filtered.pass_resonance`). Returns (u, amplitude).
        A start of the search beyond a frontier (:mod:`mmshbm.family.deflation`); the
        landing lies above ``amplitude_min`` and its fundamental holds ``family_share``."""
        from .filtered import pass_resonance

        freqs = self.tracked_frequencies
        best, pair = -1.0, None
        for state in excursion:
            shares = self.modal_shares(state).copy()
            shares[self.mode - 1, :] = -1.0
            shares[:, 0] = -1.0
            j, k = np.unravel_index(int(np.argmax(shares)), shares.shape)
            if shares[j, k] > best:
                best, pair = float(shares[j, k]), (int(j), int(k))
        if pair is None:
            raise ValueError("no internal resonance identified in the excursion")
        j, k = pair
        return pass_resonance(self, u_from, float(rec_from["amplitude"]), k, float(freqs[j]) / k,
                              amplitude_max, amplitude_min=amplitude_min, family_share=family_share)

    def _modal_basis(self):
        """Open-contact modes tracked for the energy shares: those below (H + 1) times the
        first clamped-contact frequency (an upper bound of Ω on the backbone), at least the
        starting mode and the next, at most 30; built once per model, H and mode."""
        if self._modal is None:
            model = self.model
            memo = _BASES.setdefault(model, {})
            if (self.H, self.mode) in memo:
                self._modal = memo[self.H, self.mode]
                return self._modal
            n_l = len(model.l)
            f_track = (self.H + 1) * self._upper_frequency()
            n = min(n_l, 30, max(self.mode + 1, 2))
            freqs, _ = model.linear_modes(min(n_l, 30))
            n = max(n, int(np.searchsorted(freqs, f_track)))
            n = min(n, n_l, 30)
            freqs, modes = model.linear_modes(n)
            Phi = modes[model.l]
            M_ll = model.blocks["M_ll"]
            self._modal = memo[self.H, self.mode] = (freqs, Phi, np.ascontiguousarray((M_ll @ Phi).T), M_ll)
        return self._modal

    def _start_row(self) -> np.ndarray:
        """The starting mode's row of Φᵀ M, shape (1, n_l): one object per model, H and mode
        (the key of its projections in the condensation's store)."""
        basis = self._modal_basis()
        memo = _BASES.setdefault(self.model, {})
        key = ("row", self.H, self.mode)
        row = memo.get(key)
        if row is None or row[0] is not basis:
            row = memo[key] = (basis, np.ascontiguousarray(basis[2][self.mode - 1:self.mode]))
        return row[1]

    def _upper_frequency(self) -> float:
        """First eigenfrequency (Hz) of the structure with its massless DOFs clamped: the modal
        reduction's first fixed-interface mode when the condensation has one."""
        import scipy.linalg as la

        red = getattr(self.cond, "reduction", None)
        if red is not None and red.n_modes:
            return float(red.omega[0] / (2 * np.pi))
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
        return self._modal_basis()[0].copy()

    def modal_shares(self, u: np.ndarray) -> np.ndarray:
        """Period-mean kinetic energy share of each tracked open-contact mode j (rows) in
        each harmonic k (columns), shape (n_tracked, H+1)
        (:func:`~mmshbm.harmonic.modal_energy.kinetic_energy_shares`)."""
        a, omega = self.unpack(u)
        freqs, Phi, MPhiT, M_ll = self._modal_basis()
        eta = self.unpack_eta(u)
        if self.cond.backend == "modal":
            return self._modal_shares_projected(a, omega, eta, MPhiT)
        Ql = self._recover(a, omega, eta)
        shares, _ = kinetic_energy_shares(Phi, MPhiT, Ql, omega, M_ll)
        return shares

    def mode_share(self, u: np.ndarray) -> float:
        """Share of the period-mean kinetic energy in the starting mode at the fundamental
        harmonic (the starting mode's share, records ``mode_share``); with the modal back end
        from one projected row, else from :meth:`modal_shares`."""
        fast = self._fast_setup()
        if not fast:
            return float(self.modal_shares(u)[self.mode - 1, 1])
        a, omega = self.unpack(u)
        _, dD = self._condensed(omega, True)
        return self._mode_share_at(u, a, omega, self.unpack_eta(u), dD)

    def _mode_share_at(self, u: np.ndarray, a: np.ndarray, omega: float, eta: np.ndarray,
                       dD: np.ndarray) -> float:
        """:meth:`mode_share` of ``u`` from its unpacked (a, Ω, η) and ∂D/∂Ω at Ω (the
        monitor has them)."""
        fast = self._fast_setup()
        if not fast:
            return float(self.modal_shares(u)[self.mode - 1, 1])
        row, s0, s, sv, pole_j = self._share_setup()
        D0, B, w2, Rs, keep, static, rtol = fast["cond"]
        return float(_start_mode_share(np.ascontiguousarray(a), eta, omega, dD, self._pole_k,
                                       pole_j, self._pole_w2, B, w2, keep, s0, s, sv))

    def harmonic_energies(self, u: np.ndarray) -> np.ndarray:
        """Period-mean kinetic energy (J) of each harmonic k = 0..H of the motion, shape (H+1,),
        from the condensed stiffness alone: T_k = −(Ω/8) a_kᵀ ∂D_k/∂Ω a_k (with the pole
        unknowns' part). Exact for the condensation used (no modal basis needed): the
        kinetic energy of the DOFs with mass in harmonic k, whatever their shape."""
        a, omega = self.unpack(u)
        _, dD = self._condensed(omega, True)
        return harmonic_energies(a, dD, self.unpack_eta(u), self._pole_k, omega)

    def fundamental_share(self, u: np.ndarray) -> float:
        """Share (0..1) of the period-mean kinetic energy in the fundamental harmonic (k = 1),
        all DOFs together (:meth:`harmonic_energies`): the family measure of
        :mod:`mmshbm.family.definition` (see docs/resonances.md). A change of the fundamental's
        shape (toward the closed-contact mode) leaves it unchanged; energy moving into a
        harmonic k >= 2 (near an internal resonance kΩ ≈ ω_j) lowers it."""
        energies = self.harmonic_energies(u)
        total = float(energies[1:].sum())
        return float(energies[1] / total) if total > 0 else 1.0

    def family_records(self, u: np.ndarray) -> dict:
        """The per-point records of the family guard: ``fundamental_share``
        (:meth:`fundamental_share`) and, for the harmonic k >= 2 with the most kinetic
        energy, the detuning ``resonance_detuning`` = kΩ/ω_j − 1 from the nearest tracked
        open-contact mode j (``resonance_harmonic`` k, ``resonance_mode`` j, 1-based; 0
        and NaN for H = 1). A detuning that changes sign along the branch is an internal
        resonance crossed."""
        a, omega = self.unpack(u)
        _, dD = self._condensed(omega, True)
        return self._family_records_at(a, omega, self.unpack_eta(u), dD)

    def _family_records_at(self, a: np.ndarray, omega: float, eta: np.ndarray, dD: np.ndarray) -> dict:
        """:meth:`family_records` from the unpacked (a, Ω, η) and ∂D/∂Ω at Ω, in one
        compiled pass (:mod:`._family_kernels`)."""
        return family_records(a, dD, eta, self._pole_k, omega, self._modal_basis()[0])

    def _share_setup(self):
        """(row, s0, s, sv, pole_j): the starting mode's projections for
        :func:`~mmshbm.methods.mms.corrector_kernels._start_mode_share` (modal back end; built once)."""
        data = self._share_data
        if data is None:
            cond = self.cond
            row = self._start_row()
            _, S0, S, SV = _projections(cond, row)
            sv = np.zeros((0, self.n_c)) if cond.complete else np.array([V[0] for V in SV[1:]])
            pole_j = np.array([j for _, j in self.pole_set.pairs], dtype=np.int64) if self.n_poles \
                else np.zeros(0, dtype=np.int64)
            data = self._share_data = (row, np.ascontiguousarray(S0[0]), np.ascontiguousarray(S[0]),
                                       np.ascontiguousarray(sv), pole_j)
        return data

    def branch_records(self, states) -> dict:
        """Per-point records computed once for a whole branch: ``modal_shares``, shape
        (n_points, n_tracked, H+1) (:meth:`modal_shares`; with the modal back end for all
        points at once)."""
        states = np.asarray(states, dtype=float)
        if not len(states):
            return {"modal_shares": np.empty((0,))}
        if self.cond.backend != "modal":
            return {"modal_shares": np.array([self.modal_shares(u) for u in states])}
        return {"modal_shares": self._modal_shares_all(states)}

    def _modal_shares_all(self, states: np.ndarray) -> np.ndarray:
        """:meth:`_modal_shares_projected` for many points at once, shape (n, n_t, H+1)."""
        freqs, Phi, MPhiT, M_ll = self._modal_basis()
        cond, H, n_c = self.cond, self.H, self.n_c
        _, S0, S, SV = _projections(cond, MPhiT)
        X = states * self.colscale[None, :]
        n_a = (H + 1) * n_c
        a = X[:, :n_a].reshape(len(states), H + 1, n_c)
        eta = X[:, n_a:n_a + self.n_poles]
        omega = X[:, -1]
        x = (np.arange(H + 1)[None, :] * omega[:, None]) ** 2  # (n, H+1)
        w2 = cond._w2
        keep = np.ones((H + 1, len(w2)), dtype=bool)
        keep[0] = False
        pairs = self.pole_set.pairs if self.n_poles else []
        for k, j in pairs:
            keep[k, j] = False
        den = w2[None, None, :] - x[:, :, None]
        c = np.where(keep[None], x[:, :, None] / (w2[None, None, :] * np.where(keep[None], den, 1.0)), 0.0)
        Ba = np.einsum("mc,nkc->nkm", cond.b_j, a)
        Y = np.einsum("tc,nkc->ntk", S0, a) + np.einsum("tm,nkm->ntk", S, c * Ba)
        if not cond.complete:
            for i in range(1, len(SV)):
                Y += np.einsum("tc,nkc->ntk", SV[i], a) * x[:, None, :] ** i
        Y = -Y
        for p, (k, j) in enumerate(pairs):
            Y[:, :, k] -= S[None, :, j] * (eta[:, p] * x[:, k] / self._pole_w2[p])[:, None]
        # the total kinetic energy from the condensed stiffness
        _, dD = self.condensed_many(omega, derivative=True)
        q = np.einsum("nki,nkij,nkj->nk", a, dD, a)
        for p, k in enumerate(self._pole_k):
            q[:, k] -= 2.0 * k * k * omega * eta[:, p] ** 2
        quad = q[:, 1:].sum(axis=1)
        total = -omega / 8.0 * quad
        shares = np.zeros((len(states), len(MPhiT), H + 1))
        ok = total > 0
        shares[ok, :, 1:] = 0.25 * x[ok, None, 1:] * Y[ok, :, 1:] ** 2 / total[ok, None, None]
        return shares

    def _modal_shares_projected(self, a, omega, eta, MPhiT) -> np.ndarray:
        """:meth:`modal_shares` from the modal condensation's projections (no recovery of
        the DOFs with mass): modal coordinates η_jk = −φ_jᵀ M Z_k a_k (minus the pole terms),
        T_jk = ¼ (kΩ)² η_jk², and the total kinetic energy from the condensed stiffness,
        T = −(Ω/8) Σ_k a_kᵀ ∂D_k/∂Ω a_k (with the pole unknowns' share)."""
        pairs = self.pole_set.pairs if self.n_poles else []
        Y = self.cond.projected_cosine_recovery(omega, a, MPhiT, exclude=pairs)  # (n_t, H+1)
        x = (np.arange(self.H + 1) * omega) ** 2
        if self.n_poles:
            S = self.cond._projections[id(MPhiT)][2]  # Φᵀ M φ_j
            for p, (k, j) in enumerate(pairs):
                Y[:, k] -= S[:, j] * eta[p] * x[k] / self._pole_w2[p]
        _, dD = self._condensed(omega, True)
        quad = np.einsum("ki,kij,kj->k", a, dD, a)
        for p, k in enumerate(self._pole_k):
            quad[k] -= 2.0 * k * k * omega * eta[p] ** 2
        total = -omega / 8.0 * quad[1:].sum()
        shares = np.zeros((len(MPhiT), self.H + 1))
        if total > 0:
            shares[:, 1:] = 0.25 * x[None, 1:] * Y[:, 1:] ** 2 / total
        return shares


def _projections(cond, projector: np.ndarray) -> tuple:
    """(projector, P Z_0, P φ_j, [P Ṽ_i]) of the modal condensation ``cond`` for
    ``projector`` P (n_p, n_l): its kept projections, built (by a recovery of zero motion)
    when it has none for that object."""
    cached = cond._projections.get(id(projector))
    if cached is None or cached[0] is not projector:
        cond.projected_cosine_recovery(0.0, np.zeros((2, cond.n_c)), projector)  # builds them
        cached = cond._projections[id(projector)]
    return cached
