"""What MMS-HBM gives beyond its residual: the motion of every DOF, contact forces,
harmonic content and the amplitude with its gradient (a mixin of
:class:`~mmshbm.methods.mms.conservative.MMSHBMProblem`)."""

from __future__ import annotations

import numpy as np

from ... import _validate as check
from ...core.measures import _cosine_peak, check_dof, harmonic_content
from ...harmonic.modal_reduction import KRYLOV_BLOCKS

__all__ = ["SignalsMixin"]

#: (H, τ as bytes) -> cos kτ (read only) of :meth:`SignalsMixin._cosines`: at most
#: _COSINES_KEPT grids, each of at most _COSINES_SAMPLES samples
_COSINES: dict = {}
_COSINES_KEPT = 16
_COSINES_SAMPLES = 4096
#: Ω whose amplitude row derivatives a problem keeps (:meth:`SignalsMixin._amplitude_row_derivatives`)
_ROW_DERIVATIVES_KEPT = 8


class SignalsMixin:
    """Signals of an MMS-HBM point (needs the attributes of ``MMSHBMProblem``)."""

    def _fast_setup(self):
        """Data of the compiled corrector, or False: none by default (the host overrides)."""
        return False

    # ------------------------------------------------------------------ results
    def _recover(self, a: np.ndarray, omega: float, eta: np.ndarray) -> np.ndarray:
        """Coefficients (n_l, 2H+1) of the DOFs with mass of the cosine motion a at Ω."""
        Qc = np.zeros((self.n_c, 2 * self.H + 1))
        Qc[:, 0] = a[0]
        Qc[:, 1::2] = a[1:].T
        if self.n_poles:
            return self.pole_set.recover(omega, Qc, eta)
        return self.cond.recover(omega, Qc)

    def _force_series(self, a: np.ndarray, omega: float, eta: np.ndarray) -> np.ndarray:
        """Cosine coefficients (H+1, n_k) of the stop force λ at each contact DOF: −f where
        the DOF has an upper stop, +f where it has only a lower one (in a clearance λ is
        positive at the upper stop and negative at the lower one)."""
        D, _ = self._condensed(omega, False)
        F = np.einsum("kij,kj->ki", D, a)
        for p, k in enumerate(self._pole_k):
            F[k] -= self._pole_b[p] * eta[p]
        F = F[:, self.cdof]
        return np.where(np.isfinite(self.hi)[None, :], -F, F)

    def contact_signals(self, u: np.ndarray, tau: np.ndarray | None = None):
        """Contact DOF displacement q(τ) (m) and stop force λ(τ) (N) on a grid.

        Returns (tau, q, lam): with one contact DOF ``q`` and ``lam`` have the shape of
        ``tau``; with several, shape (n_contact_dofs, len(tau)) in the order of
        ``contact_dofs``. ``tau`` defaults to a fine grid over one period. λ is the
        truncated series of the force the structure needs (−f at an upper stop, +f at a
        lower one).
        """
        a, omega = self.unpack(u)
        lam_k = self._force_series(a, omega, self.unpack_eta(u))
        if tau is None:
            tau, C = self._tau_fine, self._cos_fine
        else:
            tau = np.asarray(tau, dtype=float)
            C = np.cos(np.outer(np.arange(self.H + 1), tau))
        q = a[:, self.cdof].T @ C
        lam = lam_k.T @ C
        if len(self.cdof) == 1:
            return tau, q[0], lam[0]
        return tau, q, lam

    def condensed_many(self, omegas: np.ndarray, derivative: bool = False):
        """D_k(Ω) (and ∂D_k/∂Ω if ``derivative``) at many frequencies: arrays of shape
        (n_points, H+1, n_c, n_c) (dD None unless asked); the pole terms are left out as
        in :meth:`_condensed`."""
        omegas = np.asarray(omegas, dtype=float)
        shape = (len(omegas), self.H + 1, self.n_c, self.n_c)
        D = np.empty(shape)
        dD = np.empty(shape) if derivative else None
        fast = self._fast_setup()
        if fast:  # the modal kernel straight into the slices (as _condensed, without its cache)
            from ...harmonic._modal_kernels import _modal_dynamic_stiffness
            from ...harmonic.condense import SingularDynamicStiffness

            D0, B, w2, Rs, keep, static, rtol = fast["cond"]
            known = self._by_omega  # those computed before (the same numbers)
            hits = [known.get(omega) for omega in omegas.tolist()]
            if len(hits) and None not in hits:  # every one computed before: copied in one call each
                np.concatenate([hit[0] for hit in hits], out=D.reshape(-1, self.n_c, self.n_c))
                if derivative:
                    np.concatenate([hit[1] for hit in hits], out=dD.reshape(-1, self.n_c, self.n_c))
                return D, dD
            for i, omega in enumerate(omegas):
                omega = float(omega)
                hit = known.get(omega)
                if hit is not None:
                    D[i] = hit[0]
                    if derivative:
                        dD[i] = hit[1]
                    continue
                if _modal_dynamic_stiffness(D0, B, w2, Rs, omega, self.H, keep, rtol, D[i],
                                            dD[i] if derivative else D[i], derivative):
                    raise SingularDynamicStiffness(f"a harmonic of Ω = {omega:.6g} rad/s sits on a "
                                                   "fixed-interface eigenfrequency")
                D[i] += static
                if derivative and len(known) < self._by_omega_max:
                    known[omega] = (D[i].copy(), dD[i].copy())
            return D, dD
        cached = self._cached
        try:
            for i, omega in enumerate(omegas):
                D_i, dD_i = self._condensed(float(omega), derivative)
                D[i] = D_i
                if derivative:
                    dD[i] = dD_i
        finally:
            self._cached = cached  # the corrector's cache stays as it was
        return D, dD

    def contact_signals_many(self, states: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`contact_signals` of many points at once: (q, λ), each of shape
        (n_points, n_contact_dofs, len(tau)) in m and N (contact DOFs in the order of
        ``contact_dofs``)."""
        states = np.atleast_2d(np.asarray(states, dtype=float))
        if states.shape[1:] != (self.n_unknowns,):
            raise ValueError(f"states must have shape (n, {self.n_unknowns}), got {states.shape}")
        X = states * self.colscale[None, :]
        n_a = (self.H + 1) * self.n_c
        a = X[:, :n_a].reshape(len(X), self.H + 1, self.n_c)
        eta = states[:, n_a:n_a + self.n_poles] * self.eta_scale
        D, _ = self.condensed_many(X[:, -1])
        F = np.einsum("nkij,nkj->nki", D, a)
        for p, k in enumerate(self._pole_k):
            F[:, k] -= self._pole_b[p][None, :] * eta[:, p:p + 1]
        F = F[:, :, self.cdof]
        F = np.where(np.isfinite(self.hi)[None, None, :], -F, F)
        C = self._cosines(tau)
        q = np.einsum("nkc,kt->nct", a[:, :, self.cdof], C)
        lam = np.einsum("nkc,kt->nct", F, C)
        return q, lam

    def _cosines(self, tau) -> np.ndarray:
        """cos kτ, shape (H+1, len(tau)), k = 0..H (read only); kept per (H, τ) for grids of
        up to :data:`_COSINES_SAMPLES` samples (every branch check asks for the same)."""
        tau = np.asarray(tau, dtype=float)
        key = (self.H, tau.tobytes()) if tau.ndim == 1 and len(tau) <= _COSINES_SAMPLES else None
        C = _COSINES.get(key)
        if C is None:
            C = np.cos(np.outer(np.arange(self.H + 1), tau))
            C.flags.writeable = False
            if key is not None:
                if len(_COSINES) >= _COSINES_KEPT:
                    _COSINES.clear()
                _COSINES[key] = C
        return C

    def coefficients(self, u: np.ndarray) -> np.ndarray:
        """NLvib-ordered coefficients of all DOFs, shape (n_dof, 2H+1) (sines are zero)."""
        a, omega = self.unpack(u)
        Q = np.zeros((self.model.n_dof, 2 * self.H + 1))
        Q[self.model.c, 0] = a[0]
        Q[self.model.c, 1::2] = a[1:].T
        Q[self.model.l] = self._recover(a, omega, self.unpack_eta(u))
        return Q

    def time_signals(self, u: np.ndarray, dofs=None, n_samples: int = 256):
        """(t (n_samples,) in s, q (n_dofs, n_samples)) over one period for ``dofs``
        (all DOFs when None)."""
        n_samples = check.integer("n_samples", n_samples, minimum=1)
        a, omega = self.unpack(u)
        if dofs is None:
            Q = self.coefficients(u)
        else:
            dofs = np.atleast_1d(np.asarray(dofs))
            if dofs.dtype.kind not in "iu" or np.any((dofs < -self.model.n_dof) | (dofs >= self.model.n_dof)):
                raise ValueError(f"dofs must be integer indices in [0, {self.model.n_dof - 1}], got {dofs}")
            c = self.model.c
            pos = np.searchsorted(c, dofs % self.model.n_dof)
            if len(c) and np.all(c[np.minimum(pos, len(c) - 1)] == dofs % self.model.n_dof):
                # massless DOFs only: their coefficients are unknowns, nothing to recover
                Q = np.zeros((len(dofs), 2 * self.H + 1))
                Q[:, 0] = a[0, pos]
                Q[:, 1::2] = a[1:, pos].T
            else:
                Q = self.coefficients(u)[dofs]
        tau = 2 * np.pi * np.arange(n_samples) / n_samples
        k = np.arange(1, self.H + 1)
        q = Q[:, :1] + Q[:, 1::2] @ np.cos(np.outer(k, tau)) + Q[:, 2::2] @ np.sin(np.outer(k, tau))
        return tau / omega, q

    def contact_force(self, u: np.ndarray, n_samples: int = 256):
        """(t (n_samples,) in s, λ in N) over one period (shape (n_samples,) with one
        contact DOF, (n_contact_dofs, n_samples) with several)."""
        n_samples = check.integer("n_samples", n_samples, minimum=1)
        a, omega = self.unpack(u)
        tau = 2 * np.pi * np.arange(n_samples) / n_samples
        _, _, lam = self.contact_signals(u, tau)
        return tau / omega, lam

    def harmonic_content(self, u: np.ndarray, dof: int | None = None) -> np.ndarray:
        """|Q_k| for k = 0..H of ``dof`` (default the amplitude DOF); shape (H+1,)."""
        dof = check_dof(dof, self.model.n_dof, self.amplitude_dof)
        return harmonic_content(self.coefficients(u)[dof])

    def _amplitude_row(self, a: np.ndarray, omega: float, eta: np.ndarray) -> np.ndarray:
        """Cosine coefficients (H+1,) of the amplitude DOF's motion, from the cosine motion
        ``a`` (H+1, n_c) of the massless DOFs at Ω (rad/s) and the pole unknowns ``eta``
        (n_p,): the amplitude DOF's row of the recovery q_l,k = −Z_k a_k (minus the pole
        terms) alone, the other DOFs with mass not formed (:meth:`_recover` gives them all;
        the same numbers to round-off)."""
        if self._amp_in_c:
            return np.ascontiguousarray(a[:, self._amp_index])
        i = int(np.searchsorted(self.model.l, self.amplitude_dof))
        cond = self.cond
        a = np.asarray(a, dtype=float)
        if getattr(cond, "backend", None) == "modal":
            return self._amplitude_row_modal(cond, i, a, omega, eta)
        # a direct back end (RCM order): the solves of the recovery, one row of each Z_k
        r = int(np.flatnonzero(cond.perm == i)[0])
        poles = self.pole_set if self.n_poles else None
        row = np.empty(self.H + 1)
        row[0] = -(cond._Z0[r] @ a[0])
        for k in range(1, self.H + 1):
            Z = poles._z_regular(k, omega) if poles is not None else cond._solve(k * omega)
            row[k] = -(Z[r] @ a[k])
        if poles is not None:
            for p, (k, j) in enumerate(poles.pairs):
                row[k] -= poles.phi[r, j] * eta[p]
        return row

    def _amplitude_row_modal(self, cond, i: int, a: np.ndarray, omega: float, eta: np.ndarray) -> np.ndarray:
        """:meth:`_amplitude_row` of the modal condensation: row ``i`` (``model.l`` order) of
        its recovery (:meth:`~mmshbm.harmonic.modal.ModalCondensation.recover`, the same
        factors, shared through its cache of the last Ω) applied to the cosine columns."""
        H = a.shape[0] - 1
        pairs = self.pole_set.pairs if self.n_poles else []
        key = (H, float(omega), tuple(pairs))
        last = cond._recovery_factors
        if last is not None and last[0] == key:
            x, c = last[1]
        else:
            x, c = cond._recovery_coefficients(H, float(omega), key[2])
            cond._recovery_factors = ((H, float(omega), tuple(map(tuple, pairs))), (x, c))
        cols = np.concatenate([[0], np.arange(1, 2 * H, 2)])  # the cosine column of each harmonic
        x, c = x[cols], c[cols]
        cond._static_recovery()  # Z_0 and Ṽ_i (built once per reduction; done by any recovery before)
        aT = a.T
        row = cond._Z0[i] @ aT + cond.phi_j[i] @ ((cond.b_j @ aT) * c.T)
        if not cond.complete:
            for n in range(1, KRYLOV_BLOCKS):
                row += (cond._V[n][i] @ aT) * x**n
        row = -row
        if self.n_poles:  # the left-out pole terms, −φ_j η_jk (kΩ)²/ω_j², as the pole set's recovery
            phi_row = self.pole_set.phi[i]
            for p, (k, j) in enumerate(pairs):
                row[k] -= phi_row[j] * eta[p] * (k * omega) ** 2 / self._pole_w2[p]
        return row

    def _amplitude_row_derivatives(self, omega: float) -> tuple[np.ndarray, np.ndarray]:
        """(G, G′) of the amplitude DOF with mass at Ω (rad/s): the amplitude row is linear in
        the pole and cosine unknowns at fixed Ω, row = G·u[:-1] for the scaled unknowns u, so
        G (H+1, (H+1) n_c + n_p) is its derivative with respect to them and G′ = ∂G/∂u_Ω
        (u_Ω = Ω/``colscale[-1]``) that of ∂row/∂u_Ω = G′·u[:-1]. Each harmonic k depends
        on a_k (columns k n_c..(k+1) n_c − 1, :meth:`_amplitude_row`'s coefficients) and
        on the η_p of harmonic k_p = k alone. Kept for the last :data:`_ROW_DERIVATIVES_KEPT`
        Ω (read only)."""
        omega = float(omega)
        kept = self.__dict__.get("_row_derivatives")
        if kept is None or kept[0] is not self.cond or kept[1] != self.H:
            kept = self._row_derivatives = (self.cond, self.H, {})
        hit = kept[2].get(omega)
        if hit is not None:
            return hit
        i = int(np.searchsorted(self.model.l, self.amplitude_dof))
        cond = self.cond
        if getattr(cond, "backend", None) == "modal":
            R, dR, P, dP = self._row_coefficients_modal(cond, i, omega)
        else:  # a direct back end: Ω by central differences, step 1e-6 of the scaled Ω (the
            # solves' round-off and the truncation ~1e-8 of the derivative each)
            R, P = self._row_coefficients_direct(cond, i, omega)
            delta = 1e-6 * float(self.colscale[-1])
            Rp, _ = self._row_coefficients_direct(cond, i, omega + delta)
            Rm, _ = self._row_coefficients_direct(cond, i, omega - delta)
            dR, dP = (Rp - Rm) / (2 * delta), np.zeros(self.n_poles)
        H1, n_c = self.H + 1, self.n_c
        n_a = H1 * n_c
        scale = self.colscale
        G = np.zeros((H1, n_a + self.n_poles))
        dG = np.zeros_like(G)
        blocks = G[:, :n_a].reshape(H1, H1, n_c)  # (k, k', c): nonzero for k' = k only
        dblocks = dG[:, :n_a].reshape(H1, H1, n_c)
        diag = np.arange(H1)
        xscale = scale[:n_a].reshape(H1, n_c)
        blocks[diag, diag] = R * xscale
        dblocks[diag, diag] = dR * xscale * scale[-1]
        if self.n_poles:
            p = np.arange(self.n_poles)
            G[self._pole_k, n_a + p] = P * self.eta_scale
            dG[self._pole_k, n_a + p] = dP * self.eta_scale * scale[-1]
        G.flags.writeable = dG.flags.writeable = False
        if len(kept[2]) >= _ROW_DERIVATIVES_KEPT:
            kept[2].clear()
        kept[2][omega] = (G, dG)
        return G, dG

    def _row_coefficients_modal(self, cond, i: int, omega: float):
        """(R, ∂R/∂Ω, P, ∂P/∂Ω) of the modal condensation's amplitude row at Ω:
        row_k = Σ_c R_kc a_kc + Σ_{p: k_p = k} P_p η_p (:meth:`_amplitude_row_modal`'s
        terms, x_k = (kΩ)², c_kj = x_k/(ω_j² (ω_j² − x_k)), ∂c_kj/∂x_k = 1/(ω_j² − x_k)²)."""
        H = self.H
        pairs = self.pole_set.pairs if self.n_poles else []
        key = (H, omega, tuple(pairs))
        last = cond._recovery_factors
        if last is not None and last[0] == key:
            x, c = last[1]
        else:
            x, c = cond._recovery_coefficients(H, omega, key[2])
            cond._recovery_factors = ((H, omega, tuple(map(tuple, pairs))), (x, c))
        cols = np.concatenate([[0], np.arange(1, 2 * H, 2)])  # the cosine column of each harmonic
        x, c = x[cols], c[cols]
        k = np.arange(H + 1)
        dx = 2.0 * k**2 * omega  # ∂x_k/∂Ω
        # ∂c/∂x = (c ω_j²/x)² where kept (c = 0 where a pole term is left out, and at k = 0)
        inv = np.divide(c * cond._w2[None, :], x[:, None], out=np.zeros_like(c), where=x[:, None] > 0)
        dc = inv**2 * dx[:, None]
        cond._static_recovery()
        phi_i = cond.phi_j[i]
        R = cond._Z0[i][None, :] + (c * phi_i) @ cond.b_j
        dR = (dc * phi_i) @ cond.b_j
        if not cond.complete:
            for n in range(1, KRYLOV_BLOCKS):
                V = cond._V[n][i][None, :]
                R = R + x[:, None] ** n * V
                dR = dR + (n * x[:, None] ** (n - 1) * dx[:, None]) * V
        P = dP = np.zeros(self.n_poles)
        if self.n_poles:  # −φ_j η_jk (kΩ)²/ω_j², the pole set's recovery
            phi_row = self.pole_set.phi[i]
            j = np.array([jj for _, jj in pairs], dtype=np.int64)
            kp = self._pole_k
            P = -phi_row[j] * (kp * omega) ** 2 / self._pole_w2
            dP = -phi_row[j] * 2.0 * kp**2 * omega / self._pole_w2
        return -R, -dR, P, dP

    def _row_coefficients_direct(self, cond, i: int, omega: float):
        """(R (H+1, n_c), P (n_p,)) of a direct back end's amplitude row at Ω (the row of
        each Z_k that :meth:`_amplitude_row` applies to a_k; P_p the pole term of η_p)."""
        r = int(np.flatnonzero(cond.perm == i)[0])
        poles = self.pole_set if self.n_poles else None
        R = np.empty((self.H + 1, self.n_c))
        R[0] = -cond._Z0[r]
        for k in range(1, self.H + 1):
            Z = poles._z_regular(k, omega) if poles is not None else cond._solve(k * omega)
            R[k] = -Z[r]
        P = np.zeros(self.n_poles)
        if poles is not None:
            for p, (_, j) in enumerate(poles.pairs):
                P[p] = -poles.phi[r, j]
        return R, P

    def _amplitude_peak(self, u: np.ndarray):
        """(row, cos kτ* (H+1,), amplitude (m), s): the amplitude DOF's cosine coefficients,
        cos kτ at the time τ* of its largest excursion (fine grid, refined by Newton on
        q′(τ) = 0), the amplitude s·q(τ*) and the excursion's sign s."""
        if self._amp_in_c:
            a, omega = self.unpack(u)
            row = np.ascontiguousarray(a[:, self._amp_index])
        else:  # the row from the scaled unknowns (:meth:`_amplitude_row_derivatives`)
            G, _ = self._amplitude_row_derivatives(self._omega_of(u))
            row = G @ np.asarray(u, dtype=float)[:-1]
        cos_k = np.empty(self.H + 1)
        amplitude, s = _cosine_peak(row, self._amp_sign, cos_k)
        return row, cos_k, amplitude, s

    def _omega_of(self, u: np.ndarray) -> float:
        """Ω (rad/s) of the scaled unknowns (checked as :meth:`unpack` checks them)."""
        shape = u.shape if type(u) is np.ndarray else np.shape(u)
        if shape != (self.n_unknowns,):
            raise ValueError(f"u must have shape ({self.n_unknowns},), got {shape}")
        return float(u[-1] * self.colscale[-1])

    def amplitude_value(self, u: np.ndarray) -> float:
        """The amplitude (m) of :meth:`amplitude_and_gradient` without the gradient."""
        return float(self._amplitude_peak(u)[2])

    def amplitude_and_gradient(self, u: np.ndarray) -> tuple[float, np.ndarray]:
        """The amplitude (m) and its gradient with respect to the scaled unknowns.

        The amplitude is the largest value of a smooth periodic function over τ, so its
        derivative is that of the function at the maximiser (envelope theorem), located
        on the fine grid and refined by Newton on q′(τ) = 0: s cos kτ* applied to the
        row's derivatives (:meth:`_amplitude_row_derivatives`; Ω: the derivative of the
        row's coefficients applied to the unknowns).
        """
        row, cosk, amplitude, s = self._amplitude_peak(u)
        grad = np.zeros(self.n_unknowns)
        if self._amp_in_c:
            n_a = (self.H + 1) * self.n_c
            grad[self._amp_index:n_a:self.n_c] = s * cosk * self.colscale[self._amp_index:n_a:self.n_c]
            return float(amplitude), grad
        G, dG = self._amplitude_row_derivatives(self._omega_of(u))
        v = np.asarray(u, dtype=float)[:-1]
        sc = s * cosk
        grad[:-1] = sc @ G
        grad[-1] = sc @ (dG @ v)
        return float(amplitude), grad
