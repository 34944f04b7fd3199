"""What a penalty-HBM point gives beyond its residual: contact displacements and penalty
forces, the motion of every DOF, harmonic content and the per-point monitor (a mixin of
:class:`~mmshbm.methods.penalty.hbm.PenaltyHBMProblem`)."""

from __future__ import annotations

import numpy as np

from ...core.measures import amplitude_peak, check_dof, harmonic_content, mean_energy, refined_max

__all__ = ["PenaltySignalsMixin"]


class PenaltySignalsMixin:
    """Signals of a penalty-HBM point (needs the attributes of ``PenaltyHBMProblem``)."""

    # ------------------------------------------------------------------ results
    def _cosines(self, tau):
        if tau is None:
            return self._tau_fine, self._cos_fine
        tau = np.asarray(tau, dtype=float)
        return tau, np.cos(np.outer(np.arange(self.H + 1), tau))

    def contact_signals(self, u: np.ndarray, tau: np.ndarray | None = None):
        """Contact DOF displacements q(τ) (m) and penalty forces λ(τ) (N) on a grid.

        Returns (tau, q_contact, lam): ``tau`` (n_tau,) defaults to a fine grid over one
        period; with one contact ``q_contact`` and ``lam`` have shape (n_tau,), with
        several (n_contacts, n_tau) (one row per contact, in ``model.contacts`` order).
        """
        Q, _ = self.unpack(u)
        tau, C = self._cosines(tau)
        ct = self.contacts
        q = np.array([Q[:, d] @ C for d in ct.dof])
        pen = ct.side[:, None] * q - ct.gap[:, None]
        lam = self.penalty_stiffnesses[:, None] * np.maximum(0.0, pen)
        if ct.n == 1:
            return tau, q[0], lam[0]
        return tau, q, lam

    def coefficients(self, u: np.ndarray) -> np.ndarray:
        """NLvib-ordered coefficients of all DOFs, shape (n_dof, 2H+1) (sines are zero)."""
        Q, _ = self.unpack(u)
        out = np.zeros((self.n, 2 * self.H + 1))
        out[:, 0] = Q[0]
        out[:, 1::2] = Q[1:].T
        return out

    def time_signals(self, u: np.ndarray, dofs=None, n_samples: int = 256):
        """(t (n_samples,) in s, q (n_dofs, n_samples)) over one period for ``dofs``
        (all DOFs when None)."""
        Q, omega = self.unpack(u)
        if dofs is not None:
            dofs = np.atleast_1d(np.asarray(dofs))
            if dofs.dtype.kind not in "iu" or np.any((dofs < -self.n) | (dofs >= self.n)):
                raise ValueError(f"dofs must be integer indices in [0, {self.n - 1}], got {dofs}")
            Q = Q[:, dofs]
        tau = 2 * np.pi * np.arange(n_samples) / n_samples
        q = Q.T @ np.cos(np.outer(np.arange(self.H + 1), tau))
        return tau / omega, q

    def contact_force(self, u: np.ndarray, n_samples: int = 256):
        """(t (n_samples,) in s, λ in N) over one period; λ has shape (n_samples,) with one
        contact, (n_contacts, n_samples) with several."""
        _, omega = self.unpack(u)
        tau = 2 * np.pi * np.arange(n_samples) / n_samples
        _, _, lam = self.contact_signals(u, tau)
        return tau / omega, lam

    def harmonic_content(self, u: np.ndarray, dof: int | None = None) -> np.ndarray:
        """|Q_k| for k = 0..H of ``dof`` (default the amplitude DOF); shape (H+1,)."""
        dof = check_dof(dof, self.n, self.amplitude_dof)
        return harmonic_content(self.coefficients(u)[dof])

    def monitor(self, u: np.ndarray) -> dict:
        """The per-point quantities of a backbone: frequency (Hz), amplitude (m, at
        ``model.amplitude_dof``), energy (J, structure plus penalty springs, period
        averages), contact_force_max (N, the largest over all contacts); with several
        contacts also ``contact_force_max_<i>`` per contact i."""
        Q, omega = self.unpack(u)
        _, q, lam = self.contact_signals(u)
        ct = self.contacts
        q, lam = np.atleast_2d(q), np.atleast_2d(lam)
        penetration = ct.side[:, None] * q - ct.gap[:, None]
        spring = 0.5 * sum(float(kp * np.mean(np.maximum(0.0, pen) ** 2))
                           for kp, pen in zip(self.penalty_stiffnesses, penetration, strict=True))
        if self._amp_sign != 0 and ct.n == 1:
            q_amp = q[0]
        else:
            q_amp = Q[:, self.amplitude_dof] @ self._cos_fine
        peaks = [self.penalty_stiffnesses[i] * max(refined_max(penetration[i]), 0.0) for i in range(ct.n)]
        rec = {
            "frequency": omega / (2 * np.pi),
            "amplitude": amplitude_peak(q_amp, self._amp_sign),
            "energy": mean_energy(self.model, self.coefficients(u), omega) + spring,
            "contact_force_max": float(max(peaks)),
        }
        if ct.n > 1:
            rec.update({f"contact_force_max_{i}": float(v) for i, v in enumerate(peaks)})
        return rec
