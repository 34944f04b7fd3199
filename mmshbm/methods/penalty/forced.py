"""Baseline: forced responses by classical harmonic balance with penalty contact.

Every DOF of the finite-element model carries the full cosine and sine series up to H
(NLvib order, n-blocks: Q = [Q_0; Q_c1; Q_s1; ...]); per harmonic k ≥ 1 the linear part
is

    [K − (kΩ)²M     kΩ C      ] [Q_ck]   [F_c δ_k1]
    [  −kΩ C     K − (kΩ)²M   ] [Q_sk] − [F_s δ_k1] σ(Ω) + proj_k(f_p) = 0

(F̂ = F_c − i F_s the excitation, σ(Ω) as in :class:`~mmshbm.methods.mms.forced.Excitation`),
and each stop is a penalty spring: with the DOF's admissible interval [lo, hi],
f_p = k_p [(q − hi)₊ − (lo − q)₊], projected with the projection of MMS-HBM
(:func:`mmshbm.contact.unilateral.project_contact`: by default exact, the switching instants
located and the pieces integrated in closed form, so the residual is C¹; or sampled AFT).
The sampled projection is kinked wherever a sample changes state, and with k_p = 10³ k_c
each kink is a jump of k_p/N in the Jacobian: on the default beam (0.5 %, 2.3 N, H = 5)
semismooth Newton cycles between two active sets with a sample 2e-10 gaps from the stop
(residual 1.1e-10 ↔ 1.2e-9 against the tolerance 1e-10) and the response stops at
57.1 Hz (`ds_min`); the exact projection runs 40–60 Hz through. The Jacobian is sparse:
L(Ω) = L_K + Ω L_C + Ω² L_M is assembled once per Ω from three constant block matrices,
plus k_p G in the contact DOFs' rows and columns.
k_p defaults to 10³ times the contact DOF's condensed static stiffness; the error this
leaves is of order k_c/k_p (docs/penalty.md). This is how general harmonic-balance tools
(NLvib, pyHarm) compute forced responses with contact.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ... import _validate as check
from ...contact.unilateral import contact_projection
from ...core.measures import check_dof, harmonic_content, mean_energy, refined_max
from ...core.problem import ForcedProblemBase, OneEvaluation
from ...harmonic.harmonics import check_harmonics
from ...model.contact import admissible_intervals
from ...model.model import Model
from ..mms.damped import fine_samples
from ..mms.forced import Excitation, harmonic_force

__all__ = ["PenaltyForcedProblem", "DEFAULT_PENALTY_FACTOR"]

#: default penalty stiffness in units of the contact DOF's condensed static stiffness
DEFAULT_PENALTY_FACTOR = 1e3


class PenaltyForcedProblem(OneEvaluation, ForcedProblemBase):
    """Penalty harmonic balance on all DOFs, forced, as a continuation problem in (Q, Ω).

    Parameters
    ----------
    model : Model
        Any model with contacts (contact DOFs with or without mass).
    force : Excitation or array_like (n_dof,)
    harmonics : int
        H >= 1.
    penalty_stiffness : float, optional
        k_p (N/m); default 10³ k_c.
    n_samples : int, optional
        Samples of the sampled projection (the exact one's bracketing grid).
    projection : {"exact", "sampled"}
        Exact (default, as MMS-HBM's forced response: C¹ residual) or sampled AFT (as the
        conservative penalty-HBM; its kinks stall the default beam's response at 57.1 Hz).
    stability : bool
        Not available for this baseline (False; the monitor records no multipliers).
    """

    method = "penalty"
    setting_names = ("H", "N", "penalty_stiffness")

    def __init__(self, model: Model, force, harmonics: int = 5, penalty_stiffness: float | None = None,
                 n_samples: int | None = None, projection: str = "exact", stability: bool = False):
        if not isinstance(model, Model):
            raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
        self.model = model
        exc = force if isinstance(force, Excitation) else harmonic_force(model, force)
        if isinstance(force, Excitation):
            harmonic_force(model, force.vector)
        self.excitation = exc
        self.H, self.N = check_harmonics(harmonics, n_samples)
        H, n = self.H, model.n_dof
        self.n = n
        self.n_coef = 2 * H + 1
        dofs, self.lo, self.hi = admissible_intervals(model.contacts)
        self.dofs = dofs
        # k_c of each contact DOF: the static stiffness it sees, 1/(K⁻¹)_dd
        Kd = model.K.toarray() if n <= 2000 else None
        if Kd is not None:
            flex = np.linalg.solve(Kd, np.eye(n)[:, dofs])[dofs]
        else:  # pragma: no cover - large models
            import scipy.sparse.linalg as spla
            flex = spla.splu(model.K.tocsc()).solve(np.eye(n)[:, dofs])[dofs]
        self.contact_stiffness = 1.0 / np.diag(flex)
        if penalty_stiffness is None:
            self.penalty_stiffness = DEFAULT_PENALTY_FACTOR * self.contact_stiffness
        else:
            kp = check.positive("penalty_stiffness", penalty_stiffness)
            self.penalty_stiffness = np.full(len(dofs), kp)
        self._project = contact_projection(projection, H, self.N)
        self.stability = False
        # constant block matrices: L(Ω) = L_K + Ω L_C + Ω² L_M
        K, M = model.K.tocsr(), model.M.tocsr()
        C = model.damping.tocsr() if model.damping is not None else sp.csr_matrix((n, n))
        blocks_K, blocks_C, blocks_M = [K], [sp.csr_matrix((n, n))], [sp.csr_matrix((n, n))]
        for k in range(1, H + 1):
            blocks_K.append(sp.block_diag([K, K]))
            zero = sp.csr_matrix((2 * n, 2 * n))
            blocks_C.append(sp.bmat([[None, k * C], [-k * C, None]]) if C.nnz else zero)
            blocks_M.append(sp.block_diag([-(k * k) * M, -(k * k) * M]))
        self._LK = sp.block_diag(blocks_K, format="csr")
        self._LC = sp.block_diag(blocks_C, format="csr")
        self._LM = sp.block_diag(blocks_M, format="csr")
        pattern = (abs(self._LK) + abs(self._LC) + abs(self._LM)).tocsr()
        self._pattern = pattern
        self._idx = [np.arange(self.n_coef) * n + d for d in dofs]
        # the forcing vector (first harmonic)
        self._Fvec = np.zeros(n * self.n_coef)
        self._Fvec[n:2 * n] = exc.vector.real
        self._Fvec[2 * n:3 * n] = -exc.vector.imag
        # scales: the first mode, as for MMS-HBM (ρ makes the arclength comparable)
        freqs, modes = model.linear_modes(1)
        self.omega_ref = 2 * np.pi * float(freqs[0])
        phi = modes[:, 0]
        self.amplitude_dof = model.amplitude_dof
        phi = phi / abs(phi[self.amplitude_dof])
        length = model.gap if model.gap > 0 else 1.0
        s = length * np.maximum(np.abs(phi), 1e-3 * np.abs(phi).max())
        c = model.c if len(model.c) else np.asarray(dofs)
        rho = np.linalg.norm(phi / s) / np.linalg.norm(phi[c] / s[c])
        self.xscale = np.tile(s * rho, self.n_coef)
        # rows: work-conjugate to the columns, rowscale_i · xscale_i = k_c·gap² (one energy), so
        # the scaled Jacobian is diag(xscale) J diag(xscale)/E (symmetric scaling) and a unit of
        # residual is k_c·gap in a contact or forced translation row, as MMS-HBM's r·gap. (|K| s
        # was ~10⁶ larger on the default beam, the FE stiffness cancelling on a smooth shape:
        # the tolerance 1e-10 then allowed 2e-3 of the 2.3 N force and points within 1.2e-3 of
        # their amplitude; now 1e-9.)
        energy = float(np.min(self.contact_stiffness)) * length ** 2
        self.rowscale = energy / self.xscale
        self.colscale = np.concatenate([self.xscale, [self.omega_ref]])
        self.n_unknowns = n * self.n_coef + 1
        self._n_fine = max(512, 2 ** int(np.ceil(np.log2(16 * self.n_coef))))

    # ------------------------------------------------------------------ unknowns
    def unpack(self, u):
        y = np.asarray(u, dtype=float) * self.colscale
        return y[:-1], float(y[-1])

    def pack(self, Q, omega):
        return np.concatenate([np.asarray(Q, dtype=float), [omega]]) / self.colscale

    def linear_response_point(self, frequency: float) -> np.ndarray:
        """The linear response (stops ignored) at ``frequency`` (Hz), scaled."""
        omega = 2 * np.pi * check.positive("frequency", frequency)
        n = self.n
        s, _ = self.excitation.scale(omega)
        L1 = (self._LK + omega * self._LC + omega**2 * self._LM)[n:3 * n, n:3 * n]
        import scipy.sparse.linalg as spla

        Q = np.zeros(n * self.n_coef)
        Q[n:3 * n] = spla.spsolve(L1.tocsc(), s * self._Fvec[n:3 * n])
        return self.pack(Q, omega)

    def start_point(self, frequency: float, max_iter: int = 20, tol: float = 1e-8) -> np.ndarray:
        """Scaled unknowns of a response at ``frequency`` (Hz) converged to the scaled
        residual ``tol`` (the continuation's first corrector converges it further): the
        linear response when it stays off the stops, otherwise continued from a force level
        that does (σ from where the linear response reaches half the nearest clearance up
        to 1 in steps, a secant predictor in σ, Newton at fixed Ω, the step halved on
        failure), as MMS-HBM's forced start. Falls back to the linear response (the
        continuation's first corrector then tries).

        From the linear response itself Newton fails where that response passes a stop
        (on the default beam, 0.5 %, 2.3 N: 1.36 gaps at 44 Hz, at any H and N)."""
        import scipy.sparse.linalg as spla

        u_lin = self.linear_response_point(frequency)
        Q_lin, omega = self.unpack(u_lin)
        n = self.n
        peak = np.abs(Q_lin[n:2 * n]) + np.abs(Q_lin[2 * n:3 * n])
        room = np.minimum(self.hi, -self.lo)  # distance from rest to the nearest stop of each DOF
        ratio = float(np.max(peak[self.dofs] / np.maximum(room, 1e-300)))
        if not np.isfinite(ratio) or ratio < 0.9:
            return u_lin
        sigma = step = 0.5 / ratio
        Q = Q_lin * sigma
        slope = Q_lin  # dQ/dσ: the linear response while the stops are open, then the secant
        for _ in range(200):
            target = min(1.0, sigma + step)
            y = Q + (target - sigma) * slope
            ok = False
            for _ in range(max_iter):
                R, Jx = self._residual_parts(y, omega, target, True)
                R = R / self.rowscale
                if not np.all(np.isfinite(R)):
                    break
                if np.abs(R).max() < tol:
                    ok = True
                    break
                try:
                    y = y - self.xscale * spla.spsolve(Jx.tocsc(), R)
                except (RuntimeError, ValueError):
                    break
            if ok:
                slope = (y - Q) / (target - sigma)
                Q, sigma = y, target
                if sigma >= 1.0:
                    return self.pack(Q, omega)
                step *= 1.5
            else:
                step *= 0.5
                if step < 1e-6:
                    break
        return u_lin

    def initial_tangent(self):
        t = np.zeros(self.n_unknowns)
        t[-1] = 1.0
        return t

    # ------------------------------------------------------------------ residual

    def _residual_parts(self, Q: np.ndarray, omega: float, sigma: float, jacobian: bool):
        """Unscaled residual R (n(2H+1),) of the force scaled by σ and, if asked, the
        scaled ∂R/∂Q (rows by 1/rowscale, columns by xscale; sparse CSR), else None."""
        s, _ = self.excitation.scale(omega)
        L = self._LK + omega * self._LC + omega**2 * self._LM
        R = L @ Q - (sigma * s) * self._Fvec
        rows, cols, vals = [], [], []
        for j, idx in enumerate(self._idx):
            kp = self.penalty_stiffness[j]
            phi, G = self._project(Q[idx], self.lo[j], self.hi[j])
            R[idx] += kp * phi
            if jacobian:
                rr, cc = np.meshgrid(idx, idx, indexing="ij")
                rows.append(rr.ravel())
                cols.append(cc.ravel())
                vals.append((kp * G).ravel())
        if not jacobian:
            return R, None
        contact = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                                shape=L.shape) if vals else sp.csr_matrix(L.shape)
        Jx = (L + contact).tocsr()
        return R, sp.diags(1.0 / self.rowscale) @ Jx @ sp.diags(self.xscale)

    def _evaluate(self, u, jacobian: bool):
        """Scaled residual (n(2H+1),) and, if asked, its sparse Jacobian (CSR)."""
        Q, omega = self.unpack(u)
        R, Jx = self._residual_parts(Q, omega, 1.0, jacobian)
        R = R / self.rowscale
        if not jacobian:
            return R
        _, ds = self.excitation.scale(omega)
        dR_domega = (self._LC + 2 * omega * self._LM) @ Q - ds * self._Fvec
        col = sp.csr_matrix((dR_domega * self.omega_ref / self.rowscale)[:, None])
        J = sp.hstack([Jx, col], format="csr")
        return R, J

    # ------------------------------------------------------------------ results
    def coefficients(self, u) -> np.ndarray:
        """NLvib-ordered coefficients of all DOFs, (n_dof, 2H+1)."""
        Q, _ = self.unpack(u)
        return Q.reshape(self.n_coef, self.n).T

    def time_signals(self, u, dofs=None, n_samples: int = 256):
        Q = self.coefficients(u)
        _, omega = self.unpack(u)
        if dofs is not None:
            Q = Q[np.atleast_1d(dofs)]
        q = fine_samples(Q, check.integer("n_samples", n_samples, minimum=2 * self.H + 1))
        return 2 * np.pi * np.arange(n_samples) / n_samples / omega, q

    def contact_force(self, u, n_samples: int = 256):
        """(t, λ (n_contacts, n_samples)): the penalty forces of the stops (N)."""
        t, q = self.time_signals(u, self.dofs, n_samples)
        out = []
        for ct in self.model.contacts:
            i = int(np.flatnonzero(self.dofs == ct.dof)[0])
            kp = self.penalty_stiffness[i]
            out.append(kp * np.maximum(0.0, ct.side * q[i] - ct.gap))
        return t, np.array(out)

    def harmonic_content(self, u, dof=None):
        """|Q_k|, k = 0..H, of ``dof`` (default the amplitude DOF); shape (H+1,)."""
        dof = check_dof(dof, self.model.n_dof, self.amplitude_dof)
        return harmonic_content(self.coefficients(u)[dof])

    def monitor(self, u) -> dict:
        """frequency (Hz), amplitude (m), phase (rad), energy (J), contact_force_max (N)."""
        Qall = self.coefficients(u)
        _, omega = self.unpack(u)
        q = Qall[self.amplitude_dof]
        samples = fine_samples(q, self._n_fine)
        q1 = q[1] - 1j * q[2]
        lag = np.angle(self.excitation.reference) - np.angle(q1)
        force = 0.0
        qc = fine_samples(Qall[self.dofs], self._n_fine)
        for j in range(len(self.dofs)):
            beyond = np.maximum(0, qc[j] - self.hi[j]) + np.maximum(0, self.lo[j] - qc[j])
            pen = self.penalty_stiffness[j] * beyond
            force = max(force, refined_max(pen) if pen.max() > 0 else 0.0)
        amplitude = max(refined_max(samples), refined_max(-samples))
        return {"frequency": omega / (2 * np.pi), "amplitude": amplitude,
                "phase": float((lag + 0.5 * np.pi) % (2 * np.pi) - 0.5 * np.pi),
                "energy": mean_energy(self.model, Qall, omega), "contact_force_max": force}
