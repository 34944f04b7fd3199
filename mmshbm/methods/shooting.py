"""Baseline 2: time-domain shooting with an energy-conserving trapezoidal rule.

Because the contact DOFs are massless they follow the DOFs with mass ``l`` statically
(docs/design.md §1; the docstring of :mod:`mmshbm.methods.exact`): at fixed ``q_l`` the contact
problem is a scalar LCP with the solution λ = k_c max(0, −h(q_l)), free gap
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

from .. import _validate as check
from ..model.model import Model
from ._shooting_kernels import _band_cholesky, _band_solve, _integrate
from .mms_hbm import _refined_max

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


class ShootingProblem:
    """Symmetric-orbit shooting with the trapezoidal rule, as a continuation problem.

    Parameters
    ----------
    model : Model
        The structure (at least one massless DOF, the contact DOF among them).
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

    Notes
    -----
    The scaled unknown vector is ``u = [x/s, Ω/ω_ref]`` with ``x = q_l(0)`` (m, rad) in
    ``model.l`` order, ``s`` the per-DOF length scale ``xscale`` and ω_ref the linear
    frequency (rad/s) of the mode. ``s`` is the gap times the mode's shape (contact DOF
    1, floored at 10⁻³ of its largest entry) times a factor that makes the scaled norm of
    the linear mode equal to MMS-HBM's, so that an arclength step means the same change
    of amplitude in both methods. Residual rows are v_l(T/2) / (ω_ref s).

    Attributes
    ----------
    model, H (= 0), N (= steps_per_period), n_unknowns, contact_stiffness (N/m),
    linear_frequency (Hz of the open-contact mode), omega_ref (rad/s).
    """

    method = "shooting"
    H = 0

    def __init__(self, model: Model, steps_per_period: int = DEFAULT_STEPS_PER_PERIOD, mode: int = 1,
                 scheme: str = "avf", floquet: bool | str = "auto"):
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
        b = model.blocks
        self.n_c = len(model.c)
        self.ci = model.contact_index
        self.gap = float(model.gap)
        w = np.asarray(model.w_c, dtype=float)
        K_cc, K_lc = b["K_cc"], b["K_lc"]
        e = la.solve(K_cc, w)
        self.contact_stiffness = 1.0 / float(w @ e)
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
        # contact: free gap h = gap + a·q_l, q_c = B q_l + e λ (permuted l order)
        self.a = np.ascontiguousarray((-K_lc @ e)[perm])
        self._B = np.ascontiguousarray(-la.solve(K_cc, K_lc.T)[:, perm])
        self._e = e

        freqs, modes = model.linear_modes(self.mode)
        self.linear_frequency = float(freqs[-1])
        self.omega_ref = 2 * np.pi * self.linear_frequency
        phi = modes[:, -1]
        contact = phi[model.contact_dof]
        if abs(contact) < 1e-12 * np.max(np.abs(phi)):
            raise ValueError(f"linear mode {self.mode} does not move the contact DOF: no impact")
        phi = phi / abs(contact)  # contact DOF: +stop_side (toward the stop)
        self.mode_shape_l = phi[model.l][perm]
        length = self.gap if self.gap > 0 else 1.0
        shape_l = np.abs(self.mode_shape_l)
        s0 = length * np.maximum(shape_l, 1e-3 * shape_l.max())
        shape_c = np.abs(phi[model.c])
        s0_c = length * np.maximum(shape_c, 1e-3 * shape_c.max())
        rho = np.linalg.norm(self.mode_shape_l / s0) / np.linalg.norm(phi[model.c] / s0_c)
        self.xscale = s0 * rho
        self.colscale = np.concatenate([self.xscale, [self.omega_ref]])
        self.rowscale = self.omega_ref * self.xscale
        self.n_unknowns = n + 1
        self.floquet = (n <= FLOQUET_AUTO_LIMIT) if floquet == "auto" else bool(floquet)
        self._S_cache = None
        self._traj_cache = None

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

    def linear_point(self, amplitude: float) -> np.ndarray:
        """Scaled unknowns of the linear mode whose contact DOF swings ``amplitude`` (m);
        t = 0 is the turning point farthest from the stop."""
        y = np.concatenate([-amplitude * self.mode_shape_l, [self.omega_ref]])
        return y / self.colscale

    def initial_tangent(self) -> np.ndarray:
        """Unit tangent of the linear branch (growing amplitude, constant Ω)."""
        t = self.linear_point(1.0)
        t[-1] = 0.0
        return t / np.linalg.norm(t)

    # ------------------------------------------------------------------ integration
    def _step_matrix(self, h: float):
        """Band Cholesky factor of S = (4/h²) M + K_open, band P = (4/h²) M − K_open,
        z = S⁻¹ a and α = a·z (cached per h)."""
        if self._S_cache is not None and self._S_cache[0] == h:
            return self._S_cache[1:]
        Sf = self._Kb + (4.0 / (h * h)) * self._Mb
        Pb = (4.0 / (h * h)) * self._Mb - self._Kb
        if not _band_cholesky(Sf):
            raise ValueError(f"step matrix not positive definite at h = {h:g} s")
        z = self.a.copy()
        _band_solve(Sf, z)
        alpha = float(self.a @ z)
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
        if store:
            Q, V, LAM = np.empty((n_steps + 1, n)), np.empty((n_steps + 1, n)), np.empty(n_steps + 1)
        else:
            Q, V, LAM = np.empty((0, n)), np.empty((0, n)), np.empty(0)
        closed = _integrate(Sf, Pb, self._Mb, self._Kb, self.a, z, alpha, self.contact_stiffness, self.gap, h,
                            n_steps, self.scheme == "avf", q, v, *tangents, Q, V, LAM)
        return q, v, closed, (Q, V, LAM)

    # ------------------------------------------------------------------ residual
    def evaluate(self, u: np.ndarray, jacobian: bool = True):
        """Scaled residual v_l(T/2)/(ω_ref s), shape (n_l,), and, if asked, its Jacobian
        with respect to the scaled unknowns, shape (n_l, n_l + 1)."""
        x, omega = self.unpack(u)
        half = self.N // 2
        if not jacobian:
            _, v, _, _ = self._integrate(x, omega, half)
            return v / self.rowscale
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
        (the convention of :func:`mmshbm.methods.exact.periodic_orbit`), by Newton on the residual
        bordered with that condition. ``guess``: scaled unknowns (default the linear mode).
        Converged when the scaled residual is <= ``tol``, or <= √tol with the last Newton
        update below 1e-9 (relative): on strongly unstable orbits round-off in the
        integration leaves a residual floor above ``tol`` while Newton has converged. Far
        from the solution the Ω update is limited to 20 %. Returns the scaled unknowns;
        raises RuntimeError without convergence."""
        amplitude = check.positive("amplitude", amplitude)
        u = self.linear_point(amplitude) if guess is None else np.array(guess, dtype=float)
        # amplitude at t = 0 (open contact): -stop_side * (B x)[contact], a linear row in u
        row = -self.model.stop_side * self._B[self.ci] * self.xscale
        length = self.gap if self.gap > 0 else amplitude
        du_norm = np.inf
        for _ in range(max_iter):
            R, J = self.evaluate(u)
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

    # ------------------------------------------------------------------ trajectories
    def trajectory(self, u: np.ndarray):
        """The discrete orbit over one period at the N step instants.

        Returns
        -------
        t : ndarray (N,), s
        q_l, v_l : ndarray (N, n_l), positions and velocities of the DOFs with mass
            (``model.l`` order)
        lam : ndarray (N,), contact force (N)
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
        """(q_c (n_c, m), λ (m,)) from q_l (n_l, m) in ``model.l`` order."""
        ql = q_l[self.perm]
        lam = self.contact_stiffness * np.maximum(0.0, -(self.gap + self.a @ ql))
        return self._B @ ql + np.outer(self._e, lam), lam

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
        """(t (n_samples,) in s, λ (n_samples,) in N) over one period."""
        t, ql = self._resample(u, n_samples)
        return t, self._massless(ql)[1]

    def harmonic_content(self, u: np.ndarray, dof: int | None = None,
                         harmonics: int | None = None) -> np.ndarray:
        """|Q_k| for k = 0..harmonics of ``dof`` (default the contact DOF), from the DFT of
        the N step samples over one period; shape (harmonics+1,). ``harmonics`` defaults
        to min(10, N/2 − 1)."""
        dof = self.model.contact_dof if dof is None else check.integer("dof", dof)
        if not 0 <= dof < self.model.n_dof:
            raise ValueError(f"dof must be in [0, {self.model.n_dof - 1}], got {dof}")
        if harmonics is None:
            harmonics = min(10, self.N // 2 - 1)
        harmonics = check.integer("harmonics", harmonics, minimum=0)
        if harmonics > self.N // 2 - 1:
            raise ValueError(f"harmonics must be <= N/2 - 1 = {self.N // 2 - 1}, got {harmonics}")
        q = self._dof_at_steps(u, dof)
        c = np.fft.rfft(q) / self.N
        amp = 2 * np.abs(c[: harmonics + 1])
        amp[0] = abs(c[0].real)
        return amp

    def _dof_at_steps(self, u: np.ndarray, dof: int) -> np.ndarray:
        _, Q, _, lam = self.trajectory(u)
        model = self.model
        if dof in set(model.l.tolist()):
            return Q[:, int(np.searchsorted(model.l, dof))]
        qc, _ = self._massless(Q.T)
        return qc[int(np.searchsorted(model.c, dof))]

    # ------------------------------------------------------------------ monitor
    def energy(self, u: np.ndarray) -> float:
        """Energy (J) of the orbit's initial state: ½ xᵀ K_open x + ½ k_c min(0, h(x))²
        (velocities are zero at t = 0; this is ½ qᵀ K q over all DOFs)."""
        x, _ = self.unpack(u)
        q = x[self.perm]
        g = self.gap + self.a @ q
        return float(0.5 * q @ (self._K @ q) + 0.5 * self.contact_stiffness * min(0.0, g) ** 2)

    def monitor(self, u: np.ndarray) -> dict:
        """frequency (Hz), amplitude (m: largest excursion of the contact DOF away from the
        stop), energy (J), contact_force_max (N), closed_fraction (share of the steps with
        the contact closed), floquet_max (largest multiplier modulus; NaN when off)."""
        _, omega = self.unpack(u)
        away = -self.model.stop_side * self._dof_at_steps(u, self.model.contact_dof)
        lam = self.trajectory(u)[3]
        rec = {
            "frequency": omega / (2 * np.pi),
            "amplitude": _refined_max(away),
            "energy": self.energy(u),
            "contact_force_max": max(_refined_max(lam), 0.0) if lam.max() > 0 else 0.0,
            "closed_fraction": float(np.mean(lam > 0)),
            "floquet_max": float(np.abs(self.floquet_multipliers(u)[0])) if self.floquet else float("nan"),
        }
        return rec
