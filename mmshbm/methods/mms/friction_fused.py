"""The friction forced response's residual and Jacobian in one compiled call per Newton
iteration (:func:`~mmshbm.methods.mms._friction_fused._forced_friction_evaluate`).

:class:`FusedFrictionEvaluation` holds the kernel's constant arguments and its work buffers,
built once per problem; :meth:`FusedFrictionEvaluation.evaluate` is
:meth:`~mmshbm.methods.mms.friction_forced.FrictionForcedProblem._evaluate` (same numbers to
round-off: the same formulas, the steps in one loop instead of NumPy calls in between). It
serves the problems of that kind (:func:`fused_evaluation`): the amplitude DOF's harmonic 1
tracked with the dense blocks, the modal condensation's compiled back end, the play form
with constant slip forces (unilateral contacts allowed). The others keep the stepwise path.

:meth:`FusedFrictionEvaluation.correct` is the continuation's corrector of those problems in
one compiled call per point (:mod:`mmshbm.methods.mms._friction_newton`: the Newton loop of
:func:`~mmshbm.methods.mms.corrector.corrector_to_roundoff`, its reference, with the small
dense bordered solve of :func:`~mmshbm.core.bordered.bordered_solve`), for bordered systems
of at most :data:`COMPILED_CORRECTOR_MAX_UNKNOWNS` unknowns (:meth:`~FusedFrictionEvaluation.corrects`).
"""

from __future__ import annotations

import numpy as np

from ...harmonic.condense import SingularDynamicStiffness
from .corrector import _FLOOR, _STALL

__all__ = ["COMPILED_CORRECTOR_MAX_UNKNOWNS", "FusedFrictionEvaluation", "fused_evaluation"]

#: the compiled corrector's largest bordered system: up to this size
#: :func:`~mmshbm.core.bordered.bordered_solve` solves by the small dense LU the compiled
#: loop runs too (larger ones go to LAPACK, and the Python corrector keeps them)
COMPILED_CORRECTOR_MAX_UNKNOWNS = 40
#: the smallest step of the corrector's backtracking (:func:`~mmshbm.methods.mms.corrector.backtrack`)
_MIN_STEP = 1.0 / 4096


def fused_evaluation(problem) -> FusedFrictionEvaluation | bool:
    """The compiled evaluation of ``problem`` (a
    :class:`~mmshbm.methods.mms.friction_forced.FrictionForcedProblem`), or False where it is
    not of the kind it serves (module docstring)."""
    cond = problem.cond
    if (problem._tracker is None or not problem._compiled_rows or cond.backend != "modal"
            or getattr(cond, "_Phi_c_contiguous", None) is None):
        return False
    return FusedFrictionEvaluation(problem)


class FusedFrictionEvaluation:
    """The compiled ``_evaluate`` of one friction forced problem (module docstring). The
    scalings (``colscale``, ``rowscale``, ``length``) are read from the problem at every call;
    everything else is fixed at construction."""

    #: the record kernel's fixed arrays and work buffers, built at the first record
    _record_fixed = None
    _record_work = None

    def __init__(self, problem):
        cond, tr = problem.cond, problem._tracker
        H, n_c, n_x = problem.H, problem.n_c, problem.n_x
        self.problem = problem
        n_b = cond.B.shape[1]
        tau_u, cos_u, sin_u = problem._tables
        tau_f, cos_f, sin_f = problem._play_tables
        c = np.ascontiguousarray
        self._fixed = (
            int(H), int(problem.excitation.omega_power),
            cond._w2, cond._gamma, cond._Phi_c_contiguous, c(cond._Kcc_inv), c(cond.D0),
            cond._beta_contiguous,
            problem._rows, problem.lo, problem.hi, problem.r, problem._exact, cos_u, sin_u, tau_u,
            problem._friction_rows64, c(problem.slip_force, dtype=float), c(problem.rho, dtype=float),
            tau_f, cos_f, sin_f,
            tr.K_ll, tr.M_ll, tr.C_ll, tr._rhs, int(tr.row))
        shape = (H + 1, n_c, n_c)
        self._work = (
            np.empty(shape, dtype=complex), np.empty((1,) + shape, dtype=complex),
            np.empty((0, 0, 0), dtype=complex), np.empty((n_c, n_b), dtype=complex),
            np.empty((n_c, n_b), dtype=complex), np.empty((n_c, n_b), dtype=complex),
            np.empty(n_x), np.empty((n_x, 1)), np.empty(n_x), np.empty((n_x, n_x)), np.empty((n_x, 1)),
            np.empty(len(problem.friction_rows)), np.empty(n_c + 1, dtype=complex),
            np.empty(n_c + 1, dtype=complex))

    def evaluate(self, u: np.ndarray, jacobian: bool):
        """Scaled residual (n_x + 2,) and, with ``jacobian``, the pair (R, J), J
        (n_x + 2, n_x + 3): new arrays every call. Raises SingularDynamicStiffness where the
        condensation is singular, numpy.linalg.LinAlgError where S_1 is."""
        from ._friction_fused import _forced_friction_evaluate

        p = self.problem
        n_x = p.n_x
        if np.shape(u) != (n_x + 3,):
            raise ValueError(f"u must have shape ({n_x + 3},), got {np.shape(u)}")
        R = np.empty(n_x + 2)
        J = np.empty((n_x + 2, n_x + 3)) if jacobian else _NO_J
        try:
            status = _forced_friction_evaluate(np.ascontiguousarray(u, dtype=float), p.colscale, p.rowscale,
                                               float(p.length), *self._fixed, jacobian, *self._work, R, J)
        except np.linalg.LinAlgError as err:
            omega = float(u[-1]) * float(p.colscale[-1])
            raise np.linalg.LinAlgError(f"S_1 singular at Ω = {omega:.6g} rad/s: {err}") from None
        if status:
            omega = float(u[-1]) * float(p.colscale[-1])
            raise SingularDynamicStiffness(f"condensation singular at Ω = {omega:.6g} rad/s")
        return (R, J) if jacobian else R

    def corrects(self, n_unknowns: int) -> bool:
        """Whether :meth:`correct` serves a bordered system of ``n_unknowns`` unknowns."""
        return n_unknowns <= COMPILED_CORRECTOR_MAX_UNKNOWNS

    def correct(self, u0: np.ndarray, u_pred: np.ndarray, tangent: np.ndarray, tol: float, max_iter: int,
                step_tol: float):
        """:func:`~mmshbm.methods.mms.corrector.corrector_to_roundoff` of the problem (dense
        bordered solves) in one compiled call: (u (n,), iterations, merit history, Jacobian
        (n − 1, n) at u or at the iterate one round-off step before it), all scaled. Raises
        what that corrector raises: RuntimeError (no convergence in ``max_iter``, a stall
        above round-off, a non-finite residual, a singular bordered system),
        SingularDynamicStiffness where the condensation is singular, numpy.linalg.LinAlgError
        where S_1 is."""
        from . import _friction_newton as kn

        p = self.problem
        n = p.n_x + 3
        if np.shape(u0) != (n,) or np.shape(u_pred) != (n,) or np.shape(tangent) != (n,):
            raise ValueError(f"u0, u_pred and tangent must have shape ({n},), got {np.shape(u0)}, "
                             f"{np.shape(u_pred)}, {np.shape(tangent)}")
        u = np.empty(n)
        J = np.empty((n - 1, n))
        history = np.empty(2 * max(int(max_iter), 0) + 3)
        info = np.empty(3)
        c = np.ascontiguousarray
        try:
            status = kn._forced_friction_correct(
                c(u0, dtype=float), c(u_pred, dtype=float), c(tangent, dtype=float), float(tol),
                int(max_iter), float(step_tol), _FLOOR, _STALL, _MIN_STEP, p.colscale, p.rowscale,
                float(p.length), self._fixed, self._work, u, J, history, info)
        except np.linalg.LinAlgError as err:
            raise np.linalg.LinAlgError(f"S_1 singular in the corrector: {err}") from None
        if status == kn.NOT_FINITE:
            raise RuntimeError("non-finite residual")
        if status == kn.SINGULAR_JACOBIAN:
            raise RuntimeError("singular Jacobian")
        if status == kn.STALLED:
            raise RuntimeError(f"Newton stalled at residual {info[2]:.2e}")
        if status == kn.NO_CONVERGENCE:
            raise RuntimeError(f"no convergence in {max_iter} iterations (residual {info[2]:.2e})")
        if status == kn.SINGULAR_CONDENSATION:
            raise SingularDynamicStiffness(f"condensation singular at Ω = {info[2]:.6g} rad/s")
        return u, int(info[0]), history[:int(info[1])].copy(), J

    def _record_setup(self):
        p = self.problem
        tr, model = p._tracker, p.model
        H, n_c, n_b = p.H, p.n_c, p.cond.B.shape[1]
        c = np.ascontiguousarray
        K, M = p._dense_km if p._dense_km is not None else (c(model.K.toarray()), c(model.M.toarray()))
        p._dense_km = (K, M)
        fixed = self._fixed
        self._record_fixed = (
            *fixed[:8], *fixed[16:22], tr.K_ll, tr.M_ll, tr.C_ll, c(tr.K_lc, dtype=float),
            c(tr.force_l, dtype=complex), c(model.c, dtype=np.int64), c(model.l, dtype=np.int64), K, M)
        shape = (H + 1, n_c, n_c)
        self._record_work = (np.empty(shape, dtype=complex), np.empty(shape, dtype=complex),
                             np.empty((0, 0, 0), dtype=complex),
                             *(np.empty((n_c, n_b), dtype=complex) for _ in range(3)))

    def record_parts(self, x: np.ndarray, omega: float, sigma: float):
        """(F (n_x,) the force the structure needs at the massless DOFs (N), Q (n_dof, 2H+1)
        the coefficients of all DOFs (m), mean energy (J), largest slip fraction, friction
        work per period (J)) of a converged point; None where some S_k is singular (the
        stepwise records then apply)."""
        from ._friction_fused import _forced_friction_record

        if self._record_fixed is None:
            self._record_setup()
        p = self.problem
        F = np.empty(p.n_x)
        Q = np.empty((p.model.n_dof, p.n_coef))
        out = np.empty(3)
        try:
            status = _forced_friction_record(np.ascontiguousarray(x, dtype=float), float(omega), float(sigma),
                                             *self._record_fixed, *self._record_work, F, Q, out)
        except np.linalg.LinAlgError:
            return None
        if status:
            return None
        return F, Q, float(out[0]), float(out[1]), float(out[2])


_NO_J = np.empty((0, 0))
