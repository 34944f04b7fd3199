"""Baseline: forced responses with friction by penalty harmonic balance (Jenkins elements by
AFT), as general harmonic-balance tools compute them.

Every DOF carries the full cosine/sine series up to H, the linear part assembled as in
:class:`~mmshbm.methods.penalty.forced.PenaltyForcedProblem` (L(Ω) = L_K + Ω L_C + Ω² L_M),
and each friction contact is a Jenkins element: a tangential spring k_t in series with a
Coulomb slider of slip force s = μN, evaluated by alternating frequency-time on N samples
per period with the hysteresis made periodic by two passes
(:func:`mmshbm.contact.coulomb.jenkins_hysteresis`, exact derivative):

    L(Ω) Q − σ(Ω) F + Σ_t e_t ⊗ proj[f_t(u_t)] = 0,      f_t = Jenkins(u_t; k_t, s_t),

f_t the force the element exerts on its support (the structure receives −f_t), as in
:mod:`mmshbm.contact.coulomb`. Two uses:

* ``tangential_stiffness=k``: the spring is a penalty on a rigid Coulomb contact at the
  friction DOF; the law is regularised and the orbit tends to the rigid contact's as
  k_t → ∞, with an error of order ρ/k_t (ρ = 1/(K⁻¹)_tt the static stiffness at the
  friction DOF; plus the sampling error of the switch instants, O(1/N)).
* ``tangential_stiffness="physical"``: the friction DOF is a massless node joined by one
  spring k to one other DOF (a Jenkins element of the model itself, as
  ``Model.with_friction(..., tangential_stiffness=k)`` builds it): the node is removed and
  the Jenkins element (k, s) acts on that DOF. The law is then the model's own, and the
  only errors are the truncation to H and the AFT sampling.
* default (None): ``"physical"`` where every friction node is joined so; otherwise the
  penalty 10³ ρ at every friction DOF, with a :class:`~mmshbm.ModelWarning` saying which
  spring it adds (``tangential_origin`` records which).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ... import _validate as check
from ...contact.coulomb import jenkins_hysteresis
from ...core.measures import refined_max
from ...harmonic.harmonics import check_harmonics
from ...model.model import Model
from ..mms.damped import fine_samples
from ..mms.forced import Excitation, harmonic_force
from ..mms.friction_rows import check_friction_model
from .forced import PenaltyForcedProblem

__all__ = ["JenkinsForcedProblem", "DEFAULT_TANGENTIAL_FACTOR"]

#: default tangential stiffness in units of the friction DOF's static stiffness ρ
DEFAULT_TANGENTIAL_FACTOR = 1e3


def _physical(model: Model, dof: int) -> tuple[int, float]:
    """(the DOF the massless friction node ``dof`` is joined to, the spring k) when the
    node's stiffness row is k (e_dof − e_j); ValueError otherwise."""
    row = np.asarray(model.K[dof].toarray()).ravel() if sp.issparse(model.K) else np.asarray(model.K[dof])
    others = np.flatnonzero(row)
    others = others[others != dof]
    k = row[dof]
    if len(others) != 1 or not np.isclose(row[others[0]], -k, rtol=1e-12, atol=0) or k <= 0:
        raise ValueError(f'tangential_stiffness="physical" needs the friction DOF {dof} joined by a single '
                         f"spring to one other DOF (its stiffness row k (e_{dof} − e_j)); it is not")
    return int(others[0]), float(k)


def _all_physical(model: Model) -> bool:
    """True when every friction DOF is a massless node joined by one spring to one DOF."""
    try:
        for fc in model.friction:
            _physical(model, fc.dof)
    except ValueError:
        return False
    return True


def _warn_penalty(dofs, kt) -> None:
    import warnings

    from ..._warnings import ModelWarning

    springs = ", ".join(f"{k:.4g} N/m at DOF {d}" for d, k in zip(dofs, kt, strict=True))
    warnings.warn(f'method="penalty" adds a tangential penalty spring in series with each friction contact '
                  f"({springs}: {DEFAULT_TANGENTIAL_FACTOR:g} times the static stiffness there), as the "
                  "model has no spring of its own joining a massless slider: the orbit tends to rigid "
                  "Coulomb's as the spring stiffens (error ~ 1e-3); pass tangential_stiffness=k_t to "
                  "choose it",
                  ModelWarning, stacklevel=4)


class JenkinsForcedProblem(PenaltyForcedProblem):
    """Penalty HBM with Jenkins elements by AFT, forced, as a continuation problem in (Q, Ω).

    Parameters
    ----------
    model : Model
        A model with friction contacts of constant normal load and no unilateral contact.
    force : Excitation or array_like (n_dof,)
    harmonics : int
        H >= 1.
    tangential_stiffness : float or "physical", optional
        k_t (N/m) of every Jenkins element; "physical": the model's own spring joining each
        massless friction node to one DOF; default "physical" where the model has those
        springs, else 10³ ρ with a ModelWarning (module docstring).
    n_samples : int, optional
        AFT samples per period N (default 2^⌈log2(8(2H+1))⌉; the switches are located to
        one sample, so the error of a stick-slip orbit falls as 1/N).
    stability : bool
        Not available for this baseline (False).
    """

    method = "penalty"
    setting_names = ("H", "N")

    def __init__(self, model: Model, force, harmonics: int = 5, tangential_stiffness=None,
                 n_samples: int | None = None, stability: bool = False):
        # impact with friction (normal_contact=) would need the normal contact as a penalty
        # too, its sampled force feeding the Jenkins return map's slip force per sample: not built
        check_friction_model(model, who="the Jenkins baseline (method=\"penalty\")")
        if model.contacts:
            raise NotImplementedError("the Jenkins baseline takes friction contacts alone "
                                      "(no unilateral contact)")
        if stability:
            raise NotImplementedError("Floquet multipliers are not available for the Jenkins baseline")
        exc = force if isinstance(force, Excitation) else harmonic_force(model, force)
        self.model = model
        self.excitation = exc
        H = check.integer("harmonics", harmonics, minimum=1)
        if n_samples is None:
            n_samples = max(64, 2 ** int(np.ceil(np.log2(8 * (2 * H + 1)))))
        self.H, self.N = check_harmonics(H, n_samples)
        K = model.K.tocsr().astype(float)
        M = model.M.tocsr().astype(float)
        C = model.damping.tocsr() if model.damping is not None else sp.csr_matrix(K.shape)
        keep = np.arange(model.n_dof)
        force_vec = np.asarray(exc.vector)
        slip = np.array([fc.slip_force for fc in model.friction])
        if tangential_stiffness is None:
            tangential_stiffness = "physical" if _all_physical(model) else None
        self.tangential_origin = ("physical" if isinstance(tangential_stiffness, str)
                                  else "default penalty" if tangential_stiffness is None else "given")
        if isinstance(tangential_stiffness, str):
            if tangential_stiffness != "physical":
                raise ValueError(f'tangential_stiffness must be a stiffness (N/m) or "physical", '
                                 f"got {tangential_stiffness!r}")
            joined = [_physical(model, fc.dof) for fc in model.friction]
            removed = [fc.dof for fc in model.friction]
            keep = np.setdiff1d(keep, removed)
            K = K.tolil()
            for j, k in joined:
                K[j, j] -= k  # the spring becomes the Jenkins element's
            K = K.tocsr()
            dofs = np.searchsorted(keep, [j for j, _ in joined])
            kt = np.array([k for _, k in joined])
            rho = kt
        else:
            dofs = np.array([fc.dof for fc in model.friction])
            flex = np.linalg.solve(model.K.toarray(), np.eye(model.n_dof)[:, dofs])[dofs]
            rho = 1.0 / np.diag(flex)
            if tangential_stiffness is None:
                kt = DEFAULT_TANGENTIAL_FACTOR * rho
                _warn_penalty(dofs, kt)
            else:
                kt = np.full(len(dofs), check.positive("tangential_stiffness", tangential_stiffness))
        K, M, C = (A[keep][:, keep].tocsr() for A in (K, M, C))
        self.keep, self.dofs, self.tangential_stiffness, self.slip_force = keep, dofs, kt, slip
        self._rho = np.asarray(rho, dtype=float)
        n = len(keep)
        self.n = n
        self.n_coef = 2 * self.H + 1
        self.stability = False
        blocks_K, blocks_C, blocks_M = [K], [sp.csr_matrix((n, n))], [sp.csr_matrix((n, n))]
        for k in range(1, self.H + 1):
            blocks_K.append(sp.block_diag([K, K]))
            zero = sp.csr_matrix((2 * n, 2 * n))
            blocks_C.append(sp.bmat([[None, k * C], [-k * C, None]]) if C.nnz else zero)
            blocks_M.append(sp.block_diag([-(k * k) * M, -(k * k) * M]))
        self._LK = sp.block_diag(blocks_K, format="csr")
        self._LC = sp.block_diag(blocks_C, format="csr")
        self._LM = sp.block_diag(blocks_M, format="csr")
        self._idx = [np.arange(self.n_coef) * n + d for d in dofs]
        self._Fvec = np.zeros(n * self.n_coef)
        self._Fvec[n:2 * n] = force_vec[keep].real
        self._Fvec[2 * n:3 * n] = -force_vec[keep].imag
        # AFT matrices: samples = Φ coefficients, coefficients = P samples (NLvib order)
        tau = 2 * np.pi * np.arange(self.N) / self.N
        k = np.arange(1, self.H + 1)
        self._Phi = np.empty((self.N, self.n_coef))
        self._Phi[:, 0] = 1.0
        self._Phi[:, 1::2] = np.cos(np.outer(tau, k))
        self._Phi[:, 2::2] = np.sin(np.outer(tau, k))
        self._P = self._Phi.T * np.r_[1.0, np.full(2 * self.H, 2.0)][:, None] / self.N
        # scales: the first mode of the free-slip structure and its static response to the force
        self.amplitude_dof = int(np.searchsorted(keep, model.amplitude_dof))
        self.omega_ref, phi = self._reference(M, K, C)
        import scipy.sparse.linalg as spla

        stat = spla.spsolve(K.tocsc(), np.abs(force_vec[keep])) if n > 1 else \
            np.abs(force_vec[keep]) / K.toarray()[0]
        length = float(np.max(np.abs(stat))) or 1.0
        phi = phi / abs(phi[self.amplitude_dof]) if phi[self.amplitude_dof] != 0 else phi / np.abs(phi).max()
        self.xscale = np.tile(length * np.maximum(np.abs(phi), 1e-3 * np.abs(phi).max()), self.n_coef)
        energy = float(np.min(kt)) * length ** 2
        self.rowscale = energy / self.xscale
        self.colscale = np.concatenate([self.xscale, [self.omega_ref]])
        self.n_unknowns = n * self.n_coef + 1
        self._n_fine = max(512, 2 ** int(np.ceil(np.log2(16 * self.n_coef))))

    def _reference(self, M, K, C):
        """(ω of the first mode, its shape (n,)) of the structure with the Jenkins springs stuck
        (K + Σ k_t e eᵀ), the massless DOFs condensed statically."""
        Kst = K.toarray().copy()
        for d, k in zip(self.dofs, self.tangential_stiffness, strict=True):
            Kst[d, d] += k
        Md = M.toarray()
        heavy = np.flatnonzero(Md.diagonal() > 0)
        light = np.setdiff1d(np.arange(len(Md)), heavy)
        Kr = Kst[np.ix_(heavy, heavy)]
        if len(light):
            Kll = Kst[np.ix_(light, light)]
            Kr = Kr - Kst[np.ix_(heavy, light)] @ np.linalg.solve(Kll, Kst[np.ix_(light, heavy)])
        from scipy.linalg import eigh

        w2, v = eigh(Kr, Md[np.ix_(heavy, heavy)], subset_by_index=[0, 0])
        phi = np.zeros(len(Md))
        phi[heavy] = v[:, 0]
        if len(light):
            phi[light] = -np.linalg.solve(Kst[np.ix_(light, light)], Kst[np.ix_(light, heavy)] @ v[:, 0])
        return float(np.sqrt(w2[0])), phi

    # ------------------------------------------------------------------ residual
    def _evaluate(self, u, jacobian: bool):
        """Scaled residual (n(2H+1),) and, if asked, its sparse Jacobian (CSR)."""
        Q, omega = self.unpack(u)
        s, ds = self.excitation.scale(omega)
        L = self._LK + omega * self._LC + omega**2 * self._LM
        R = L @ Q - s * self._Fvec
        rows, cols, vals = [], [], []
        for j, idx in enumerate(self._idx):
            f, df = jenkins_hysteresis(self._Phi @ Q[idx], self.slip_force[j], self.tangential_stiffness[j],
                                       self._Phi)
            R[idx] += self._P @ f
            if jacobian:
                rr, cc = np.meshgrid(idx, idx, indexing="ij")
                rows.append(rr.ravel())
                cols.append(cc.ravel())
                vals.append((self._P @ df).ravel())
        R = R / self.rowscale
        if not jacobian:
            return R
        dR_domega = (self._LC + 2 * omega * self._LM) @ Q - ds * self._Fvec
        ij = (np.concatenate(rows), np.concatenate(cols))
        fric = sp.coo_matrix((np.concatenate(vals), ij), shape=L.shape)
        Jx = sp.diags(1.0 / self.rowscale) @ (L + fric).tocsr() @ sp.diags(self.xscale)
        col = sp.csr_matrix((dR_domega * self.omega_ref / self.rowscale)[:, None])
        return R, sp.hstack([Jx, col], format="csr")

    def start_point(self, frequency: float, max_iter: int = 60, tol: float = 1e-10) -> np.ndarray:
        """Converged scaled unknowns at ``frequency`` (Hz): Newton with a backtracking line
        search on max|R| from the linear response of the free-slip structure, the tangential
        stiffness raised from at most 10 ρ to k_t by factors of 10, each stage started from
        the last (a stiff Jenkins spring from the free-slip guess does not converge); the
        linear response when a stage does not converge."""
        u0 = self.linear_response_point(frequency)
        target = self.tangential_stiffness.copy()
        k0 = np.minimum(target, 10.0 * self._rho)
        stages = int(np.ceil(np.max(np.log10(target / k0)))) if np.any(target > k0) else 0
        u = u0
        try:
            for i in range(stages + 1):
                self.tangential_stiffness = np.minimum(target, k0 * 10.0 ** i)
                u, ok = self.solve_at(frequency, u, max_iter, tol)
                if not ok:
                    return u0
        finally:
            self.tangential_stiffness = target
        return u

    def solve_at(self, frequency: float, guess: np.ndarray, max_iter: int = 60, tol: float = 1e-10):
        """Newton at fixed Ω from the scaled ``guess`` with a backtracking line search on
        max|R|: (scaled unknowns, converged)."""
        import scipy.sparse.linalg as spla

        u = np.array(guess, dtype=float)
        u[-1] = 2 * np.pi * frequency / self.omega_ref
        r = float(np.abs(self.residual(u)).max())
        for _ in range(max_iter):
            if r < tol:
                return u, True
            R, J = self.residual_and_jacobian(u)
            du = np.zeros_like(u)
            du[:-1] = spla.spsolve(J[:, :-1].tocsc(), -R)
            lam = 1.0
            while True:
                r_new = float(np.abs(self.residual(u + lam * du)).max())
                if r_new < (1 - 1e-4 * lam) * r:
                    u, r = u + lam * du, r_new
                    break
                lam *= 0.5
                if lam < 2.0 ** -20:
                    return u, False
        return u, r < tol

    # ------------------------------------------------------------------ results
    def coefficients(self, u) -> np.ndarray:
        """NLvib-ordered coefficients (n_dof, 2H+1) of every DOF of the model (a node removed
        by ``"physical"`` recovered statically: sticking or sliding, it carries the spring
        force, u_t = u_j − f/k)."""
        Q, _ = self.unpack(u)
        Qk = Q.reshape(self.n_coef, self.n).T
        if len(self.keep) == self.model.n_dof:
            return Qk
        out = np.zeros((self.model.n_dof, self.n_coef))
        out[self.keep] = Qk
        for fc, d, k in zip(self.model.friction, self.dofs, self.tangential_stiffness, strict=True):
            f, _ = jenkins_hysteresis(self._Phi @ Qk[d], fc.slip_force, k)
            out[fc.dof] = Qk[d] - self._P @ f / k
        return out

    def monitor(self, u) -> dict:
        """frequency (Hz), amplitude (m), phase (rad), energy (J, nan), contact_force_max (0),
        friction_dissipation (J per period, Σ ∮ f u̇ of the sampled hysteresis)."""
        Q, omega = self.unpack(u)
        q = Q.reshape(self.n_coef, self.n).T[self.amplitude_dof]
        samples = fine_samples(q, self._n_fine)
        q1 = q[1] - 1j * q[2]
        lag = np.angle(self.excitation.reference) - np.angle(q1)
        work = 0.0
        for j, idx in enumerate(self._idx):
            us = self._Phi @ Q[idx]
            f, _ = jenkins_hysteresis(us, self.slip_force[j], self.tangential_stiffness[j])
            work += float(np.sum(0.5 * (f + np.roll(f, 1)) * (us - np.roll(us, 1))))
        amplitude = max(refined_max(samples), refined_max(-samples))
        return {"frequency": omega / (2 * np.pi), "amplitude": amplitude,
                "phase": float((lag + 0.5 * np.pi) % (2 * np.pi) - 0.5 * np.pi), "energy": np.nan,
                "contact_force_max": 0.0, "friction_dissipation": work}
