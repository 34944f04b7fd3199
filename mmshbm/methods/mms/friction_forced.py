"""Forced responses by MMS-HBM of structures with Coulomb friction at massless DOFs.

The structure of :class:`~mmshbm.model.Model` with damping C (optional: friction alone
damps it), a harmonic force on the DOFs with mass, unilateral contacts (optional) and
friction contacts with constant normal load on massless DOFs,

    M q'' + C q' + K q = Σ w_i λ_i − Σ e_t f_t + Re(F̂ e^{iΩt}),
    f_t = clip(f_t + r u̇_t, −s_t, s_t),   s_t = μ_t N_t,   u_t = q[dof_t],

f_t the force node t exerts on its support (:mod:`mmshbm.contact.coulomb`). The ansatz,
unknowns and condensation are those of :class:`~mmshbm.methods.mms.forced.ForcedResponseProblem`
(the full cosine/sine series of the massless DOFs, F = 𝔇(Ω) x − P the force the structure
needs there, so f_t = −F_t; the support's force on node t is F_t). Each friction DOF's
2H+1 rows are the Coulomb law projected exactly on harmonics 0..H, in one of two
equivalent forms (``law=``), both with ρ = 1/(K_cc⁻¹)_tt, the node's stiffness with the
DOFs with mass held (N/m):

* ``"play"`` (default), displacement level: with y = u_t − F_t/ρ (= wᵀq_l when no other
  massless DOF is loaded: where the free node would sit, as smooth as the motion of the
  DOFs with mass), Coulomb's law says that
  u_t is the play operator of y of half-width s/ρ (the time integral of the proximal
  equation), so R_t = F_t − proj[ρ (Play(y) − y)] = 0
  (:func:`~mmshbm.contact.coulomb.project_coulomb_play`: extrema of y and stick-to-slip
  instants located as zeros of trigonometric polynomials, closed-form integrals, exact
  Jacobian);
* ``"velocity"``, the velocity-level proximal equation
  R_t = F_t + proj[clip(−F_t + ρ u_t′, −s, s)] = 0, u_t′ = d u_t/dτ = u̇_t/Ω (physical
  parameter r = ρ/Ω, N·s/m) (:func:`~mmshbm.contact.coulomb.project_coulomb`, exact
  projection and Jacobian ∂R/∂F = G, ∂R/∂u′ = ρ (I − G), G the projection of the slip
  indicator [|p| > s]).

Both have the exact law's solutions as H → ∞; they differ in how fast they get there. The
velocity form asks the truncated u_t, which has kinks at every stick-to-slip switch, to
have zero velocity on the stick arcs in the Galerkin sense: on the Jenkins oscillator of
the tests its largest displacement is still 0.5–1.3 % off the exact orbit at H = 31. The
play form evaluates the law exactly on the smooth y and is 5e-7 off at H = 31 (7e-5 at
H = 7) on the same orbit (docs/friction.md).

Full stick. Where node t sticks over the whole period its position is history, not a
steady state (the velocity form's mean row vanishes identically). Both forms take the
symmetric position: mean friction force zero (the play form: u_t = mean(y) when that
keeps |F_t| <= s; the velocity form replaces its mean row by F_t,0 = 0), the limit of the
slipping orbits of a symmetric structure under a harmonic force as the slip vanishes.

Impact with friction (``normal_contact=j``): the slip force s(τ) = μ (N0 + λ_j(τ)) with
λ_j = r_j (side·p_j − gap)₊ the proximal contact force of unilateral contact j (a
trigonometric polynomial on its closed arcs, 0 on the open ones, continuous); the play form
with a time-varying half-width s/ρ (:mod:`mmshbm.contact.coulomb_coupled`), its Jacobian
including ∂s/∂(the normal contact's coefficients). Play form only.

Evaluation. The play form with constant slip forces runs compiled: the fused unilateral
residual, then the friction rows in place (:mod:`mmshbm.methods.mms._friction_kernels`);
the coupled and velocity forms assemble their rows in NumPy
(:meth:`~mmshbm.methods.mms.friction_rows.FrictionRows.contact_residual`). Where moreover
the amplitude DOF's harmonic 1 is tracked with the dense blocks and the condensation is
modal, the whole scaled residual and Jacobian, and each point's records, are one compiled
call each (:mod:`mmshbm.methods.mms.friction_fused`; ``_fused = False`` takes the steps
above, its reference).

Floquet multipliers (``stability=True``, :mod:`mmshbm.methods.mms.friction_stability`), play
form. Not yet: the velocity form with ``normal_contact=`` or with stability
(NotImplementedError).
"""

from __future__ import annotations

import numpy as np

from ...core.measures import mean_energy
from ...model.model import Model
from .condensation.damped_condense import DENSE_LIMIT
from .corrector import at_roundoff, backtrack, corrector_to_roundoff
from .forced import ForcedResponseProblem
from .friction_fused import fused_evaluation
from .friction_rows import FrictionRows, check_friction_model, check_law
from .friction_tracked import TrackedHarmonic

__all__ = ["FrictionRows", "FrictionForcedProblem", "check_friction_model", "check_law"]



class FrictionForcedProblem(FrictionRows, ForcedResponseProblem):
    """MMS-HBM forced response of a model with Coulomb friction, continued in (x, Ω).

    Parameters
    ----------
    model : Model
        With at least one friction contact (``model.with_friction``, constant normal load);
        unilateral contacts and viscous damping optional.
    force, harmonics, n_samples, backend, projection
        As :class:`~mmshbm.methods.mms.forced.ForcedResponseProblem`.
    r : float, optional
        Proximal parameter of the unilateral contacts (N/m); the friction contacts use
        ρ = 1/(K_cc⁻¹)_tt, the node's stiffness with the DOFs with mass held.
    stability : bool or "auto"
        True: Floquet multipliers at every point (:mod:`~mmshbm.methods.mms.friction_stability`;
        play form, NotImplementedError otherwise). "auto" and False skip them.
    law : {"play", "velocity"}
        The form of the friction rows (module docstring); "play" needs the exact projection.
    linear_solver : {"auto", "dense", "krylov"}
        The corrector's linear solves: "dense" LU, or "krylov", GMRES preconditioned by one
        factorisation per harmonic (:mod:`~mmshbm.methods.mms.forced_krylov`; the same
        points to the Newton tolerance, det [J; t]'s sign not tracked; with constant slip
        forces and no unilateral contacts the Jacobian is then never assembled,
        :mod:`~mmshbm.methods.mms.forced_operator`). "auto" (default):
        "krylov" from :data:`~mmshbm.methods.mms.forced_krylov.FORCED_KRYLOV_MIN_UNKNOWNS`
        unknowns on (:data:`~mmshbm.methods.mms.forced_krylov.FORCED_MATRIX_FREE_MIN_UNKNOWNS`
        where the Jacobian is an operator).

    Notes
    -----
    Records per point, besides those of the unilateral problem: ``slip_fraction`` (the
    largest fraction of the period any friction node slips, 0 in full stick) and
    ``friction_dissipation`` (J per period, Σ_t ∮ f_t u̇_t dt of the degree-H signals).
    The length scale of the unknowns is the static response of the structure with free
    friction nodes to the force. When the amplitude DOF carries mass, harmonic 1 of it is
    carried as two more unknowns (scaled u = [x, a_1, b_1, Ω]) with rows equating them to
    their recovery from x: a stuck node's coefficients vanish, and without them the
    arclength would not see (and step over) the resonances of the stuck structure.
    """

    #: the continuation crosses corners of the branch at fixed frequency
    #: (:func:`mmshbm.core.steps._corner_step`): where stick arcs appear or vanish the
    #: tangent can turn by more than 90° within 1e-5 Hz (107° on the tip damper at H = 7)
    corner_parameter = True
    #: the Floquet solver of the normal contacts' phases; None until built
    _normal_floquet = None
    #: the compiled evaluation (:class:`~mmshbm.methods.mms.friction_fused.FusedFrictionEvaluation`):
    #: None until first asked, False where the problem is not of the kind it evaluates
    _fused = None
    #: :meth:`start_point` above this many harmonics first solves at half as many (recursively)
    #: and starts Newton from that solution, its higher harmonics zero: from the linear or
    #: stuck response Newton does not reach the stick arcs of a lap joint's lightly loaded
    #: pairs at H = 25 to 33 (it returns the stuck point), from the solution at H/2 it does
    start_ladder_harmonics = 8
    #: the corrector's Newton loop compiled where the evaluation is fused
    #: (:meth:`~mmshbm.methods.mms.friction_fused.FusedFrictionEvaluation.correct`); False:
    #: the Python loop (:func:`~mmshbm.methods.mms.corrector.corrector_to_roundoff`), its reference
    compiled_corrector = True

    def __init__(self, model: Model, force, harmonics: int = 5, n_samples: int | None = None,
                 r: float | None = None, backend: str = "auto", stability: bool | str = "auto",
                 projection: str = "exact", law: str = "play", linear_solver: str = "auto"):
        check_friction_model(model, coupled_ok=True)
        check_law(law, projection)
        if not (stability is True or stability is False or stability == "auto"):
            raise ValueError(f"stability must be True, False or 'auto', got {stability!r}")
        if stability is True and law != "play":
            raise NotImplementedError("Floquet multipliers with friction take the stick arcs of the play "
                                      "form: pass law='play'")
        super().__init__(model, force, harmonics, n_samples, r, backend, False, projection)
        # what a problem at fewer harmonics needs (:meth:`fewer_harmonics`)
        self._options = {"force": force, "r": r, "backend": backend, "projection": projection, "law": law,
                         "linear_solver": linear_solver}
        self._init_friction(model, law, projection)
        if stability is True:
            from .friction_stability import FrictionFloquet, ImpactFrictionFloquet

            self._floquet = ImpactFrictionFloquet(model) if model.contacts else FrictionFloquet(model)
            self.stability = True
        self._rescale(self._static_length(), 1)
        # harmonic 1 of the amplitude DOF (when it carries mass) as two more unknowns
        hit = np.flatnonzero(model.l == self.amplitude_dof)
        self._track = int(hit[0]) if len(hit) else None
        self._tracker = None
        self._tracked_dx = None  # (z, ∂(cos, sin)/∂x) of the last Ω the tracker was asked
        self._dense_km = None
        if self._track is not None and self.cond.n_l <= DENSE_LIMIT:
            self._tracker = TrackedHarmonic(model.blocks, self._track, self.force_l)
        if self._track is not None:
            self.colscale = np.concatenate([self.xscale, [self.length, self.length, self.omega_ref]])
            self.n_unknowns = self.n_x + 3
        self._init_linear_solver(linear_solver)

    def _init_linear_solver(self, linear_solver: str) -> None:
        """The corrector's linear solves: the dense LU, or GMRES with the harmonics' blocks
        (:mod:`~mmshbm.methods.mms.forced_krylov`, which then also solves the tangent)."""
        from .forced_krylov import ForcedKrylovSolver, resolve_forced_solver
        from .forced_operator import supports_matrix_free

        # the Jacobian as an operator where its structure allows (mmshbm.methods.mms.forced_operator)
        operator = supports_matrix_free(self)
        self.linear_solver = resolve_forced_solver(linear_solver, self.n_unknowns, operator)
        self._krylov = ForcedKrylovSolver(self.n_c, self.H) if self.linear_solver == "krylov" else None
        self._matrix_free = self._krylov is not None and operator
        if self._krylov is not None:
            self.solved_tangent = self._krylov.tangent

    # ------------------------------------------------------------------ unknowns
    def unpack(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """Scaled unknowns -> (x (n_x,) in m/rad, Ω in rad/s); the tracked harmonic of the
        amplitude DOF is dropped (it follows from x and Ω)."""
        if self._track is None:
            return super().unpack(u)
        if np.shape(u) != (self.n_unknowns,):
            raise ValueError(f"u must have shape ({self.n_unknowns},), got {np.shape(u)}")
        y = np.asarray(u, dtype=float) * self.colscale
        return y[:self.n_x], float(y[-1])

    def pack(self, x: np.ndarray, omega: float) -> np.ndarray:
        if self._track is None:
            return super().pack(x, omega)
        ab = self._tracked(np.asarray(x, dtype=float), omega)[0]
        return np.concatenate([x, ab, [omega]]) / self.colscale

    def _tracked(self, x: np.ndarray, omega: float, derivative: bool = False):
        """(cos, sin) of harmonic 1 of the amplitude DOF (m), ∂/∂x (2, n_x) and, with
        ``derivative``, ∂/∂Ω (2,) (else None).

        Q̂ = −z·Û_1 + σ y, z the amplitude DOF's row of Z_1 = S_1⁻¹K_lc, y its row of
        S_1⁻¹F̂_l (:class:`~mmshbm.methods.mms.friction_tracked.TrackedHarmonic`, exact
        derivatives; above DENSE_LIMIT DOFs with mass from the condensation's recovery and
        central differences in Ω, step 1e-6 Ω)."""
        s, ds = self.excitation.scale(omega)
        if self._tracker is not None:
            z, y, dz, dy = self._tracker.at(omega, derivative)
        else:
            ch = self._condensed(omega, recover=True)
            z, y, dz, dy = ch.Z[1][self._track], ch.Y[self._track, 0], None, None
        n_c = self.n_c
        Uc, Us = x[n_c:2 * n_c], x[2 * n_c:3 * n_c]
        U = Uc - 1j * Us
        q = -z @ U + s * y
        memo = self._tracked_dx
        if memo is not None and memo[0] is z:  # z is the tracker's array for this Ω
            dx = memo[1]
        else:
            dx = np.zeros((2, self.n_x))
            dx[0, n_c:2 * n_c], dx[0, 2 * n_c:3 * n_c] = -z.real, -z.imag
            dx[1, n_c:2 * n_c], dx[1, 2 * n_c:3 * n_c] = z.imag, -z.real
            dx.flags.writeable = False
            if self._tracker is not None:
                self._tracked_dx = (z, dx)
        dw = None
        if derivative and dz is not None:
            dq = -dz @ U + ds * y + s * dy
            dw = np.array([dq.real, -dq.imag])
        elif derivative:
            h = 1e-6 * omega
            dw = (self._tracked(x, omega + h)[0] - self._tracked(x, omega - h)[0]) / (2 * h)
            self._condensed(omega, 0.0, True, recover=True)  # back to Ω in the cache
        return np.array([q.real, -q.imag]), dx, dw

    def _evaluate(self, u: np.ndarray, jacobian: bool):
        """Scaled residual and, if asked, its Jacobian; with the amplitude DOF tracked, two
        more rows (its harmonic-1 unknowns equal their recovery from x, :meth:`_tracked`).
        With the Krylov solves and constant slip forces the Jacobian is an operator
        (:func:`~mmshbm.methods.mms.forced_operator.evaluate_matrix_free`)."""
        if self._matrix_free:
            from .forced_operator import evaluate_matrix_free

            return evaluate_matrix_free(self, u, jacobian)
        if self._track is None:
            return super()._evaluate(u, jacobian)
        if self._fused is None:
            self._fused = fused_evaluation(self)
        if self._fused is not False and self._compiled_rows:
            return self._fused.evaluate(u, jacobian)
        x, omega = self.unpack(u)
        ab = np.asarray(u[self.n_x:self.n_x + 2], dtype=float) * self.length
        R_x, Jx, Jw = self._parts(x, omega, jacobian)
        rec, drec, dw = self._tracked(x, omega, jacobian)
        n_x = self.n_x
        R = np.empty(n_x + 2)
        np.divide(R_x, self.rowscale, out=R[:n_x])
        R[n_x:] = (ab - rec) / self.length
        if not jacobian:
            return R
        if self._jscale is None:  # the scaling of the x columns: xscale_j / rowscale_i
            self._jscale = self.xscale[None, :] / self.rowscale[:, None]
        J = np.empty((n_x + 2, self.n_unknowns))
        np.multiply(Jx, self._jscale, out=J[:n_x, :n_x])
        J[:n_x, n_x:n_x + 2] = 0.0
        J[:n_x, -1] = Jw * self.omega_ref / self.rowscale
        J[n_x:, :n_x] = -drec * self.xscale[None, :] / self.length
        J[n_x:, n_x:n_x + 2] = np.eye(2)
        J[n_x:, -1] = -dw * self.omega_ref / self.length
        return R, J

    def _parts(self, x: np.ndarray, omega: float, jacobian: bool):
        """:meth:`ForcedResponseProblem.residual_parts` at σ = 1 without the σ column:
        R (n_x,) and, if asked, ∂R/∂x (n_x, n_x) and ∂R/∂Ω (n_x,) (else None)."""
        ch = self._condensed(omega, 0.0, jacobian)
        s, ds = self.excitation.scale(omega)
        Pv = self.first_harmonic_vector(s * ch.P[:, 0])
        if not jacobian:
            return self.fused_residual(ch.D, x, Pv)[0], None, None
        dload = self.first_harmonic_vector(s * ch.dP_domega[:, 0] + ds * ch.P[:, 0])[:, None]
        R, Jx, Jp = self.fused_residual(ch.D, x, Pv, ch.dD_domega[None], dload)
        return R, Jx, Jp[:, 0]

    def _static_length(self) -> float:
        """The static response (m) to the force, friction nodes free (1 if it is zero)."""
        import scipy.sparse.linalg as spla

        s, _ = self.excitation.scale(self.omega_ref)
        F_l = s * self.force_l
        K_red = self.model.reduced_stiffness.tocsc()
        stat = [spla.spsolve(K_red, part) for part in (F_l.real, F_l.imag) if np.any(part)]
        length = max(float(np.abs(q).max()) for q in stat)
        return length if length > 0 else 1.0

    # ------------------------------------------------------------------ start
    def stuck_point(self, frequency: float) -> np.ndarray:
        """Scaled unknowns of the linear response with every friction node held at 0
        (the full-stick orbit in the symmetric position)."""
        omega = 2 * np.pi * frequency
        ch = self._condensed(omega)
        s, _ = self.excitation.scale(omega)
        free = np.setdiff1d(np.arange(self.n_c), self.friction_rows)
        Qc = np.zeros(self.n_c, dtype=complex)
        if len(free):
            Qc[free] = np.linalg.solve(ch.D[1][np.ix_(free, free)], s * ch.P[free, 0])
        x = np.zeros(self.n_x)
        x[self.n_c:2 * self.n_c] = Qc.real
        x[2 * self.n_c:3 * self.n_c] = -Qc.imag
        return self.pack(x, omega)

    def solve_at(self, frequency: float, guess: np.ndarray, max_iter: int = 50, tol: float = 1e-11):
        """Newton at fixed Ω from the scaled ``guess``, with a backtracking line search on
        max|R/rowscale|: (scaled unknowns, converged). Converged: the scaled residual is
        <= ``tol`` and Newton has reached the solve's round-off
        (:func:`~mmshbm.methods.mms.corrector.at_roundoff`)."""
        x, omega = self.unpack(guess)
        omega = 2 * np.pi * frequency
        xs = self.xscale

        def merit(x):
            R = self.residual_parts(x, omega, 1.0, False)[0]
            return float(np.abs(R / self.rowscale).max()), R

        r, R = merit(x)
        for _ in range(max_iter):
            if not np.isfinite(r):
                return guess, False
            if self._matrix_free:
                from .forced_operator import square_operator

                Jx = square_operator(self, x, omega)[1]
            else:
                _, Jx, _, _ = self.residual_parts(x, omega, 1.0, True)
            if self._krylov is not None:
                dx = self._krylov.square_solve(Jx, -R)
            else:
                try:
                    dx = np.linalg.solve(Jx, -R)
                except np.linalg.LinAlgError:
                    dx = np.linalg.lstsq(Jx, -R, rcond=None)[0]
            if r <= tol:
                done, x, r, R = at_roundoff(merit, x, dx, r, R, xs)
                if done:
                    return self.pack(x, omega), True
                continue
            x, r, R, ok = backtrack(merit, x, dx, r)
            if not ok:
                return self.pack(x, omega), False
        return self.pack(x, omega), r <= tol

    def fast_newton(self, u, u_pred, tangent, tol, max_iter, step_tol):
        """The continuation's corrector on [R(u); t·(u − u_pred)] = 0, globalised: each Newton
        step is halved until the merit max(|R|, |t·(u − u_pred)|) (scaled) decreases. The
        friction rows are semismooth, and where a node sticks only briefly (a stiff node,
        slip over > 99 % of the period) plain Newton cycles. Stopped at the solve's round-off
        (:func:`~mmshbm.methods.mms.corrector.corrector_to_roundoff`: the residual alone does
        not bound the error where the friction rows are weak, condition numbers of 1e7 and
        more). Returns (u, iterations, residual history, Jacobian); raises RuntimeError when
        it does not converge. Where the evaluation is fused and the bordered system small,
        the whole loop is one compiled call
        (:meth:`~mmshbm.methods.mms.friction_fused.FusedFrictionEvaluation.correct`; the
        same steps and tests, ``compiled_corrector = False`` keeps the Python loop)."""
        compiled = self.compiled_corrector and self._krylov is None and self._track is not None
        if compiled and self._compiled_rows:
            if self._fused is None:
                self._fused = fused_evaluation(self)
            if self._fused is not False and self._fused.corrects(self.n_unknowns):
                return self._fused.correct(u, u_pred, tangent, tol, max_iter, step_tol)
        solve = self._krylov.bordered_solve if self._krylov is not None else None
        return corrector_to_roundoff(self, u, u_pred, tangent, tol, max_iter, step_tol, solve)

    def fewer_harmonics(self, harmonics: int | None = None) -> FrictionForcedProblem:
        """The same problem at h = ``harmonics`` (default H // 2) harmonics, 1 <= h < H
        (ValueError otherwise), its time sampling the default."""
        h = self.H // 2 if harmonics is None else int(harmonics)
        if not 1 <= h < self.H:
            raise ValueError(f"harmonics must be in [1, {self.H - 1}], got {h}")
        return type(self)(self.model, harmonics=h, **self._options)

    def from_fewer_harmonics(self, low: FrictionForcedProblem, u_low: np.ndarray,
                             frequency: float) -> np.ndarray:
        """Scaled unknowns at ``frequency`` (Hz) whose harmonics 0..h are those of ``u_low``,
        scaled unknowns of ``low`` (the same problem at h <= H harmonics,
        :meth:`fewer_harmonics`), the higher ones zero: a guess for :meth:`solve_at`."""
        if low.n_c != self.n_c or low.H > self.H:
            raise ValueError(f"low must be the same problem at <= {self.H} harmonics")
        x_low, _ = low.unpack(u_low)
        x = np.zeros((self.n_coef, self.n_c))
        x[:low.n_coef] = x_low.reshape(low.n_coef, low.n_c)
        return self.pack(x.ravel(), 2 * np.pi * frequency)

    def start_point(self, frequency: float, max_iter: int = 50, tol: float = 1e-11) -> np.ndarray:
        """Converged unknowns at ``frequency`` (Hz) by Newton from the free-slip, then the
        full-stick linear response, then (with unilateral contacts) the force ramped up from
        a level that keeps the stops open (the first that converges); the stuck response when
        none does (the continuation's first corrector then tries). Above
        :attr:`start_ladder_harmonics` harmonics Newton starts first from the solution at
        half as many (:meth:`fewer_harmonics`). ``tol`` as :meth:`solve_at`."""
        guesses = [self.linear_response_point, self.stuck_point]
        if self.H > self.start_ladder_harmonics:
            def ladder(f):
                low = self.fewer_harmonics()
                return self.from_fewer_harmonics(low, low.start_point(f, max_iter, tol), f)

            guesses.insert(0, ladder)
        if self.model.contacts:  # the force raised from a level that keeps the stops open
            guesses.append(lambda f: ForcedResponseProblem.start_point(self, f))
        for guess in guesses:
            u, ok = self.solve_at(frequency, guess(frequency), max_iter, tol)
            if ok:
                return u
        return self.stuck_point(frequency)

    # ------------------------------------------------------------------ results
    def _multipliers(self, Q: np.ndarray, omega: float) -> np.ndarray:
        """Floquet multipliers (2 n_l + m,) of the orbit with coefficients Q (n_dof, 2H+1):
        the phases from each node's stick arcs (:mod:`mmshbm.methods.mms.friction_stability`)."""
        from ...contact.coulomb import play_pieces
        from ...contact.coulomb_coupled import coupled_play_pieces
        from .friction_stability import merge_phases

        x = np.ascontiguousarray(Q[self.model.c].T).ravel()
        F = self._needed(x, omega, 1.0)
        pieces = []
        for j, i in enumerate(self.friction_rows):
            idx = self._coef_index[i]
            y = x[idx] - F[idx] / self.rho[j]
            if self.coupling[j] is None:
                pc = play_pieces(y, self.slip_force[j], self.rho[j])
            else:
                k, side, gap, mu, preload = self.coupling[j]
                idx_n = self._coef_index[self.contact_rows[k]]
                z = side * (x[idx_n] - F[idx_n] / self.r[k])
                pc = coupled_play_pieces(y, z, mu * preload / self.rho[j], mu * self.r[k] / self.rho[j], gap)
            pieces.append([(p[0], p[1], p[2]) for p in pc])
        if not self.model.contacts:
            return self._floquet.multipliers([[(a, b) for a, b, sg in pc if sg == 0] for pc in pieces], omega)
        from .stability import FloquetSolver

        if self._normal_floquet is None:
            self._normal_floquet = FloquetSolver(self.model)
        normal = self._normal_floquet.phases(Q[self.model.l])
        return self._floquet.multipliers(merge_phases(normal, pieces), omega)

    def _record(self, x: np.ndarray, omega: float, sigma: float) -> dict:
        if self.stability:
            rec = super()._record(x, omega, sigma)
            rec.update(self.friction_records(x, omega, sigma))
            return rec
        # the records of ForcedResponseProblem._record and friction_records, the force the
        # structure needs computed once (in one compiled call where the evaluation is fused)
        parts = self._fused_record(x, omega, sigma)
        if parts is not None:
            F, Q, energy, slip, work = parts
            q = Q[self.amplitude_dof]
            return {"frequency": omega / (2 * np.pi), "amplitude": self.amplitude(q), "phase": self.phase(q),
                    "energy": energy, "contact_force_max": self.contact_force_max(x, F),
                    "slip_fraction": slip, "friction_dissipation": work}
        Q = self._coefficients(x, omega, sigma)
        q = Q[self.amplitude_dof]
        F = self._needed(x, omega, sigma)
        slip, work = self.slip_and_work(x, F)
        return {"frequency": omega / (2 * np.pi), "amplitude": self.amplitude(q), "phase": self.phase(q),
                "energy": self._energy(Q, omega), "contact_force_max": self.contact_force_max(x, F),
                "slip_fraction": slip, "friction_dissipation": work}

    def _fused_record(self, x: np.ndarray, omega: float, sigma: float):
        """:meth:`FusedFrictionEvaluation.record_parts
        <mmshbm.methods.mms.friction_fused.FusedFrictionEvaluation.record_parts>` where the
        evaluation is fused (and the friction rows compiled), else None."""
        if self._track is None or not self._compiled_rows:
            return None
        if self._fused is None:
            self._fused = fused_evaluation(self)
        return None if self._fused is False else self._fused.record_parts(x, omega, sigma)

    def _energy(self, Q: np.ndarray, omega: float) -> float:
        """:func:`~mmshbm.core.measures.mean_energy` of Q (n_dof, 2H+1) at Ω, with dense K and
        M where the dense blocks are held (small models: the sparse products cost more)."""
        if self._tracker is None:
            return mean_energy(self.model, Q, omega)
        if self._dense_km is None:
            self._dense_km = (np.ascontiguousarray(self.model.K.toarray()),
                              np.ascontiguousarray(self.model.M.toarray()))
        K, M = self._dense_km
        KQ = np.einsum("ij,ij->j", Q, K @ Q)
        MQ = np.einsum("ij,ij->j", Q[:, 1:], M @ Q[:, 1:])
        k2 = np.repeat(np.arange(1, self.H + 1), 2) ** 2
        return float(0.5 * KQ[0] + 0.25 * KQ[1:].sum() + 0.25 * omega**2 * (k2 @ MQ))

    def _coefficients(self, x: np.ndarray, omega: float, sigma: float) -> np.ndarray:
        """NLvib-ordered coefficients of all DOFs (n_dof, 2H+1): the DOFs with mass recovered
        by one batched solve with S_k = K_ll + ikΩ C_ll − (kΩ)² M_ll, k = 0..H (the massless
        DOFs carry no mass or damping, so Q̂_l,k = S_k⁻¹ (σ F̂_l δ_k1 − K_lc Q̂_c,k)), where the
        dense blocks are held (:class:`~mmshbm.methods.mms.friction_tracked.TrackedHarmonic`);
        otherwise the condensation's recovery."""
        tr = self._tracker
        if tr is None:
            return super()._coefficients(x, omega, sigma)
        n_c, n_coef = self.n_c, self.n_coef
        Xc = x.reshape(n_coef, n_c).T  # (n_c, 2H+1)
        w = omega * np.arange(self.H + 1)
        S = (tr.K_ll[None] + (1j * w)[:, None, None] * tr.C_ll[None]
             - (w**2)[:, None, None] * tr.M_ll[None])
        rhs = np.empty((self.H + 1, len(tr.K_ll), 1), dtype=complex)
        rhs[0, :, 0] = -(tr.K_lc @ Xc[:, 0])
        rhs[1:, :, 0] = -(tr.K_lc @ (Xc[:, 1::2] - 1j * Xc[:, 2::2])).T
        s, _ = self.excitation.scale(omega)
        rhs[1, :, 0] += sigma * s * tr.force_l
        try:
            Ql_hat = np.linalg.solve(S, rhs)[:, :, 0].T  # (n_l, H+1)
        except np.linalg.LinAlgError:
            return super()._coefficients(x, omega, sigma)
        Q = np.empty((self.model.n_dof, n_coef))
        Q[self.model.c] = Xc
        Ql = Q[self.model.l]
        Ql[:, 0] = Ql_hat[:, 0].real
        Ql[:, 1::2] = Ql_hat[:, 1:].real
        Ql[:, 2::2] = -Ql_hat[:, 1:].imag
        Q[self.model.l] = Ql
        return Q
