"""Baseline 2: time-domain shooting with an energy-conserving trapezoidal rule.

Because the contact DOFs are massless they follow the DOFs with mass ``l`` statically
(docs/design.md §1; the docstring of :mod:`mmshbm.methods.exact`): at fixed ``q_l`` the contact
problem of one contact is a scalar LCP with the solution λ = k_c max(0, −h(q_l)), free gap
h(q_l) = gap + a·q_l, a = −K_lc K_cc⁻¹ w_c and k_c = 1/(w_cᵀ K_cc⁻¹ w_c). The motion of
the DOFs with mass is the continuous, piecewise-linear system

    M_ll q_l'' + K_open q_l = λ(q_l) a,      K_open = K_ll − K_lc K_cc⁻¹ K_cl,

with no impacts (positions, velocities and accelerations are continuous at a switch).

Time stepping: the trapezoidal rule (Newmark average acceleration) on the linear part,
with the contact force implicit, in one of two standard forms (``scheme``):

* ``"trapezoidal"``: the force at both ends of the step, (λ_k + λ_k+1)/2 — Newmark with a
  nonlinear internal force;
* ``"avf"`` (default): the force averaged exactly along the step, ∫₀¹ λ(q_k + s Δq) ds (the
  averaged-vector-field / discrete-gradient form of energy-conserving algorithms for
  contact, cf. Laursen & Chawla 1997, Armero & Petőcz 1998). Because λ depends on the state
  only through the free gap h, which is linear in s, the integral is exact in closed form.

Each step solves S q_k+1 = P q_k + (4/h) M v_k + F(h_k, h_k+1) a with S = (4/h²) M + K_open,
P = (4/h²) M − K_open and F the step's force sum; F depends on the unknown state only
through the scalar h_k+1, so one band solve with the factor of S, a closed-form root of a
scalar piecewise-quadratic equation and one correction along z = S⁻¹ a give the step
exactly (no inner iteration). Both forms are symmetric (time-reversible) and of order 2:
the force is Lipschitz with a jump only in its gradient, so the step that contains a
switch has a local error O(h²) instead of O(h³), and with two switches per period the
global error stays O(h²) (the constant depends on where in its step a switch falls, so the
error is not a smooth function of h). Moreau–Jean θ = 1/2 would lump the contact
percussion at the step's end, which is order 1; with a massless contact node there are no
impacts to justify that. On the linear system both forms conserve energy with a
frequency shrunk by tan(ω̃h/2) = ωh/2, i.e. a relative error ≈ (ωh)²/12 (N ≈ 180 steps per
period for 1e-4); they are unconditionally stable, so high modes the step does not
resolve stay bounded but mistimed. Why "avf" is the default:

* it conserves the energy ½vᵀMv + ½qᵀK_open q + ½k_c min(0, h)² exactly (to round-off)
  across contact, like the exact flow;
* its step map is C¹ in the state (F is C¹ in (h_k, h_k+1)), so the shooting residual is
  C¹ and Newton converges as on a smooth problem. With the plain trapezoidal rule the
  residual has a kink whenever one step's contact state flips; when the contact is stiff
  compared with 1/h² (the beam's fine tip element) these kinks are large, and the
  semismooth Newton iteration cycles between two active sets near grazing (observed on
  the 21-element beam: the continuation stalls at 1.005 gaps).

``S`` and ``M`` are stored in band form (reverse Cuthill–McKee ordering of the DOFs with
mass when it narrows the band); ``S`` is factored once per step size, i.e. per Newton
iterate, in O(n p²).

Several contacts (details: docs/shooting.md, :mod:`mmshbm.methods.shooting._contact_kernels`).
With free gaps h = gap + A q_l the contact forces at fixed q_l solve the LCP
g = h + G λ >= 0, λ >= 0, gᵀλ = 0 (G = Wᵀ K_cc⁻¹ W), whose solution is continuous and
piecewise linear in h. The step keeps its form with Aᵀ F(h0, h1) for the force, and the
new free gaps solve the monotone m-dimensional equation h1 = hy + A S⁻¹Aᵀ F(h0, h1) by
semismooth Newton to round-off; F (λ(h0) + λ(h1), or the exact path average for "avf",
still a discrete gradient) and its derivatives are computed exactly by following λ along
the step's straight path in h (principal pivoting); sensitivities by the Woodbury form.
One contact keeps the closed-form scalar step of 0.1 (bit for bit).

Contact DOFs with mass (FE-package models): a penalty spring λ = k_p max(0, −g) on the
DOF, which in this step is an LCP row with G_ii = 1/k_p and h = gap − side q_dof: the
implicit, A-stable, energy-conserving step integrates it as a stiff ODE (order 2 once the
contact phase is resolved; ``penalty_stiffness``, default 10³ times the static stiffness
at the contact, as penalty-HBM).

Unknowns and phase. The system is reversible (q, v, t) -> (q, −v, −t) and so is the
trapezoidal map, exactly. The nonlinear modes continued from the linear modes are
symmetric orbits: all velocities vanish at t = 0 and at t = T/2. Shooting uses this as
MMS-HBM's cosine-only ansatz does: the unknowns are the initial positions x = q_l(0) (the
DOFs with mass; the massless ones follow statically) and the period (as Ω = 2π/T), the
initial velocities are zero, and the equations are v_l(T/2) = 0 after N/2 steps. Starting
at a turning point fixes the phase (only the discrete half-period shift remains), and
the conservative degeneracy disappears: a full-period shooting z(T) − z(0) = 0 has a
monodromy with a double multiplier +1 (phase and energy), so its 2 n_l equations in
2 n_l + 1 unknowns would need a phase condition *and* an unfolding parameter; the
half-period problem has n_l equations in n_l + 1 unknowns with full row rank along the
family, at half the integration cost. The discrete orbit is exactly periodic (the
second half is the mirror image of the first) because the scheme is reversible.
Convention as :mod:`mmshbm.methods.exact`: t = 0 is the turning point farthest from the stop.

Newton. The Jacobian comes from the tangent (sensitivity) vectors propagated with the
step, no finite differences: n_l + 1 columns (initial positions and Ω; Ω enters through
the step size h = T/N). Each column costs one band solve and two band products per step,
so one Jacobian costs O(N n_l² p): for large models shooting pays for the dense
monodromy. The columns are processed in blocks so that the band recurrences vectorise.

Floquet multipliers. The monodromy of the discrete map over one period (2 n_l tangent
vectors) gives the multipliers; on a symmetric orbit of the reversible map they come in
pairs μ, 1/μ, and energy conservation and the phase give two equal +1.
:meth:`ShootingProblem.floquet_multipliers` computes them on demand; ``monitor`` records
``floquet_max`` (largest modulus) when ``floquet`` is on (default for models with at most
``FLOQUET_AUTO_LIMIT`` DOFs with mass: the dense eigenproblem of size 2 n_l is the cost).
"""

from __future__ import annotations

import logging

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
from scipy.sparse.csgraph import reverse_cuthill_mckee

from ... import _validate as check
from ...contact.lcp import lcp_solve
from ...contact.table import contact_law, contact_table, penalty_values, start_mode
from ...core.measures import amplitude_peak, amplitude_sign, refined_max
from ...core.problem import BackboneProblemBase
from ...model.model import Model
from ._contact_kernels import _integrate_multi
from ._kernels import _band_cholesky, _band_solve, _band_solve_rows, _integrate
from .signals import ShootingSignals

__all__ = ["ShootingProblem", "DEFAULT_STEPS_PER_PERIOD", "FLOQUET_AUTO_LIMIT"]

log = logging.getLogger(__name__)

#: Default time steps per period.
DEFAULT_STEPS_PER_PERIOD = 256
#: ``floquet="auto"`` computes multipliers at every point up to this many DOFs with mass.
FLOQUET_AUTO_LIMIT = 100


def _lower_band(A: sp.spmatrix, p: int) -> np.ndarray:
    """Lower band storage (p+1, n) of the symmetric sparse matrix ``A``."""
    A = sp.coo_matrix(A)
    n = A.shape[0]
    ab = np.zeros((p + 1, n))
    keep = A.row >= A.col
    d = A.row[keep] - A.col[keep]
    np.add.at(ab, (d, A.col[keep]), A.data[keep])
    return ab


class ShootingProblem(ShootingSignals, BackboneProblemBase):
    """Symmetric-orbit shooting with the trapezoidal rule, as a continuation problem.

    Parameters
    ----------
    model : Model
        The structure; contacts on massless DOFs are exact (their LCP per step), contacts
        on DOFs with mass are penalty springs (``penalty_stiffness``).
    steps_per_period : int
        Time steps N per period (even, >= 8); N/2 steps are integrated.
    mode : int
        Which linear mode (1-based) the branch starts from.
    scheme : {"avf", "trapezoidal"}
        Contact force averaged exactly along each step (energy conserving, C¹ residual)
        or taken at the step's ends (plain Newmark average acceleration).
    floquet : bool or "auto"
        Record ``floquet_max`` in :meth:`monitor` ("auto": when the model has at most
        ``FLOQUET_AUTO_LIMIT`` DOFs with mass; otherwise NaN is recorded).
    penalty_stiffness : float or sequence of float, optional
        k_p (N/m) of the contacts whose DOF carries mass: one for all, or one per contact
        (entries of massless contacts unused). Default ``DEFAULT_PENALTY_FACTOR`` (10³)
        times the static stiffness at each contact, 1/(e_dᵀ K⁻¹ e_d). A ValueError if
        every contact DOF is massless (their contact is exact).

    Notes
    -----
    The scaled unknown vector is ``u = [x/s, Ω/ω_ref]`` with ``x = q_l(0)`` (m, rad) in
    ``model.l`` order, ``s`` the per-DOF length scale ``xscale`` and ω_ref the linear
    frequency (rad/s) of the mode. ``s`` is the gap times the mode's shape (amplitude DOF
    1, floored at 10⁻³ of its largest entry) times a factor that makes the scaled norm of
    the linear mode equal to MMS-HBM's, so that an arclength step means the same change
    of amplitude in both methods. Residual rows are v_l(T/2) / (ω_ref s).

    Attributes
    ----------
    model, H (= 0), N (= steps_per_period), n_unknowns, contact_stiffness (N/m),
    linear_frequency (Hz of the open-contact mode), omega_ref (rad/s).
    """

    method = "shooting"
    setting_names = ("N", "mode")
    H = 0

    def __init__(self, model: Model, steps_per_period: int = DEFAULT_STEPS_PER_PERIOD, mode: int = 1,
                 scheme: str = "avf", floquet: bool | str = "auto", penalty_stiffness=None):
        if not isinstance(model, Model):
            raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
        N = check.integer("steps_per_period", steps_per_period, minimum=8)
        if N % 2:
            raise ValueError(f"steps_per_period must be even (half a period is integrated), got {N}")
        if scheme not in ("avf", "trapezoidal"):
            raise ValueError(f"scheme must be 'avf' or 'trapezoidal', got {scheme!r}")
        self.scheme = scheme
        if not (isinstance(floquet, bool) or floquet == "auto"):
            raise ValueError(f"floquet must be True, False or 'auto', got {floquet!r}")
        self.model = model
        self.N = N
        self.mode = check.integer("mode", mode, minimum=1)
        if self.mode > len(model.l):
            raise ValueError(f"mode must be <= the number of DOFs with mass ({len(model.l)}), "
                             f"got {self.mode}")
        self.amplitude_dof = model.amplitude_dof  # ValueError naming it if it is needed and missing
        self._amp_sign = amplitude_sign(model)
        self.contacts = ct = contact_table(model)
        b = model.blocks
        self.n_c = len(model.c)
        self.gap = float(model.gap)
        K_cc, K_lc = b["K_cc"], b["K_lc"]
        K_open = model.reduced_stiffness
        M_ll = b["M_ll"]
        n = M_ll.shape[0]
        self.n_l = n

        # DOF order: reverse Cuthill–McKee when it narrows the band
        pattern = (abs(M_ll) + abs(K_open)).tocsr()

        def bandwidth(P):
            P = P.tocoo()
            return int(np.max(np.abs(P.row - P.col))) if P.nnz else 0

        perm = np.arange(n)
        p = bandwidth(pattern)
        rcm = reverse_cuthill_mckee(pattern, symmetric_mode=True)
        p_rcm = bandwidth(pattern[rcm][:, rcm])
        if p_rcm < p:
            perm, p = np.asarray(rcm), p_rcm
        self.perm = perm
        self.bandwidth = p
        Mp = M_ll[perm][:, perm]
        Kp = K_open[perm][:, perm]
        self._Mb = _lower_band(Mp, p)
        self._Kb = _lower_band(Kp, p)
        self._K = Kp.tocsr()
        self._B = np.ascontiguousarray(-la.solve(K_cc, K_lc.T)[:, perm]) if self.n_c else np.zeros((0, n))
        self._init_contacts(K_cc, K_lc, penalty_stiffness)

        freq, phi = start_mode(model, self.mode)
        self.linear_frequency = freq
        self.omega_ref = 2 * np.pi * self.linear_frequency
        amp = phi[self.amplitude_dof]
        if abs(amp) < 1e-12 * np.max(np.abs(phi)):
            raise ValueError(f"linear mode {self.mode} does not move the contact DOF: no impact")
        if np.all(np.abs(phi[ct.dofs]) < 1e-12 * np.max(np.abs(phi))):
            raise ValueError(f"linear mode {self.mode} does not move any contact DOF: no impact")
        phi = phi / abs(amp)  # amplitude DOF ±1; the (first) contact DOF toward its stop
        self.mode_shape_l = phi[model.l][perm]
        # sign of the amplitude DOF at t = 0 (the turning point farthest from the stop)
        self._amp_sigma = -float(np.sign(phi[self.amplitude_dof]))
        length = self.gap if self.gap > 0 else 1.0
        shape_l = np.abs(self.mode_shape_l)
        s0 = length * np.maximum(shape_l, 1e-3 * shape_l.max())
        # MMS-HBM's unknowns are the massless DOFs; without them the contact DOFs
        ref = model.c if (model.massless_contacts and self.n_c) else ct.dofs
        shape_c = np.abs(phi[ref])
        s0_c = length * np.maximum(shape_c, 1e-3 * shape_c.max())
        rho = np.linalg.norm(self.mode_shape_l / s0) / np.linalg.norm(phi[ref] / s0_c)
        self.xscale = s0 * rho
        self.colscale = np.concatenate([self.xscale, [self.omega_ref]])
        self.rowscale = self.omega_ref * self.xscale
        self.n_unknowns = n + 1
        self.floquet = (n <= FLOQUET_AUTO_LIMIT) if floquet == "auto" else bool(floquet)
        self._S_cache = None
        self._traj_cache = None

    def _init_contacts(self, K_cc, K_lc, penalty_stiffness) -> None:
        """Free gaps h = gap + A q_l (permuted order), the Delassus matrix G of the LCP at
        fixed q_l and the massless DOFs' recovery q_c = B q_l + E λ
        (:func:`~mmshbm.contact.table.contact_law`; penalty springs on DOFs with mass)."""
        ct = self.contacts
        if (~ct.massless).any():
            kp = penalty_values(self.model, penalty_stiffness)
        elif penalty_stiffness is not None:
            raise ValueError("penalty_stiffness applies to contact DOFs with mass; every contact DOF of this "
                             "model is massless (its contact is exact)")
        else:
            kp = None
        self.penalty_stiffnesses = kp
        A, E, G = contact_law(self.model, kp)
        A = A[:, self.perm]
        if ct.n == 1 and ct.massless[0]:
            # one massless contact: the arithmetic of mmshbm 0.1
            w = np.zeros(self.n_c)
            w[int(np.searchsorted(self.model.c, ct.dof[0]))] = -float(ct.side[0])
            e = la.solve(K_cc, w)
            self.contact_stiffness = 1.0 / float(w @ e)
            self.a = np.ascontiguousarray((-K_lc @ e)[self.perm])
            self._e = e
            E, A = e[:, None], self.a[None, :]
        elif ct.n == 1:  # a penalty spring on a DOF with mass
            self.contact_stiffness = float(kp[0])
            self.a = np.ascontiguousarray(A[0])
            self._e = E[:, 0]
        else:
            self.contact_stiffness = float(np.min(1.0 / np.diag(G)))
        self._A = np.ascontiguousarray(A)
        self._E = np.ascontiguousarray(E)
        self._G = np.ascontiguousarray(G)
        self._gaps = np.ascontiguousarray(ct.gap)

    # ------------------------------------------------------------------ unknowns
    def unpack(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """Scaled unknowns -> (x = q_l(0) (n_l,) in ``model.l`` order (m, rad), Ω (rad/s))."""
        u = np.asarray(u, dtype=float)
        if u.shape != (self.n_unknowns,):
            raise ValueError(f"u must have shape ({self.n_unknowns},), got {u.shape}")
        y = u * self.colscale
        x = np.empty(self.n_l)
        x[self.perm] = y[:-1]
        return x, float(y[-1])

    def pack(self, x: np.ndarray, omega: float) -> np.ndarray:
        """(x = q_l(0) (n_l,) in ``model.l`` order, Ω (rad/s)) -> scaled unknowns."""
        x = np.asarray(x, dtype=float)
        return np.concatenate([x[self.perm], [float(omega)]]) / self.colscale

    def linear_mode_point(self, amplitude: float) -> np.ndarray:
        """Scaled unknowns of the linear mode whose contact DOF swings ``amplitude`` (m);
        t = 0 is the turning point farthest from the stop."""
        y = np.concatenate([-amplitude * self.mode_shape_l, [self.omega_ref]])
        return y / self.colscale

    def initial_tangent(self) -> np.ndarray:
        """Unit tangent of the linear branch (growing amplitude, constant Ω)."""
        t = self.linear_mode_point(1.0)
        t[-1] = 0.0
        return t / np.linalg.norm(t)

    # ------------------------------------------------------------------ integration
    def _step_matrix(self, h: float):
        """Band Cholesky factor of S = (4/h²) M + K_open, band P = (4/h²) M − K_open,
        z = S⁻¹ a and α = a·z (cached per h); with several contacts z = S⁻¹ Aᵀ (n_l, n_ct)
        and α = A z (n_ct, n_ct)."""
        if self._S_cache is not None and self._S_cache[0] == h:
            return self._S_cache[1:]
        Sf = self._Kb + (4.0 / (h * h)) * self._Mb
        Pb = (4.0 / (h * h)) * self._Mb - self._Kb
        if not _band_cholesky(Sf):
            raise ValueError(f"step matrix not positive definite at h = {h:g} s")
        if self.contacts.n == 1:
            z = self.a.copy()
            _band_solve(Sf, z)
            alpha = float(self.a @ z)
        else:  # Z = S⁻¹ Aᵀ (n_l, n_ct) and A Z (n_ct, n_ct)
            Zt = self._A.copy()
            _band_solve_rows(Sf, Zt)
            z = np.ascontiguousarray(Zt.T)
            alpha = np.ascontiguousarray(self._A @ z)
        self._S_cache = (h, Sf, Pb, z, alpha)
        return Sf, Pb, z, alpha

    def _check_omega(self, omega: float) -> float:
        if not (np.isfinite(omega) and omega > 0):
            raise ValueError(f"the frequency unknown must be positive, got Ω = {omega!r} rad/s")
        return 2 * np.pi / omega / self.N

    def _integrate(self, x, omega, n_steps, tangents=None, store=False):
        """Integrate ``n_steps`` from the turning point x; tangents = (dq, dv, dh) with dq,
        dv (n_l, m) (permuted order, one column per parameter) and dh (m,)."""
        h = self._check_omega(omega)
        Sf, Pb, z, alpha = self._step_matrix(h)
        n = self.n_l
        q, v = np.ascontiguousarray(x[self.perm]), np.zeros(n)
        if tangents is None:
            tangents = (np.zeros((n, 0)), np.zeros((n, 0)), np.zeros(0))
        m = self.contacts.n
        lam_shape = (n_steps + 1,) if m == 1 else (n_steps + 1, m)
        if store:
            Q, V, LAM = np.empty((n_steps + 1, n)), np.empty((n_steps + 1, n)), np.empty(lam_shape)
        else:
            Q, V, LAM = np.empty((0, n)), np.empty((0, n)), np.empty((0,) * len(lam_shape))
        avf = self.scheme == "avf"
        if m == 1:
            closed = _integrate(Sf, Pb, self._Mb, self._Kb, self.a, z, alpha, self.contact_stiffness,
                                self.gap, h, n_steps, avf, q, v, *tangents, Q, V, LAM)
        else:
            closed = _integrate_multi(Sf, Pb, self._Mb, self._Kb, self._A, z, alpha, self._G, self._gaps, h,
                                      n_steps, avf, q, v, *tangents, Q, V, LAM)
            if closed < 0:
                raise RuntimeError(f"the contact problem of step {-1 - closed} has no unique solution "
                                   f"(Ω = {omega:.6g} rad/s)")
        return q, v, closed, (Q, V, LAM)

    # ------------------------------------------------------------------ residual
    def residual(self, u: np.ndarray) -> np.ndarray:
        """Scaled residual v_l(T/2)/(ω_ref s), shape (n_l,)."""
        x, omega = self.unpack(u)
        _, v, _, _ = self._integrate(x, omega, self.N // 2)
        return v / self.rowscale

    def residual_and_jacobian(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(R, J): :meth:`residual` (n_l,) and its Jacobian with respect to the scaled
        unknowns, shape (n_l, n_l + 1), from the integration's sensitivities."""
        x, omega = self.unpack(u)
        half = self.N // 2
        n = self.n_l
        h = self._check_omega(omega)
        dq = np.zeros((n, n + 1))
        dq[np.arange(n), np.arange(n)] = self.xscale
        dv = np.zeros((n, n + 1))
        dh = np.zeros(n + 1)
        dh[-1] = -h / omega * self.omega_ref  # h = 2π/(Ω N): ∂h/∂(Ω/ω_ref)
        _, v, _, _ = self._integrate(x, omega, half, (dq, dv, dh))
        R = v / self.rowscale
        J = dv / self.rowscale[:, None]
        return R, J

    def solve_at_amplitude(self, amplitude: float, guess: np.ndarray | None = None, tol: float = 1e-10,
                           max_iter: int = 30) -> np.ndarray:
        """The orbit whose contact DOF starts ``amplitude`` (m) away from the stop at t = 0
        (the convention of :func:`mmshbm.methods.exact.periodic_orbit`; with several
        contacts the amplitude DOF's value at t = 0, signed as the start of the first-mode
        family), by Newton on the residual
        bordered with that condition. ``guess``: scaled unknowns (default the linear mode).
        Converged when the scaled residual is <= ``tol``, or <= √tol with the last Newton
        update below 1e-9 (relative): on strongly unstable orbits round-off in the
        integration leaves a residual floor above ``tol`` while Newton has converged. Far
        from the solution the Ω update is limited to 20 %. Returns the scaled unknowns;
        raises RuntimeError without convergence."""
        amplitude = check.positive("amplitude", amplitude)
        u = self.linear_mode_point(amplitude) if guess is None else np.array(guess, dtype=float)
        # amplitude at t = 0, a linear row in u: -stop_side * (B x)[contact] for one contact on
        # the amplitude DOF (open there), else the amplitude DOF's value (a massless one by
        # the open-contact recovery B) signed as the start of the family
        row = self._amplitude_row() * self.xscale
        length = self.gap if self.gap > 0 else amplitude
        du_norm = np.inf
        for _ in range(max_iter):
            R, J = self.residual_and_jacobian(u)
            c = (row @ u[:-1] - amplitude) / length
            res = max(np.max(np.abs(R)), abs(c))
            if res <= tol or (res <= np.sqrt(tol) and du_norm <= 1e-9 * np.max(np.abs(u))):
                return u
            A = np.vstack([J, np.append(row / length, 0.0)])
            du = np.linalg.solve(A, np.append(R, c))
            # damping far from the solution: Ω changes by at most 20 % per iteration
            du *= min(1.0, 0.2 * u[-1] / max(abs(du[-1]), 1e-300))
            u = u - du
            du_norm = float(np.max(np.abs(du)))
        raise RuntimeError(f"no convergence at amplitude {amplitude:g} m in {max_iter} iterations "
                           f"(residual {max(np.max(np.abs(R)), abs(c)):.2e})")

    def _amplitude_row(self) -> np.ndarray:
        """Row r (n_l, permuted order) with the amplitude = r · q_l at t = 0."""
        model, amp = self.model, self.amplitude_dof
        if self._amp_sign != 0 and self.contacts.massless[0]:
            return -self._amp_sign * self._B[int(np.searchsorted(model.c, amp))]
        sigma = -self._amp_sign if self._amp_sign else self._amp_sigma
        if amp in set(model.l.tolist()):
            row = np.zeros(self.n_l)
            row[np.argsort(self.perm)[int(np.searchsorted(model.l, amp))]] = sigma
            return row
        return sigma * self._B[int(np.searchsorted(model.c, amp))]

    def floquet_multipliers(self, u: np.ndarray) -> np.ndarray:
        """Eigenvalues of the discrete map's monodromy matrix over one period at ``u``,
        shape (2 n_l,), sorted by decreasing modulus."""
        x, omega = self.unpack(u)
        n = self.n_l
        dq = np.hstack([np.eye(n), np.zeros((n, n))])
        dv = np.hstack([np.zeros((n, n)), np.eye(n)])
        self._integrate(x, omega, self.N, (dq, dv, np.zeros(2 * n)))
        monodromy = np.vstack([dq, dv])  # column j: tangent of (q, v) to initial (q, v)_j
        mu = la.eigvals(monodromy)
        return mu[np.argsort(-np.abs(mu), kind="stable")]

    # ------------------------------------------------------------------ monitor
    def energy(self, u: np.ndarray) -> float:
        """Energy (J) of the orbit's initial state (velocities are zero at t = 0): ½ qᵀ K q
        over all DOFs, i.e. ½ xᵀ K_open x + ½ λᵀ G λ with λ the contact forces at x (one
        contact: ½ xᵀ K_open x + ½ k_c min(0, h(x))²); a penalty spring's energy is included."""
        x, _ = self.unpack(u)
        q = x[self.perm]
        if self.contacts.n == 1:
            g = self.gap + self.a @ q
            return float(0.5 * q @ (self._K @ q) + 0.5 * self.contact_stiffness * min(0.0, g) ** 2)
        lam, _ = lcp_solve(self._G, self._gaps + self._A @ q)
        return float(0.5 * q @ (self._K @ q) + 0.5 * lam @ (self._G @ lam))

    def monitor(self, u: np.ndarray) -> dict:
        """frequency (Hz), amplitude (m, at ``model.amplitude_dof``: the excursion away from
        the stop for the DOF of a single contact, else max |q|), energy (J),
        contact_force_max (N, over all contacts), closed_fraction (share of the steps
        with a contact closed), floquet_max (largest multiplier modulus; NaN when off);
        with several contacts also ``contact_force_max_<i>`` per contact."""
        _, omega = self.unpack(u)
        lam = self.trajectory(u)[3]
        q_amp = self._dof_at_steps(u, self.amplitude_dof)
        if lam.ndim == 1:
            peak = max(refined_max(lam), 0.0) if lam.max() > 0 else 0.0
            closed = float(np.mean(lam > 0))
            peaks = [peak]
        else:
            peaks = [max(refined_max(col), 0.0) if col.max() > 0 else 0.0 for col in lam.T]
            closed = float(np.mean(np.any(lam > 0, axis=1)))
        rec = {
            "frequency": omega / (2 * np.pi),
            "amplitude": amplitude_peak(q_amp, self._amp_sign),
            "energy": self.energy(u),
            "contact_force_max": float(max(peaks)),
            "closed_fraction": closed,
            "floquet_max": float(np.abs(self.floquet_multipliers(u)[0])) if self.floquet else float("nan"),
        }
        if len(peaks) > 1:
            rec.update({f"contact_force_max_{i}": float(v) for i, v in enumerate(peaks)})
        return rec

