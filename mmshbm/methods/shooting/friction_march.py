"""Impact with friction on several massless nodes: forced orbits by marching to steady state
(no Newton), the per-step law of :mod:`.friction_impact` compiled in modal coordinates.

The model: unilateral contacts k on massless DOFs, each with one friction contact on a
massless DOF coupled to it (``normal_contact=k``, slip force μ (preload + λ_k(t))), viscous
damping diagonal in the open structure's modes (modal ratios or Rayleigh damping). With Φ
the mass-normalised modes of (K_red, M_ll) (all n_l of them), q_l = Φ η, the interface
DOFs I (normal, tangential per contact) and their forces f (f_n = −side λ, f_t = g),

    η'' + 2 ζ ω η' + ω² η = Φᵀ F(t) − ψ f,      q_I = A_II f − ψᵀ η,      ψ = Φᵀ K_lc A[:, I],

A = K_cc⁻¹. Newmark's average acceleration per mode is the same scheme as the physical
coordinates' of :class:`~.friction_impact.ImpactFrictionShooting` (the scheme is invariant
under the change of coordinates: one node, the two march the same orbit to round-off), at
O(n_l + n_l m) per step instead of a dense solve. Each step solves the contacts' laws
exactly: one contact as :mod:`.friction_impact` (the first consistent {open, closed} ×
{stick, slip ±} combination, a 2 × 2 solve each); several by a primal–dual active set
(every contact's combination at once, one linear solve per pass, the contacts whose laws
fail switched; warm-started from the previous step, one pass where nothing changes). Where
it cycles, block Gauss–Seidel over the contacts (each block that exact solve with the
others' forces held, to a relative change of ``sweep_tol``), which settles on mildly
coupled contacts only (on the face's 9 contacts with the stops pressed by 2e-7 m it did
not, in 20000 sweeps): a step that neither settles raises.

Steady state by marching: no Newton on the period map. The transient of mode j decays as
exp(−2π ζ_j f_j t); :func:`march_to_steady` marches until the modal state repeats after
k <= ``max_multiple`` periods (period-doubled orbits are steady states too), and reports
the change per period and the orbit's measures over its last k periods. The tip layer's
stiffest modes must be resolved (h ω_max of order 1): the trapezoidal rule neither
resolves nor damps a mode with h ω >> 1, and impacts ring such modes on
(docs/friction.md).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as la

from ... import _validate as check
from ..mms.forced import Excitation, harmonic_force
from ._march_kernels import _march

__all__ = ["ImpactFrictionMarch", "SteadyOrbit", "march_to_steady"]


class ImpactFrictionMarch:
    """The period map of a model whose contacts each carry one coupled friction contact,
    by Newmark steps in modal coordinates (module docstring).

    Parameters
    ----------
    model : Model
        Unilateral contacts on massless DOFs, one friction contact per contact with
        ``normal_contact`` = that contact; damping diagonal in the open modes (or none).
    force : array_like (n_dof,) or Excitation
    frequency : float
        Hz.
    steps_per_period : int
    sweep_tol : float
        Relative change of the interface forces that ends the Gauss–Seidel sweeps (several
        contacts).
    """

    def __init__(self, model, force, frequency: float, steps_per_period: int = 512, *,
                 sweep_tol: float = 1e-13, max_sweeps: int = 2000):
        friction = {fc.normal_contact: fc for fc in model.friction}
        if (not model.contacts or len(friction) != len(model.friction) or None in friction
                or sorted(friction) != list(range(len(model.contacts)))):
            raise NotImplementedError("the march takes one friction contact per unilateral contact, each "
                                      "coupled to it (normal_contact=k)")
        exc = force if isinstance(force, Excitation) else harmonic_force(model, force)
        self.omega = 2 * np.pi * check.positive("frequency", frequency)
        self.steps = check.integer("steps_per_period", steps_per_period, minimum=8)
        self.h = h = 2 * np.pi / self.omega / self.steps
        self.sweep_tol, self.max_sweeps = float(sweep_tol), int(max_sweeps)
        b = model.blocks
        M = b["M_ll"].toarray()
        K = model.reduced_stiffness.toarray()
        w2, Phi = la.eigh(0.5 * (K + K.T), 0.5 * (M + M.T))
        self.Phi, self.M = Phi, M
        C = b["C_ll"].toarray() if b["C_ll"] is not None else np.zeros_like(M)
        Cm = Phi.T @ C @ Phi
        cd = np.diag(Cm).copy()  # off the diagonal: round-off of the eigenvectors (1e-8 on the solid)
        off = np.abs(Cm - np.diag(cd)).max() / max(np.abs(cd).max(), 1e-300)
        if off > 1e-6:
            raise NotImplementedError(f"the march needs damping diagonal in the open modes (modal or "
                                      f"Rayleigh); off-diagonal share {off:.1e}")
        K_cc = b["K_cc"].toarray() if hasattr(b["K_cc"], "toarray") else np.asarray(b["K_cc"])
        K_lc = b["K_lc"].toarray() if hasattr(b["K_lc"], "toarray") else np.asarray(b["K_lc"])
        A = la.inv(K_cc)
        dofs = [d for k, ct in enumerate(model.contacts) for d in (ct.dof, friction[k].dof)]
        idx = [int(np.searchsorted(model.c, d)) for d in dofs]
        self.interface = np.array(dofs)
        psi = Phi.T @ (K_lc @ A[:, idx])
        self.w2, self.cd = np.ascontiguousarray(w2), np.ascontiguousarray(cd)
        self.kinv = 1.0 / (self.w2 + 2.0 / h * self.cd + 4.0 / h**2)
        self.psi, self.psiT = np.ascontiguousarray(psi), np.ascontiguousarray(psi.T)
        self.R0 = np.ascontiguousarray(A[np.ix_(idx, idx)])
        self.R = np.ascontiguousarray(self.R0 + (psi.T * self.kinv) @ psi)
        self.side = np.array([float(ct.side) for ct in model.contacts])
        self.gap = np.array([float(ct.gap) for ct in model.contacts])
        self.mu = np.array([float(friction[k].mu) for k in range(len(model.contacts))])
        self.pre = np.array([float(friction[k].preload) for k in range(len(model.contacts))])
        sig, _ = exc.scale(self.omega)
        F = sig * np.asarray(exc.vector, dtype=complex)[model.l]
        self.fc, self.fs = Phi.T @ F.real, -(Phi.T @ F.imag)
        self.n_l, self.n_k = M.shape[0], len(model.contacts)
        self.model = model
        self.reset()

    def reset(self) -> None:
        """The laws' warm start: every contact open and stuck, no force."""
        self._lam, self._g = np.zeros(self.n_k), np.zeros(self.n_k)
        self._combo = np.zeros(self.n_k, dtype=np.int64)

    def to_modal(self, z: np.ndarray):
        """z = (q_l, q_l', u_t (n_k,)) -> (η, η', u_t)."""
        n = self.n_l
        PM = self.Phi.T @ self.M
        return PM @ z[:n], PM @ z[n:2 * n], np.array(z[2 * n:], dtype=float)

    def to_physical(self, eta, vel, ut) -> np.ndarray:
        return np.concatenate([self.Phi @ eta, self.Phi @ vel, ut])

    def march(self, z: np.ndarray, record: bool = False):
        """One period from z = (q_l, q_l', u_t) at τ = 0: (z at T, friction work over the period
        (J)) and, with ``record``, (q_l (n_l, steps+1), λ (steps+1, n_k), g, u_t (steps+1, n_k))."""
        eta, vel, ut = self.to_modal(np.asarray(z, dtype=float))
        work, rec = self._period(eta, vel, ut, record)
        end = self.to_physical(eta, vel, ut)
        if record:
            return end, work, (self.Phi @ rec[0].T,) + rec[1:]
        return end, work

    def _period(self, eta, vel, ut, record):
        """One period in place on the modal state; (work, records or None)."""
        s = self.steps + 1 if record else 0
        rec = (np.empty((s, self.n_l)),) + tuple(np.empty((s, self.n_k)) for _ in range(3))
        work, sweeps = _march(eta, vel, ut, self._lam, self._g, self._combo, self.w2, self.cd, self.kinv,
                              self.fc, self.fs, self.psi, self.psiT, self.R, self.R0, self.side, self.gap,
                              self.mu, self.pre, self.h, self.steps, self.max_sweeps, self.sweep_tol, *rec)
        if sweeps < 0:
            raise RuntimeError("no consistent contact state at a step (μ too large for the coupling, or the "
                               "Gauss–Seidel sweeps over the contacts did not settle)")
        return work, (rec if record else None)


class SteadyOrbit:
    """The last ``multiple`` periods of :func:`march_to_steady`.

    Attributes
    ----------
    state : ndarray (2 n_l + n_k,)
        (q_l, q_l', u_t) at τ = 0 of the recorded periods.
    multiple : int
        The orbit's period in periods of the force (1: T-periodic; 2: period doubled, ...),
        the smallest k <= ``max_multiple`` whose change fell below the tolerance (the
        largest when none did).
    converged : bool
        Whether one did (False: ``max_periods`` ran out).
    periods : int
        Periods marched before the record.
    change : ndarray (periods, max_multiple)
        Relative change of the modal state (η, η'/Ω) over k = 1..max_multiple periods, after
        each period (nan before k periods).
    q_l : ndarray (n_l, multiple·steps + 1); lam, g, u_t : ndarray (multiple·steps + 1, n_k)
        The recorded periods' samples: displacements of the DOFs with mass (m), contact
        forces (N), the support's tangential forces on the nodes (N), the nodes' tangential
        positions (m).
    work : ndarray (multiple,)
        Friction work over each recorded period (J, Σ −½(g_0 + g_1)(u_1 − u_0), > 0 dissipated).
    """

    def __init__(self, state, multiple, periods, change, q_l, lam, g, u_t, work, bound):
        self.state, self.multiple, self.periods = state, multiple, periods
        self.change = np.asarray(change)
        self.q_l, self.lam, self.g, self.u_t = q_l, lam, g, u_t
        self.work = np.asarray(work, dtype=float)
        self._bound = bound
        self.period, self.converged = float("nan"), False

    @property
    def max_displacement(self) -> float:
        """Largest |q| (m) over the DOFs with mass and the samples."""
        return float(np.abs(self.q_l).max())

    @property
    def contact_force_max(self) -> float:
        """Largest contact force (N) over the contacts and the samples."""
        return float(self.lam.max())

    @property
    def impulse(self) -> np.ndarray:
        """Contact impulse per recorded period (N·s, summed over the contacts, trapezoidal):
        the period's mean contact force times T, shape (multiple,)."""
        lam = self.lam.sum(axis=1)
        steps = (len(lam) - 1) // self.multiple
        h = self.period / steps
        mid = 0.5 * (lam[1:] + lam[:-1])
        return np.array([mid[i * steps:(i + 1) * steps].sum() * h for i in range(self.multiple)])

    @property
    def slip_fraction(self) -> float:
        """Largest fraction of the steps any node slides (|g| at its bound)."""
        return float(np.max(np.mean(np.abs(self.g[1:]) >= self._bound[1:] * (1 - 1e-12), axis=0)))


def march_to_steady(model, force, frequency: float, steps_per_period: int = 512, state=None, *,
                    max_periods: int = 2000, tol: float = 1e-9, min_periods: int = 1, max_multiple: int = 4,
                    marcher: ImpactFrictionMarch | None = None) -> SteadyOrbit:
    """March whole periods from ``state`` (default rest) until the modal state (η, η'/Ω)
    repeats after k <= ``max_multiple`` periods to ``tol`` (relative to its largest entry)
    or ``max_periods``; then k periods recorded.

    Parameters
    ----------
    model, force, frequency, steps_per_period
        As :class:`ImpactFrictionMarch` (or pass ``marcher``).
    state : ndarray (2 n_l + n_k,), optional
        (q_l, q_l', u_t) at τ = 0.
    tol : float
        On the relative change over k periods; the periodicity of the returned orbit.
    min_periods : int
        Periods marched at least (a start that is already periodic to ``tol`` is tested
        over these).

    Returns
    -------
    SteadyOrbit
    """
    mr = marcher or ImpactFrictionMarch(model, force, frequency, steps_per_period)
    n = mr.n_l
    z = np.zeros(2 * n + mr.n_k) if state is None else np.asarray(state, dtype=float).copy()
    eta, vel, ut = mr.to_modal(z)
    mr.reset()
    sc_v = 1.0 / mr.omega
    past = [np.concatenate([eta, sc_v * vel])]
    change, multiple, converged = [], max_multiple, False
    for p in range(max_periods):
        mr._period(eta, vel, ut, False)
        now = np.concatenate([eta, sc_v * vel])
        size = max(np.abs(now).max(), 1e-300)
        change.append([np.abs(now - past[-k]).max() / size if k <= len(past) else np.nan
                       for k in range(1, max_multiple + 1)])
        past = (past + [now])[-max_multiple:]
        hit = [k + 1 for k, c in enumerate(change[-1]) if c <= tol]
        if p + 1 >= min_periods and hit:
            multiple, converged = hit[0], True
            break
    z = mr.to_physical(eta, vel, ut)
    recs, work = [], []
    for _ in range(multiple):
        w, rec = mr._period(eta, vel, ut, True)
        recs.append(rec)
        work.append(w)
    joined = [np.concatenate([r[i][:-1] for r in recs] + [recs[-1][i][-1:]]) for i in range(4)]
    orbit = SteadyOrbit(z, multiple, len(change), change, mr.Phi @ joined[0].T, *joined[1:], work,
                        mr.mu * (mr.pre + joined[1]))
    orbit.period, orbit.converged = 2 * np.pi / mr.omega, converged
    return orbit
