"""The MMS-HBM residual and its semi-analytic Jacobian (Schreyer, Peter & Leine).

Unknowns: the Fourier coefficients of the massless DOFs q_c and the fundamental frequency
Ω. The linear structure is condensed per harmonic (:mod:`mmshbm.harmonic.condense`):
F_k = D_k(Ω) a_k is the force the structure needs at the massless DOFs. The massless
DOFs are static, so at each of them that force comes from the stops alone:

    massless DOF without a stop:   F_k,i = 0,
    contact DOF (interval [lo, hi]):  proj_k[ f + r ((p − hi)₊ − (lo − p)₊) ] = 0,
                                      p = q − f/r,

the proximal form of the Signorini law on the interval of positions its stop(s) allow
(:mod:`mmshbm.methods.mms.contact_kernels`; one stop: [−inf, gap] or [−gap, inf], a clearance:
[−gap₋, gap₊]), whose zeros are exactly the complementarity pairs for any r > 0. Newton
iterates only in these numbers, however many DOFs the FE model has.

Projection. ``projection="exact"`` (default) locates the switching instants (zeros of the
degree-H trigonometric polynomial p − θ) and integrates each smooth piece in closed form:
the residual is C¹ in the unknowns and the sample count N only brackets zeros.
``projection="sampled"`` is the alternating frequency-time projection on N samples of
mmshbm 0.1 (a sample that switches is a kink: the branch has corners).

Autonomy and conservation. A time shift of a periodic solution is a solution, and for
a conservative system the anchored square system is degenerate along the whole family
(the energy-balance harmonic equation is implied by the others). mmshbm removes both at
once with a *cosine-only (time-symmetric) ansatz*: q_c(τ) = Σ_k a_k cos kτ. The system
is reversible (no damping, massless contact: no restitution), so the nonlinear modes
continued from the linear modes are symmetric about a turning point, where all
velocities vanish; putting that point at τ = 0 anchors the phase (only the discrete
half-period shift remains), and the residual of an even q_c is even, so its sine
projections vanish identically: the energy-balance identity, which lives in the sine
projections, drops out of the equations. What remains is (H+1)·n_c equations in
(H+1)·n_c + 1 unknowns with full row rank along the family: a regular one-parameter
branch that pseudo-arclength continuation follows with a well-conditioned bordered
Jacobian. The price: non-symmetric orbits are outside the ansatz.

All vectors handed to the continuation are scaled: coefficients by the first mode's
massless-DOF shape times the gap, Ω by the linear frequency, residual rows by the force
those scales produce.
"""

from __future__ import annotations

import numpy as np

from ... import _validate as check
from ...core._entry import compiled_entry
from ...core.problem import BackboneProblemBase, OneEvaluation
from ...harmonic._modal_kernels import _modal_dynamic_stiffness
from ...harmonic.condense import SingularDynamicStiffness, make_condensation
from ...harmonic.harmonics import check_harmonics
from ...model.model import Model
from . import _family_kernels
from . import corrector_kernels as ck
from .contact_kernels import _mmshbm_eval, _mmshbm_monitor_multi
from .family import FamilyMixin
from .fast import fast_data
from .fixed import _FIXED, _FIXED_CONTACTS, _FIXED_SCALING, _own, fixed_contacts, fixed_scaling, kept_entries
from .held import _held_frequency
from .krylov import KrylovCorrector, check_linear_solver, resolve_linear_solver
from .signals import SignalsMixin
from .tables import _tables, _tables_kept

__all__ = ["MMSHBMProblem"]

_PROJECTIONS = ("exact", "sampled")
#: the compiled corrector's statuses read on every call
_CONVERGED, _SKIPPED = ck.CONVERGED, ck.SKIPPED
#: 2π, the factor from Ω (rad/s) to the frequency (Hz) of the records
_TWO_PI = 2 * np.pi
#: most Ω whose condensed stiffness a problem keeps (:attr:`MMSHBMProblem._by_omega`), and
#: the most bytes they may take (fewer Ω for many contact DOFs)
_BY_OMEGA = 4096
_BY_OMEGA_BYTES = 64 << 20


class MMSHBMProblem(OneEvaluation, SignalsMixin, FamilyMixin, BackboneProblemBase):
    """MMS-HBM on a :class:`Model`, as a continuation problem.

    Parameters
    ----------
    model : Model
        The structure; every contact DOF must be massless.
    harmonics : int
        Highest harmonic H >= 1.
    n_samples : int, optional
        Time samples per period N >= 2H+1 (default :func:`default_n_samples`): the
        sampled projection's rule, the exact projection's bracketing grid.
    r : float, sequence of float or {"static", "residual"}, optional
        Proximal parameter (N/m), one for all contact DOFs or one each. Default
        ("static"): each contact DOF's condensed static stiffness (e_iᵀ D_0⁻¹ e_i)⁻¹.
        "residual": the inverse compliance of the modes above (H+1)·ω_ref, which the
        harmonics the series drops see (:mod:`~mmshbm.methods.mms.proximal`). The exact
        complementarity problem's solution does not depend on r; the truncated one does:
        with "residual" the series is cut in the smooth quasi-static position of the
        contact DOF instead of its own kinked one (5–90× smaller truncation errors on
        stiff contacts, docs/exact.md).
    mode : int
        Which linear mode (1-based) the branch starts from.
    backend : {"auto", "banded", "splu", "modal"}
        Linear solver of the condensation (:func:`~mmshbm.harmonic.condense.make_condensation`).
    projection : {"exact", "sampled"}
        Harmonic projection of the contact law (see the module docstring).
    linear_solver : {"auto", "dense", "krylov"}
        The corrector's linear solve. "dense": the LU of the whole bordered Jacobian (the
        compiled corrector on the modal back end; exact, O(((H+1) n_c)³) per iteration).
        "krylov": preconditioned GMRES with one n_c × n_c factorisation per harmonic
        (:mod:`~mmshbm.methods.mms.krylov`; the same points to the Newton tolerance, the
        sign of det [J; t] not tracked). "auto" (default): "krylov" from
        :data:`~mmshbm.methods.mms.krylov.KRYLOV_MIN_UNKNOWNS` (300) unknowns on
        ((H+1)·n_c + n_p + 1 with the pole unknowns; 32 contacts on the contact string
        at H = 5).
    poles : bool
        Carry the poles of D_k that the backbone's frequency range contains as extra
        unknowns η_jk (:mod:`mmshbm.methods.mms.condensation.poles`), so that kΩ = ω_j (an eigenfrequency
        of the structure with its massless DOFs clamped) is a regular point.

    Notes
    -----
    The scaled unknown vector is ``u = [a_0/s, a_1/s, ..., a_H/s, η/s_η, Ω/ω_ref]`` with
    a_k ∈ R^{n_c} (``model.c`` order), ``s`` the per-DOF length scale ``xscale`` and η
    the pole unknowns (``pole_set.pairs``; none when no pole lies in the range).
    """

    method = "mmshbm"
    setting_names = ("H", "N", "r", "mode")
    #: how the pole unknowns are scaled (:func:`~mmshbm.methods.mms.fixed`; recorded with a
    #: result and a checkpoint: files from before it was recorded scaled them by force)
    pole_scaling: str | None = None
    #: the continuation's step rule for this problem (ContinuationOptions.step_control="auto")
    step_control = "residual"
    #: the compiled corrector's data (:meth:`_fast_setup`): None until built, False when it does not apply
    _fast: dict | bool | None = None
    #: (J, t, x, sign) of the compiled corrector's last tangent solve (:meth:`solved_tangent`)
    _solved_tangent = None
    #: the Floquet solver of :func:`~mmshbm.methods.mms.stability.conservative_multipliers`; None until built
    _floquet_solver = None
    #: (fine τ, cos kτ on it) of :meth:`_fine_grid`; None until first used
    _fine: tuple | None = None
    #: the Newton–Krylov corrector (``linear_solver="krylov"``); None: the dense one
    krylov = None

    def __init__(self, model: Model, harmonics: int = 5, n_samples: int | None = None,
                 r=None, mode: int = 1, backend: str = "auto", projection: str = "exact", poles: bool = True,
                 linear_solver: str = "auto"):
        if not isinstance(model, Model):
            raise TypeError(f"model must be an mmshbm.Model, got {type(model).__name__}")
        model.require_massless_contacts("MMS-HBM")
        self.model = model
        self.H, self.N = check_harmonics(harmonics, n_samples)
        self.mode = check.integer("mode", mode, minimum=1)
        if self.mode > len(model.l):
            raise ValueError(f"mode must be <= the number of DOFs with mass ({len(model.l)}), "
                             f"got {self.mode}")
        if projection not in _PROJECTIONS:
            raise ValueError(f"projection must be one of {_PROJECTIONS}, got {projection!r}")
        self.projection = projection
        self.cond = make_condensation(model, backend, harmonics=self.H, mode=self.mode)
        self.n_c = len(model.c)
        check_linear_solver(linear_solver)
        # the numbers fixed by (model, H, N, mode, back end, projection, poles) with a named r
        # (the default, "static" or "residual"): computed once per model, each problem its own
        # copies
        named = r is None or isinstance(r, str)
        memo = _FIXED.setdefault(model, {}) if named else None
        key = (type(self), self.H, self.N, self.mode, backend, projection, bool(poles))
        if isinstance(r, str) and r != "static":
            key += (r,)
        fixed = memo.get(key) if memo is not None else None
        if fixed is None:
            fixed_contacts(self, model, r)
        else:
            for name in _FIXED_CONTACTS:
                setattr(self, name, _own(fixed[name]))
        #: compiled overloads shared with the problems built from the same kept numbers (None:
        #: this problem computed its own numbers and types its kernels' arguments itself)
        self._entries = kept_entries(fixed)

        self.pole_set = None
        if poles:
            from .condensation.poles import PoleSet

            self.pole_set = PoleSet(self.cond, model, self.H, self._omega_range())
        n_p = self.pole_set.n if self.pole_set is not None else 0
        self.n_poles = n_p
        self._pole_k = self.pole_set.k if n_p else np.zeros(0, dtype=np.int64)
        self._pole_groups = self.pole_set.groups if n_p else []
        self._pole_b = self.pole_set.b if n_p else np.zeros((0, self.n_c))
        self._pole_w2 = self.pole_set.omega2 if n_p else np.zeros(0)

        if fixed is None:
            fixed_scaling(self, n_p)
            if memo is not None:
                memo[key] = {name: _own(getattr(self, name)) for name in _FIXED_CONTACTS + _FIXED_SCALING}
        else:
            for name in _FIXED_SCALING:
                setattr(self, name, _own(fixed[name]))
        self.n_unknowns = (self.H + 1) * self.n_c + n_p + 1
        self.linear_solver = resolve_linear_solver(linear_solver, self.n_unknowns)

        H, N = self.H, self.N
        # sample grid, its cosine and sine tables (each problem its own copies: the kernels take
        # them as writable arrays); the fine grid for amplitude peaks and signals on first use
        tables = _tables(H, N)
        self._tau, self._cos_table, self._sin_table = (t.copy() for t in tables[:3])
        self._fine = None if _tables_kept(H, N) else tables[3:]  # computed for this problem: its own
        self._work = (np.empty((H + 1, self.n_c)), np.empty((H + 1, self.n_c)), np.empty(H + 1),
                      np.zeros(H + 1), np.empty(H + 1), np.empty(N), np.empty(N), np.empty(2 * N + 2),
                      np.empty(2 * H + 1), np.empty(2 * H + 1), np.empty(2 * H + 1), np.empty((H + 1, H + 1)))
        self._J_dummy = np.empty((1, 1))
        # work arrays of the monitor's kernel (its last four arguments; out (3,) last)
        self._monitor_work = (np.empty(H + 1), np.empty(H + 1), np.empty(N), np.empty(3))
        self._monitor_call = None
        self._monitor_args = None  # the monitor kernel's arguments fixed at construction, with its entry
        self._point_records = None  # the share records' compiled overloads and arguments, () where none
        # the condensed stiffness of the last Ω (the monitor of a converged point reuses
        # the one of Newton's last evaluation)
        self._cached = (None, None, None)
        #: Ω (rad/s) -> (D, dD) computed by :meth:`_condensed` or at a point the compiled
        #: corrector converged to (read only): what :meth:`condensed_many` takes instead of
        #: computing it again
        self._by_omega = {}
        self._by_omega_max = max(16, min(_BY_OMEGA, _BY_OMEGA_BYTES // (16 * (H + 1) * self.n_c ** 2)))
        #: residual (+ Jacobian) evaluations so far, the compiled corrector's included
        self.evaluations = 0
        self._modal = None  # open-contact modes for the energy shares (built on first use)
        self.krylov = KrylovCorrector(self) if self.linear_solver == "krylov" else None

    @property
    def _tau_fine(self) -> np.ndarray:
        """The fine grid τ (n_fine,) rad, n_fine = max(512, 8N) (:func:`~.tables._tables`)."""
        return self._fine_grid()[0]

    @property
    def _cos_fine(self) -> np.ndarray:
        """cos kτ (H+1, n_fine) on the fine grid."""
        return self._fine_grid()[1]

    def _fine_grid(self) -> tuple[np.ndarray, np.ndarray]:
        """(fine τ, cos kτ on it): copies of this problem's own, made on first use (a backbone
        needs neither; the amplitude peak's kernel and the signals on the fine grid do)."""
        fine = self._fine
        if fine is None:
            fine = self._fine = tuple(t.copy() for t in _tables(self.H, self.N)[3:])
        return fine

    # ------------------------------------------------------------------ unknowns
    def unpack(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """Scaled unknowns -> (cosine coefficients a (H+1, n_c) in m/rad, Ω in rad/s)."""
        return self._unpack_all(u)[:2]

    def _unpack_all(self, u: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
        """(a, Ω) of :meth:`unpack` and η (n_p,) of :meth:`unpack_eta` from one product
        (``colscale`` holds ``eta_scale`` at the pole unknowns: the same numbers)."""
        shape = u.shape if type(u) is np.ndarray else np.shape(u)
        if shape != (self.n_unknowns,):
            raise ValueError(f"u must have shape ({self.n_unknowns},), got {shape}")
        x = u * self.colscale
        n_h, n_c = self.H + 1, self.n_c
        n_a = n_h * n_c
        return x[:n_a].reshape(n_h, n_c), float(x[-1]), x[n_a:n_a + self.n_poles]

    def state_convention(self) -> dict:
        """``{"pole_scaling": ...}`` once the pole unknowns are scaled (see :attr:`pole_scaling`)."""
        return {"pole_scaling": self.pole_scaling} if self.pole_scaling else {}

    def states_from_force_scaling(self, states: np.ndarray) -> np.ndarray:
        """Scaled unknowns (n_points, n_unknowns) of a branch saved when the pole unknowns
        were scaled by the force alone (η/s_force) in this problem's scaling."""
        out = np.array(states, dtype=float, copy=True)
        if self.n_poles and out.ndim == 2 and out.shape[1] == self.n_unknowns:
            n_a = (self.H + 1) * self.n_c
            out[:, n_a:n_a + self.n_poles] *= self._eta_scale_force / self.eta_scale
        return out

    def unpack_eta(self, u: np.ndarray) -> np.ndarray:
        """The pole unknowns η (n_p,) of the scaled unknowns
        (see :mod:`mmshbm.methods.mms.condensation.poles`)."""
        n_a = (self.H + 1) * self.n_c
        return np.asarray(u, dtype=float)[n_a:n_a + self.n_poles] * self.eta_scale

    def pack(self, a: np.ndarray, omega: float, eta: np.ndarray | None = None) -> np.ndarray:
        """(a (H+1, n_c), Ω[, η]) -> scaled unknowns; η defaults to its value at that (a, Ω)
        (b_jᵀ a_k / (ω_j² − (kΩ)²))."""
        a = np.asarray(a, dtype=float)
        if eta is None:  # b_jᵀa_k/(ω_j² − (kΩ)²); 0 exactly on a pole (where b_jᵀa_k = 0 too)
            gap = self._pole_w2 - (self._pole_k * omega) ** 2
            ba = np.array([self._pole_b[p] @ a[k] for p, k in enumerate(self._pole_k)])
            eta = np.divide(ba, gap, out=np.zeros(len(gap)), where=gap != 0)
        return np.concatenate([a.ravel(), np.asarray(eta, dtype=float), [omega]]) / self.colscale

    def harmonic_columns(self, k: int) -> np.ndarray:
        """Indices in u of the unknowns of harmonic k: a_k and the η of its poles."""
        n_a = (self.H + 1) * self.n_c
        own = np.arange(k * self.n_c, (k + 1) * self.n_c)
        poles = n_a + np.flatnonzero(self._pole_k == k)
        return np.concatenate([own, poles]).astype(int)

    def linear_mode_point(self, amplitude: float) -> np.ndarray:
        """Scaled unknowns of the linear mode whose amplitude DOF swings ``amplitude``."""
        a = np.zeros((self.H + 1, self.n_c))
        a[1] = amplitude * self.mode_shape_c
        return self.pack(a, self.omega_ref)

    def initial_tangent(self) -> np.ndarray:
        """Unit tangent of the linear branch (growing amplitude, constant Ω)."""
        t = self.linear_mode_point(1.0)
        t[-1] = 0.0
        return t / np.linalg.norm(t)

    def _omega_range(self) -> tuple[float, float]:
        """Ω (rad/s) the backbone can reach: from the linear frequency up to the zero-gap
        (bilinear) limit of a single one-sided contact, else the frequency with every
        contact DOF held at its stop."""
        model = self.model
        if len(model.contacts) == 1 and model.contacts[0].dof == self.amplitude_dof and self.mode == 1:
            top = model.zero_gap_frequency()
        else:
            top = _held_frequency(model, self.contact_dofs, self.mode)
        return self.omega_ref, 2 * np.pi * max(top, self.linear_frequency)

    # ------------------------------------------------------------------ compiled corrector
    def _fast_setup(self):
        """Data of the compiled corrector (:mod:`mmshbm.methods.mms.corrector_kernels`), or False
        when it does not apply (a back end other than the modal one)."""
        fast = self._fast
        if fast is not None:
            return fast
        self._fast = fast = fast_data(self)
        return fast

    def fast_newton(self, u0, u_pred, tangent, tol: float, max_iter: int, step_tol: float):
        """Newton corrector on [R(u); t·(u − u_pred)] = 0 in one compiled loop (modal
        condensation only; None otherwise, and the continuation's Python loop runs).

        Returns (u, iterations, residual history, Jacobian at u), or raises ArithmeticError
        with the reason (the continuation's failure). With ``linear_solver="krylov"`` the
        Newton–Krylov corrector (:mod:`~mmshbm.methods.mms.krylov`) on any back end."""
        if self.krylov is not None:
            return self.krylov.newton(u0, u_pred, tangent, tol, max_iter, step_tol)
        fast = self._fast
        if fast is None:
            fast = self._fast_setup()
        if not fast:
            return None
        u = np.array(u0, dtype=float)
        hist = np.empty(max_iter + 1)
        u_pred = np.ascontiguousarray(u_pred, dtype=float)
        tangent = np.ascontiguousarray(tangent, dtype=float)
        call = fast.get("call")
        if call is None:  # the compiled overload, without the dispatcher's per-call typing
            args = (u, u_pred, tangent, float(tol), float(step_tol), int(max_iter), *fast["fixed"], hist,
                    *fast["data"])
            call = fast["call"] = (compiled_entry(ck._newton_modal, args, self._entries)
                                   if hasattr(ck._newton_modal, "compile") else ck._newton_modal)
        n_c, H = fast["fixed"]
        scale, cond, poles, law, samples, work, ework = fast["data"]
        status, it = call(u, u_pred, tangent, float(tol), float(step_tol), int(max_iter), n_c, H, hist,
                          scale, cond, poles, law, samples, work, ework)
        self.evaluations += it if status == _SKIPPED else it + 1
        self._solved_tangent = None
        if status == _CONVERGED or status == _SKIPPED:  # SKIPPED: D, J of the iterate before
            if status == _CONVERGED:  # the point's stiffness: its monitor's, and the branch's records'
                omega, D, dD = float(u[-1] * self.colscale[-1]), work.D.copy(), work.dD.copy()
                self._cached = (omega, D, dD)
                by_omega = self._by_omega
                if len(by_omega) >= self._by_omega_max:
                    by_omega.clear()
                by_omega[omega] = (D, dD)
            J = work.J.copy()
            tx = work.tx
            if len(tx) and work.t_info[0] == 0:
                self._solved_tangent = (J, tangent, tx.copy(), float(work.t_sign[0]))
            return u, int(it), hist[: it + 1], J
        if status == ck.POLE:  # the condensation's own message names the harmonic and the mode
            self._condensed(float(u[-1] * self.colscale[-1]), True)
        reason = {ck.NO_CONVERGENCE: f"no convergence in {max_iter} iterations (residual {hist[it]:.2e})",
                  ck.NON_FINITE: "non-finite residual", ck.SINGULAR: "singular Jacobian",
                  ck.POLE: "a harmonic of Ω sits on a fixed-interface eigenfrequency"}[status]
        raise ArithmeticError(reason)

    def solved_tangent(self, J, t_prev):
        """(x, sign of det [J; t_prevᵀ]) with [J; t_prevᵀ] x = e_n, when the compiled
        corrector solved it at its return: ``J`` the Jacobian it returned and ``t_prev`` the
        tangent it was given (the same objects); else None. Given once per corrector run
        (the caller may scale x in place)."""
        solved = self._solved_tangent
        if solved is None or solved[0] is not J or solved[1] is not t_prev:
            return None
        self._solved_tangent = None
        return solved[2], solved[3]

    # ------------------------------------------------------------------ residual
    def _condensed(self, omega: float, derivative: bool):
        """(D, dD) of :meth:`Condensation.dynamic_stiffness` at Ω (dD None unless
        ``derivative``), reusing the last result when Ω is the same number."""
        last, D, dD = self._cached
        if last == omega and (dD is not None or not derivative):
            return D, dD
        fast = self._fast
        if fast is None:
            fast = self._fast_setup()
        if fast:  # the modal kernel with the poles' terms left out and their static part added
            D0, B, w2, Rs, keep, static, rtol = fast["cond"]
            H = self.H
            shape = (H + 1, self.n_c, self.n_c)
            D = np.empty(shape)
            dD = np.empty(shape) if derivative else None
            call = fast.get("stiffness")
            if call is None:  # the kernel's overload typed once (its arguments' types are fixed)
                args = (D0, B, w2, Rs, float(omega), H, keep, rtol, D, D, bool(derivative))
                call = fast["stiffness"] = (compiled_entry(_modal_dynamic_stiffness, args, self._entries)
                                            if hasattr(_modal_dynamic_stiffness, "compile")
                                            else _modal_dynamic_stiffness)
            info = call(D0, B, w2, Rs, float(omega), H, keep, rtol, D, D if dD is None else dD,
                        bool(derivative))
            if info:
                k, j = divmod(info - 1, len(w2))
                raise SingularDynamicStiffness(
                    f"K_ll - ({k}·{omega:.6g} rad/s)^2 M_ll is singular: harmonic {k} of Ω sits on the "
                    f"fixed-interface eigenfrequency {np.sqrt(w2[j]):.9g} rad/s (mode index {j})")
            D += static
            self._cached = (omega, D, dD)
            if derivative:  # a converged point's (the monitor's): the branch's records use it again
                by_omega = self._by_omega
                if len(by_omega) >= self._by_omega_max:
                    by_omega.clear()
                by_omega[omega] = (D, dD)
            return D, dD
        if self.pole_set is not None and self.pole_set.n:
            D, dD = self.pole_set.dynamic_stiffness(omega, derivative)
        elif derivative:
            D, dD = self.cond.dynamic_stiffness(omega, self.H, derivative=True)
        else:
            D, dD = self.cond.dynamic_stiffness(omega, self.H, derivative=False), None
        self._cached = (omega, D, dD)
        return D, dD


    def _evaluate(self, u: np.ndarray, jacobian: bool):
        """Scaled residual ((H+1) n_c + n_p,) and, if asked, its Jacobian
        ((H+1) n_c + n_p, (H+1) n_c + n_p + 1). Counted in :attr:`evaluations`."""
        self.evaluations += 1
        a, omega = self.unpack(u)
        D, dD = self._condensed(omega, jacobian)
        R = np.empty(self.n_unknowns - 1)
        J = np.empty((self.n_unknowns - 1, self.n_unknowns)) if jacobian else self._J_dummy
        _mmshbm_eval(D, D if dD is None else dD, np.ascontiguousarray(a), self.unpack_eta(u), omega,
                     self._pole_k, self._pole_b, self._pole_w2, self.cdof, self.lo, self.hi, self.r_each,
                     self.projection == "exact", self._cos_table, self._sin_table, self._tau, self.rowscale,
                     self.colscale, jacobian, R, J, *self._work)
        return (R, J) if jacobian else R

    def monitor(self, u: np.ndarray) -> dict:
        """The per-point quantities of a backbone: frequency (Hz), amplitude (m), energy
        (J), contact_force_max (N), mode_share (share of the kinetic energy in the
        starting mode at the fundamental harmonic) and fundamental_share (share of the
        kinetic energy in the fundamental harmonic: what makes a point a member of the
        starting mode's family, rather than an internal resonance) and mode_leads (the
        definition's third condition, :meth:`mode_leads`). The
        table of every tracked mode and harmonic, ``modal_shares``, is added for the whole
        branch at the end (:meth:`branch_records`)."""
        a, omega, eta = self._unpack_all(u)
        cond = self.cond
        if cond.backend == "modal" and not cond.complete:  # with every mode kept nothing is left out
            cond.check_range(omega, self.H)  # warns once past the modes kept
        D, dD = self._condensed(omega, True)
        a = np.ascontiguousarray(a)
        work = self._monitor_work
        row = self._amplitude_row(a, omega, eta)
        call = self._monitor_call
        if call is not None:  # the compiled overload with the arguments it was typed for
            contacts, tables = self._monitor_args
            call(D, dD, a, eta, *contacts, omega, row, *tables)
        else:
            contacts = (self._pole_k, self._pole_b, self.cdof, self.lo, self.hi, self.r_each)
            tables = (self._amp_sign, self._cos_table, self._sin_table, *work)
            args = (D, dD, a, eta, *contacts, omega, row, *tables)
            call = _mmshbm_monitor_multi
            if self._fast and hasattr(_mmshbm_monitor_multi, "compile"):
                # the compiled corrector's problems (modal back end) pass arrays of fixed types
                # (C-contiguous float64, made here or by the corrector): the compiled overload
                # is typed once, and the arguments fixed at construction are kept with it;
                # others go through the dispatcher
                self._monitor_call = compiled_entry(_mmshbm_monitor_multi, args, self._entries)
                self._monitor_args = (contacts, tables)
            call(*args)
        amplitude, energy, force = work[-1].tolist()
        shares = self._point_records
        if shares is None:
            shares = self._point_records_setup()
        if not shares:
            return {"frequency": omega / (2 * np.pi), "amplitude": amplitude, "energy": energy,
                    "contact_force_max": force, "mode_share": self._mode_share_at(u, a, omega, eta, dD),
                    **self._family_records_at(a, omega, eta, dD), "mode_leads": self.mode_leads(u, omega)}
        # the compiled corrector's problems: the share kernels' overloads typed once
        share_call, share_args, family_call, family_args, records = shares
        share = share_call(a, eta, omega, dD, self._pole_k, *share_args)
        family_call(a, dD, eta, self._pole_k, omega, *family_args)
        fundamental, harmonic, mode, detuning = records.tolist()
        return {"frequency": omega / _TWO_PI, "amplitude": amplitude, "energy": energy,
                "contact_force_max": force, "mode_share": float(share), "fundamental_share": fundamental,
                "resonance_harmonic": harmonic, "resonance_mode": mode, "resonance_detuning": detuning,
                "mode_leads": self.mode_leads(u, omega)}

    def _point_records_setup(self):
        """(entry, arguments after pole_k, entry, arguments after Ω, records (4,)): the
        compiled overloads of the starting mode's share (``_start_mode_share``) and of the
        family records (``_family_kernels._family_records``) for the compiled corrector's
        problems (modal back end); () for the others."""
        shares, fast = (), self._fast_setup()
        if fast and hasattr(ck._start_mode_share, "compile"):
            _, s0, s, sv, pole_j = self._share_setup()
            _, B, w2, _, keep, _, _ = fast["cond"]
            records = np.empty(4)
            share_args = (pole_j, self._pole_w2, B, w2, keep, s0, s, sv)
            family_args = (np.ascontiguousarray(self._modal_basis()[0], dtype=float), np.empty(self.H + 1),
                           records)
            a = np.zeros((self.H + 1, self.n_c))  # arguments of the monitor's types
            dD, eta = np.zeros((self.H + 1, self.n_c, self.n_c)), np.zeros(self.n_poles)
            share = compiled_entry(ck._start_mode_share, (a, eta, 0.0, dD, self._pole_k, *share_args),
                                   self._entries)
            family = compiled_entry(_family_kernels._family_records,
                                    (a, dD, eta, self._pole_k, 0.0, *family_args), self._entries)
            shares = (share, share_args, family, family_args, records)
        self._point_records = shares
        return shares

