"""A Newton corrector for MMS-HBM in one compiled loop (modal condensation).

For small dense problems (MMS-HBM's usual case: (H+1)·n_c + n_p + 1 unknowns) the cost of
a corrector step is dominated by Python: unpacking, the condensation call, the residual
call, assembling and solving the bordered system. :func:`_newton_modal` does all of it in
Numba — the condensed dynamic stiffness from fixed-interface modes
(:func:`~mmshbm.harmonic._modal_kernels._modal_dynamic_stiffness`, with the pole pairs left out
and their static part added back, :mod:`mmshbm.methods.mms.condensation.poles`), the fused residual and
Jacobian (:func:`~mmshbm.methods.mms.contact_kernels._mmshbm_eval`), the bordered LU
(:func:`~mmshbm.harmonic.kernels._dense_solve`) and the convergence test of
:func:`mmshbm.core.continuation.newton` — so that an iteration costs its arithmetic. The
numbers are those of the Python loop (the same kernels, in the same order).

Caching: this kernel calls kernels of three other files; the package's cache policy
(:mod:`mmshbm._kernel_cache`) recompiles it when any of them changes.
"""

from __future__ import annotations

import math
from collections import namedtuple

from numba import njit

from ...harmonic._modal_kernels import _modal_dynamic_stiffness
from ...harmonic.kernels import JIT_OPTIONS, _dense_solve
from .contact_kernels import _mmshbm_eval

__all__ = ["ModalCondensation", "PoleTerms", "ContactLaw", "Sampling", "Scaling", "NewtonWork", "EvalWork",
           "newton_modal_entry"]

#: status codes of :func:`_newton_modal`
CONVERGED, NO_CONVERGENCE, NON_FINITE, SINGULAR, POLE, SKIPPED = 0, 1, 2, 3, 4, 5


#: The arguments of :func:`_newton_modal`, grouped (numba takes named tuples of arrays and
#: scalars as arguments; :meth:`MMSHBMProblem._fast_setup` builds them, once per problem).
#: The modal condensation: D0 (n_c, n_c), B (m, n_c) the b_j, w2 (m,) the ω_j², Rs (P, n_c, n_c)
#: the residual-inertia terms, keep (H+1, m) uint8 (0: the mode's term is carried by a pole
#: unknown), static (H+1, n_c, n_c) the static part b_j b_jᵀ/ω_j² of those terms, pole_rtol
#: the relative distance to a fixed-interface eigenfrequency that counts as a pole.
ModalCondensation = namedtuple("ModalCondensation", "D0 B w2 Rs keep static pole_rtol")
#: The pole unknowns η_jk (:mod:`mmshbm.methods.mms.condensation.poles`): harmonic k (n_p,) int64,
#: b (n_p, n_c), w2 (n_p,).
PoleTerms = namedtuple("PoleTerms", "k b w2")
#: The contact law: cdof (n_contacts,) int64 rows of the contact DOFs, lo/hi their admissible
#: intervals (m), r (n_contacts,) the proximal parameters (N/m), exact the closed-form projection.
ContactLaw = namedtuple("ContactLaw", "cdof lo hi r exact")
#: Alternating frequency-time tables: cos (2H+1, N), sin (H+1, N), tau (N,) (rad).
Sampling = namedtuple("Sampling", "cos sin tau")
#: Scaling of the unknowns (n,) and of the residual rows (n-1,).
Scaling = namedtuple("Scaling", "colscale rowscale")
#: Work arrays of the corrector: D, dD (H+1, n_c, n_c), R (n-1,), J (n-1, n), A (n, n), rhs (n,),
#: LU (n, n), du (n,), a (H+1, n_c), eta (n_p,), sign (1,); the tangent solve at the converged
#: point: tx (n,) or (0,) for none, t_sign (1,) the sign of its determinant, t_info (1,) 0 or
#: the solve's nonzero return (singular).
NewtonWork = namedtuple("NewtonWork", "D dD R J A rhs LU du a eta sign tx t_sign t_info")
#: Work arrays of :func:`~mmshbm.methods.mms.contact_kernels._mmshbm_eval` (its last twelve arguments).
EvalWork = namedtuple("EvalWork", "F dF pc ps gc g_t dg_t roots C_hi C_lo S_w P")


@njit(**JIT_OPTIONS)
def _newton_modal(u, u_pred, t, tol, step_tol, max_iter, n_c, H, hist, scale, cond, poles, law, samples,
                  work, ework):
    """Newton on [R(u); t·(u − u_pred)] = 0 from ``u`` (updated in place).

    Converged when max(|R|∞, |t·(u − u_pred)|) <= tol, or when the last update's ∞-norm is
    <= step_tol with the residual <= √tol. ``hist`` (max_iter+1,) receives the residual
    norms; on return work.J (n−1, n) is the Jacobian at the last evaluated iterate and
    work.D, work.dD the condensed stiffness there. Returns (status, iterations) with the
    status codes of this module: SKIPPED is a convergence whose last update was not
    evaluated again, because quadratic convergence predicted its residual below tol/10
    (``hist[it]`` holds that prediction; J, D and dD are those of the iterate before).

    ``scale`` (:data:`Scaling`), ``cond`` (:data:`ModalCondensation`), ``poles``
    (:data:`PoleTerms`), ``law`` (:data:`ContactLaw`), ``samples`` (:data:`Sampling`),
    ``work`` (:data:`NewtonWork`) and ``ework`` (:data:`EvalWork`) group the data of
    :func:`_mmshbm_eval` and of the bordered solve.
    """
    colscale, rowscale = scale.colscale, scale.rowscale
    D, dD, R, J, A, rhs, LU, du, a, eta = (work.D, work.dD, work.R, work.J, work.A, work.rhs, work.LU,
                                           work.du, work.a, work.eta)
    n = u.shape[0]
    n_a = (H + 1) * n_c
    with_derivative = n > 0  # a run-time bool: a literal True would compile the callee twice
    n_p = eta.shape[0]
    du_norm = math.inf
    for it in range(max_iter + 1):
        for k in range(H + 1):
            for i in range(n_c):
                a[k, i] = u[k * n_c + i] * colscale[k * n_c + i]
        for p in range(n_p):
            eta[p] = u[n_a + p] * colscale[n_a + p]
        omega = u[n - 1] * colscale[n - 1]
        if _modal_dynamic_stiffness(cond.D0, cond.B, cond.w2, cond.Rs, omega, H, cond.keep, cond.pole_rtol,
                                    D, dD, with_derivative) != 0:
            return POLE, it
        static = cond.static
        for k in range(H + 1):
            for i in range(n_c):
                for j in range(n_c):
                    D[k, i, j] += static[k, i, j]
        _mmshbm_eval(D, dD, a, eta, omega, poles.k, poles.b, poles.w2, law.cdof, law.lo, law.hi, law.r,
                     law.exact, samples.cos, samples.sin, samples.tau, rowscale, colscale, True, R, J,
                     ework.F, ework.dF, ework.pc, ework.ps, ework.gc, ework.g_t, ework.dg_t, ework.roots,
                     ework.C_hi, ework.C_lo, ework.S_w, ework.P)
        arc = 0.0
        for i in range(n):
            arc += t[i] * (u[i] - u_pred[i])
        norm = abs(arc)
        for i in range(n - 1):
            v = abs(R[i])
            if v > norm or v != v:
                norm = v
        hist[it] = norm
        if not math.isfinite(norm):
            return NON_FINITE, it
        if norm <= tol or (du_norm <= step_tol and norm <= math.sqrt(tol)):
            _tangent_solve(J, t, A, rhs, LU, work)
            return CONVERGED, it
        if it == max_iter:
            break
        for i in range(n - 1):
            for j in range(n):
                A[i, j] = J[i, j]
            rhs[i] = R[i]
        for j in range(n):
            A[n - 1, j] = t[j]
        rhs[n - 1] = arc
        if _dense_solve(A, rhs, LU, du, work.sign) != 0:
            return SINGULAR, it
        du_norm = 0.0
        for i in range(n):
            v = abs(du[i])
            if v > du_norm:
                du_norm = v
        if not math.isfinite(du_norm):
            return SINGULAR, it
        for i in range(n):
            u[i] -= du[i]
        # quadratic convergence predicts the next residual below tol/10: accept the updated
        # point without evaluating it (as mmshbm.core.steps._predicted_converged)
        if it >= 1 and tol >= 1e-11:  # steps.SKIP_MIN_TOL
            r_prev = hist[it - 1]
            if r_prev > 0.0 and norm <= math.sqrt(tol) and norm <= 0.1 * r_prev:
                predicted = norm * (norm / r_prev) ** 2
                if predicted <= 0.1 * tol:
                    hist[it + 1] = predicted
                    _tangent_solve(J, t, A, rhs, LU, work)
                    return SKIPPED, it + 1
    return NO_CONVERGENCE, max_iter


@njit(**JIT_OPTIONS)
def _tangent_solve(J, t, A, rhs, LU, work):
    """The continuation's tangent system at the returned Jacobian J (n−1, n) with the
    corrector's hyperplane normal t (n,): [J; tᵀ] x = e_n into ``work.tx``, the sign of the
    determinant into ``work.t_sign``, the solve's return into ``work.t_info`` (the same LU,
    so the same numbers, as :func:`mmshbm.core.bordered.bordered_solve_sign` of a small
    dense system). Nothing when ``work.tx`` is empty (a system that path solves otherwise)."""
    n = t.shape[0]
    x = work.tx
    if x.shape[0] != n:
        return
    for i in range(n - 1):
        for j in range(n):
            A[i, j] = J[i, j]
        rhs[i] = 0.0
    for j in range(n):
        A[n - 1, j] = t[j]
    rhs[n - 1] = 1.0
    work.t_info[0] = _dense_solve(A, rhs, LU, x, work.t_sign)


def newton_modal_entry(args: tuple):
    """The compiled :func:`_newton_modal` for the types of ``args`` (its full argument
    tuple), as a plain callable: compiled, or taken from the disk cache, on first use.

    Numba's dispatcher resolves the type of every argument on each call, and for named
    tuples that takes its slow path (≈ 1 µs a tuple: a third of a warm corrector on a small
    problem). A problem resolves the types once and keeps the entry point; every later call
    must pass arguments of the same types (the problem's arrays are fixed; u, u_pred, t and
    hist are C-contiguous float64 vectors, the scalars Python floats and ints). The entry
    point is kept per argument types (:func:`~mmshbm.core._entry.compiled_entry`): the
    next problem's arguments are not typed again. Under ``NUMBA_DISABLE_JIT=1`` the
    Python function itself.
    """
    if not hasattr(_newton_modal, "compile"):
        return _newton_modal
    from ...core._entry import compiled_entry

    return compiled_entry(_newton_modal, args)


@njit(**JIT_OPTIONS)
def _start_mode_share(a, eta, omega, dD, pole_k, pole_j, pole_w2, B, w2, keep, s0, s, sv):
    """Share of the period-mean kinetic energy in one open-contact mode at the fundamental
    harmonic (the starting mode's family test), from the modal condensation's projections
    onto that mode (s0 = φᵀ M Z_0 (n_c,), s = φᵀ M φ_j (m,), sv (q, n_c) the projections of
    the left-out modes' blocks Ṽ_1.., empty when the reduction is complete):

        η = −(s0·a_1 + Σ_j keep[1, j] s_j (b_j·a_1) x/(ω_j²(ω_j² − x)) + Σ_i x^i sv_i·a_1)
            − Σ_{poles of harmonic 1} s_j η_j1 x/ω_j²,       x = Ω²,
        share = ¼ x η² / T,   T = −(Ω/8) Σ_{k>=1} (a_kᵀ ∂D_k/∂Ω a_k − 2k²Ω Σ_{poles of k} η²).

    dD is the regular part of ∂D_k/∂Ω (poles left out). Returns 0 when T <= 0.
    """
    H1 = dD.shape[0]
    n_c = dD.shape[1]
    m = B.shape[0]
    x = omega * omega
    y = 0.0
    for i in range(n_c):
        y += s0[i] * a[1, i]
    for j in range(m):
        if keep[1, j] == 0:
            continue
        ba = 0.0
        for i in range(n_c):
            ba += B[j, i] * a[1, i]
        y += s[j] * ba * x / (w2[j] * (w2[j] - x))
    xi = 1.0
    for q in range(sv.shape[0]):
        xi *= x
        for i in range(n_c):
            y += xi * sv[q, i] * a[1, i]
    y = -y
    for p in range(pole_k.shape[0]):
        if pole_k[p] == 1:
            y -= s[pole_j[p]] * eta[p] * x / pole_w2[p]
    quad = 0.0
    for k in range(1, H1):
        for i in range(n_c):
            acc = 0.0
            for j in range(n_c):
                acc += dD[k, i, j] * a[k, j]
            quad += a[k, i] * acc
    for p in range(pole_k.shape[0]):
        quad -= 2.0 * pole_k[p] * pole_k[p] * omega * eta[p] * eta[p]
    total = -omega / 8.0 * quad
    if total <= 0.0:
        return 0.0
    return 0.25 * x * y * y / total
