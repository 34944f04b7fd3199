"""The signals of a shooting orbit: the discrete trajectory over a period (mirrored from
the integrated half), the massless DOFs and contact forces that follow statically, Hermite
resampling, harmonic content. A mixin of :class:`~mmshbm.methods.shooting.conservative.ShootingProblem`
(it uses the problem's ``unpack``, ``_integrate``, contact data and permutation).
"""

from __future__ import annotations

import numpy as np

from ... import _validate as check
from ...contact.lcp import lcp_solve
from ...core.measures import check_dof, harmonic_content, sample_coefficients

__all__ = ["ShootingSignals"]


class ShootingSignals:
    """Trajectory and signal methods of :class:`~mmshbm.methods.shooting.conservative.ShootingProblem`."""

    def trajectory(self, u: np.ndarray):
        """The discrete orbit over one period at the N step instants.

        Returns
        -------
        t : ndarray (N,), s
        q_l, v_l : ndarray (N, n_l), positions and velocities of the DOFs with mass
            (``model.l`` order)
        lam : ndarray (N,), contact force (N); (N, n_contacts) with several contacts
        """
        key = np.asarray(u, dtype=float).tobytes()
        if self._traj_cache is not None and self._traj_cache[0] == key:
            return self._traj_cache[1]
        x, omega = self.unpack(u)
        half = self.N // 2
        _, _, _, (Q, V, LAM) = self._integrate(x, omega, half, store=True)
        # the second half mirrors the first: q(T − t) = q(t), v(T − t) = −v(t)
        Qf = np.vstack([Q, Q[half - 1 : 0 : -1]])
        Vf = np.vstack([V, -V[half - 1 : 0 : -1]])
        lam = np.concatenate([LAM, LAM[half - 1 : 0 : -1]])
        inv = np.argsort(self.perm)
        T = 2 * np.pi / omega
        out = (T * np.arange(self.N) / self.N, Qf[:, inv], Vf[:, inv], lam)
        self._traj_cache = (key, out)
        return out

    def _massless(self, q_l: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(q_c (n_c, m), λ) from q_l (n_l, m) in ``model.l`` order; λ shape (m,) with one
        contact, (n_contacts, m) with several (the LCP at each column)."""
        ql = q_l[self.perm]
        if self.contacts.n == 1:
            lam = self.contact_stiffness * np.maximum(0.0, -(self.gap + self.a @ ql))
            return self._B @ ql + np.outer(self._e, lam), lam
        lam, _ = lcp_solve(self._G, self._gaps[:, None] + self._A @ ql)
        return self._B @ ql + self._E @ lam, lam

    def _resample(self, u: np.ndarray, n_samples: int):
        """(t (n_samples,), q_l (n_l, n_samples)) by cubic Hermite interpolation of the
        discrete orbit (positions and velocities at the steps)."""
        n_samples = check.integer("n_samples", n_samples, minimum=1)
        t_steps, Q, V, _ = self.trajectory(u)
        _, omega = self.unpack(u)
        T = 2 * np.pi / omega
        h = T / self.N
        t = T * np.arange(n_samples) / n_samples
        s = t / h
        k = np.minimum(np.floor(s).astype(int), self.N - 1)
        r = (s - k)[None, :]
        k1 = (k + 1) % self.N
        h00 = 2 * r**3 - 3 * r**2 + 1
        h10 = r**3 - 2 * r**2 + r
        h01 = -2 * r**3 + 3 * r**2
        h11 = r**3 - r**2
        q = h00 * Q[k].T + h10 * h * V[k].T + h01 * Q[k1].T + h11 * h * V[k1].T
        return t, q

    def time_signals(self, u: np.ndarray, dofs=None, n_samples: int = 256):
        """(t (n_samples,) in s, q (n_dofs, n_samples)) over one period for ``dofs``
        (all DOFs when None); massless DOFs follow statically from the DOFs with mass."""
        t, ql = self._resample(u, n_samples)
        qc, _ = self._massless(ql)
        q = np.empty((self.model.n_dof, len(t)))
        q[self.model.l] = ql
        q[self.model.c] = qc
        if dofs is not None:
            dofs = np.atleast_1d(np.asarray(dofs))
            if dofs.dtype.kind not in "iu" or np.any((dofs < -self.model.n_dof) | (dofs >= self.model.n_dof)):
                raise ValueError(f"dofs must be integer indices in [0, {self.model.n_dof - 1}], got {dofs}")
            q = q[dofs]
        return t, q

    def contact_force(self, u: np.ndarray, n_samples: int = 256):
        """(t (n_samples,) in s, λ in N) over one period; λ has shape (n_samples,) with one
        contact, (n_contacts, n_samples) with several."""
        t, ql = self._resample(u, n_samples)
        return t, self._massless(ql)[1]

    def harmonic_content(self, u: np.ndarray, dof: int | None = None,
                         harmonics: int | None = None) -> np.ndarray:
        """|Q_k| for k = 0..harmonics of ``dof`` (default the amplitude DOF), from the DFT of
        the N step samples over one period; shape (harmonics+1,). ``harmonics`` defaults
        to min(10, N/2 − 1)."""
        dof = check_dof(dof, self.model.n_dof, self.amplitude_dof)
        if harmonics is None:
            harmonics = min(10, self.N // 2 - 1)
        harmonics = check.integer("harmonics", harmonics, minimum=0)
        if harmonics > self.N // 2 - 1:
            raise ValueError(f"harmonics must be <= N/2 - 1 = {self.N // 2 - 1}, got {harmonics}")
        return harmonic_content(sample_coefficients(self._dof_at_steps(u, dof), harmonics))

    def _dof_at_steps(self, u: np.ndarray, dof: int) -> np.ndarray:
        _, Q, _, lam = self.trajectory(u)
        model = self.model
        if dof in set(model.l.tolist()):
            return Q[:, int(np.searchsorted(model.l, dof))]
        qc, _ = self._massless(Q.T)
        return qc[int(np.searchsorted(model.c, dof))]
