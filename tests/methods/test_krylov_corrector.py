"""The Newton–Krylov corrector (mmshbm.methods.mms.krylov) against the dense one.

Ground truth: the dense corrector's LU solve of the same bordered system. Two points that
both satisfy the bordered equations [R(u); t·(u − u_p)] = 0 to residuals r_1, r_2 (∞-norm,
each <= newton_tol) differ by at most ‖A⁻¹‖∞ (‖r_1‖∞ + ‖r_2‖∞) to first order, A = [J; tᵀ]
at the solution: the tolerances below are that bound (times 2 for the linearisation),
computed at each point, not chosen.
"""

from __future__ import annotations

import numpy as np
import pytest

import mmshbm
from mmshbm.fe.contact_string import contact_string
from mmshbm.methods.mms.conservative import MMSHBMProblem
from mmshbm.methods.mms.krylov import KRYLOV_MIN_UNKNOWNS, KrylovCorrector, resolve_linear_solver

TOL = 1e-10  # ContinuationOptions.newton_tol's default


def _bordered_residual(problem, u, u_pred, t):
    R = problem.residual(u)
    return max(float(np.abs(R).max()), abs(float(t @ (u - u_pred))))


def _inverse_norm(problem, u, t):
    _, J = problem.residual_and_jacobian(u)
    return float(np.abs(np.linalg.inv(np.vstack([J, t]))).sum(axis=1).max())


@pytest.mark.parametrize("n", [8, 16])
def test_corrector_matches_dense_on_the_same_predictors(n):
    """From the same predictors along a dense branch of the contact string (open, grazing and
    contact points), the Krylov corrector converges to the dense corrector's point within
    the bound that the two residuals allow."""
    model = contact_string(n)
    dense = MMSHBMProblem(model, 5, linear_solver="dense")
    krylov = MMSHBMProblem(model, 5, linear_solver="krylov")
    assert dense.krylov is None and isinstance(krylov.krylov, KrylovCorrector)
    branch = mmshbm.backbone(model, harmonics=5, max_amplitude=1.5, max_steps=60, linear_solver="dense")
    states = branch.states
    assert len(states) > 15
    checked = 0
    for i in range(1, len(states), 3):
        u_prev, u_next = states[i - 1], states[i]
        ds = float(np.linalg.norm(u_next - u_prev))
        t = (u_next - u_prev) / ds
        u_pred = u_prev + 1.05 * ds * t  # a predictor off the branch
        out_d = dense.fast_newton(u_pred.copy(), u_pred, t, TOL, 12, 0.0)
        out_k = krylov.fast_newton(u_pred.copy(), u_pred, t, TOL, 12, 0.0)
        u_d, u_k = out_d[0], out_k[0]
        r_d = _bordered_residual(dense, u_d, u_pred, t)
        r_k = _bordered_residual(krylov, u_k, u_pred, t)
        assert r_k <= TOL
        bound = 2.0 * _inverse_norm(dense, u_d, t) * (r_d + r_k)
        assert float(np.abs(u_d - u_k).max()) <= bound
        checked += 1
    assert checked >= 5
    assert krylov.krylov.solves > 0 and krylov.krylov.fallbacks == 0


def test_krylov_tangent_matches_dense():
    """The tangent the Krylov corrector hands to the continuation solves [J; tᵀ] x = e_n:
    equal to the dense solve within ‖A⁻¹‖∞ times its backward error bound."""
    model = contact_string(8)
    krylov = MMSHBMProblem(model, 5, linear_solver="krylov")
    branch = mmshbm.backbone(model, harmonics=5, max_amplitude=1.5, max_steps=60, linear_solver="dense")
    u_prev, u = branch.states[-3], branch.states[-2]
    t = (u - u_prev) / np.linalg.norm(u - u_prev)
    out = krylov.fast_newton(u.copy(), u, t, TOL, 12, 0.0)
    J = out[3]
    solved = krylov.solved_tangent(J, t)
    assert solved is not None
    x, sign = solved
    assert sign == 0.0  # not computed on this path
    A = np.vstack([J, t])
    e = np.zeros(len(t))
    e[-1] = 1.0
    x_dense = np.linalg.solve(A, e)
    inv = np.abs(np.linalg.inv(A)).sum(axis=1).max()
    backward = float(np.abs(A @ x - e).max())
    assert float(np.abs(x - x_dense).max()) <= 2.0 * inv * backward + 1e3 * np.finfo(float).eps * inv


@pytest.mark.parametrize("n", [8, 16])
def test_branches_agree(n):
    """Whole backbones of the contact string past grazing: the same points, each within the
    bound that the Newton tolerance and the bordered system's conditioning allow."""
    model = contact_string(n)
    kw = dict(harmonics=5, max_amplitude=1.5, max_steps=60)
    dense = mmshbm.backbone(model, linear_solver="dense", **kw)
    krylov = mmshbm.backbone(model, linear_solver="krylov", **kw)
    assert dense.status == krylov.status
    assert len(dense.states) == len(krylov.states)
    assert max(dense.amplitude) > 1.4 * model.contacts[0].gap  # past grazing: contacts closed
    problem = MMSHBMProblem(model, 5, linear_solver="dense")
    for i in range(1, len(dense.states)):
        u, v = dense.states[i], krylov.states[i]
        t = (u - dense.states[i - 1]) / np.linalg.norm(u - dense.states[i - 1])
        # each point solves its own hyperplane to TOL: the bound of two such solutions
        bound = 2.0 * _inverse_norm(problem, u, t) * 2 * TOL
        assert float(np.abs(u - v).max()) <= bound, i


def test_linear_solver_option():
    """The switch: "auto" takes Krylov from KRYLOV_MIN_UNKNOWNS unknowns on (the string's
    32 contacts at H = 5, not its 24); a bad name is refused naming the option."""
    assert resolve_linear_solver("auto", KRYLOV_MIN_UNKNOWNS - 1) == "dense"
    assert resolve_linear_solver("auto", KRYLOV_MIN_UNKNOWNS) == "krylov"
    assert resolve_linear_solver("dense", 10_000) == "dense"
    assert MMSHBMProblem(contact_string(24), 5).linear_solver == "dense"
    assert MMSHBMProblem(contact_string(32), 5).linear_solver == "krylov"
    with pytest.raises(ValueError, match="linear_solver"):
        MMSHBMProblem(contact_string(4), 3, linear_solver="gmres")


def test_krylov_on_the_banded_back_end():
    """The Krylov corrector takes the problem's own residual and Jacobian, so it runs on a
    back end without the compiled corrector (banded LU; the dense path is then the Python
    Newton loop): the same branch within the bound of the Newton tolerance."""
    model = contact_string(8)
    kw = dict(harmonics=5, max_amplitude=1.5, max_steps=60, backend="banded")
    dense = mmshbm.backbone(model, linear_solver="dense", **kw)
    krylov = mmshbm.backbone(model, linear_solver="krylov", **kw)
    assert krylov.solver.cond.backend == "banded" and krylov.solver.krylov.solves > 0
    assert dense.status == krylov.status and len(dense.states) == len(krylov.states)
    problem = MMSHBMProblem(model, 5, backend="banded", linear_solver="dense")
    for i in range(1, len(dense.states)):
        u, v = dense.states[i], krylov.states[i]
        t = (u - dense.states[i - 1]) / np.linalg.norm(u - dense.states[i - 1])
        assert float(np.abs(u - v).max()) <= 4.0 * _inverse_norm(problem, u, t) * TOL, i


def test_preconditioner_is_exact_with_every_contact_open():
    """Below grazing (every contact open, P = 0) J has no coupling between harmonics: the
    preconditioner (the harmonics' blocks with the bordering eliminated onto the
    fundamental's) is then the exact inverse of [J; tᵀ], also on the linear mode where the
    fundamental's block alone is singular, and GMRES stops at once."""
    model = contact_string(8)
    problem = MMSHBMProblem(model, 5, linear_solver="krylov")
    u = problem.linear_mode_point(0.5 * model.contacts[0].gap)
    t = problem.initial_tangent()
    _, J = problem.residual_and_jacobian(u)
    idx1 = problem.harmonic_columns(1)
    block = J[np.ix_(idx1, idx1)]
    assert np.linalg.svd(block, compute_uv=False)[-1] < 1e-12 * np.abs(block).max()  # singular alone
    A = np.vstack([J, t])
    rhs = np.random.default_rng(3).standard_normal(len(t))
    pre = problem.krylov._preconditioner(J, t)
    assert pre is not None
    x = pre(rhs)
    cond = np.linalg.cond(A, np.inf)
    assert float(np.abs(A @ x - rhs).max()) <= 100 * np.finfo(float).eps * cond * np.abs(rhs).max()
    before = problem.krylov.krylov_iterations
    problem.krylov.solve(J, t, rhs, pre)
    assert problem.krylov.krylov_iterations - before <= 1


# ---------------------------------------------------------------------- forced response
@pytest.fixture(scope="module")
def joint():
    from mmshbm.fe.lap_joint import lap_joint

    return lap_joint(8, tip_load=1.0)


def _scaled_square(problem, u):
    x, omega = problem.unpack(u)
    R, Jx, _, _ = problem.residual_parts(x, omega, 1.0, True)
    return R / problem.rowscale, Jx * problem.xscale[None, :] / problem.rowscale[:, None]


def test_forced_krylov_solve_matches_dense_on_the_lap_joint(joint):
    """At fixed frequency (slip over part of the period), Newton with the harmonics' block
    preconditioner and GMRES converges to the dense solve's point within the bound its
    residuals allow (‖J⁻¹‖∞ (r_d + r_k), scaled unknowns, times 2)."""
    from mmshbm.methods.mms.friction_forced import FrictionForcedProblem

    dense = FrictionForcedProblem(joint.model, joint.force, harmonics=3, linear_solver="dense")
    krylov = FrictionForcedProblem(joint.model, joint.force, harmonics=3, linear_solver="krylov")
    assert dense._krylov is None and krylov._krylov is not None
    for f in (0.97 * joint.bending_frequency, joint.bending_frequency):
        guess = dense.linear_response_point(f)
        u_d, ok_d = dense.solve_at(f, guess)
        u_k, ok_k = krylov.solve_at(f, guess)
        assert ok_d and ok_k
        x, omega = dense.unpack(u_d)
        assert 0.05 < dense._record(x, omega, 1.0)["slip_fraction"] < 0.999
        R_d, J = _scaled_square(dense, u_d)
        R_k, _ = _scaled_square(krylov, u_k)
        bound = 2 * np.abs(np.linalg.inv(J)).sum(axis=1).max() * (np.abs(R_d).max() + np.abs(R_k).max())
        assert np.abs(u_k - u_d)[:dense.n_x].max() <= max(bound, 1e-13)
    assert krylov._krylov.krylov_iterations > 0 and krylov._krylov.fallbacks == 0


def test_forced_krylov_response_points_are_dense_solutions(joint):
    """A frequency response with the Krylov corrector (through ``frequency_response``'s
    ``linear_solver`` option): every point checked is a dense fixed-frequency solution from
    itself, within the bound of the two residuals."""
    from mmshbm.methods.mms.friction_forced import FrictionForcedProblem

    f0 = 0.97 * joint.bending_frequency
    res = mmshbm.frequency_response(joint.model, joint.force, (f0, 1.01 * f0), harmonics=3,
                                    linear_solver="krylov")
    assert res.status == "bound:frequency" and len(res.frequency) >= 3
    dense = FrictionForcedProblem(joint.model, joint.force, harmonics=3, linear_solver="dense")
    for i in (0, len(res.frequency) // 2, len(res.frequency) - 1):
        u = np.asarray(res.states[i])
        u_d, ok = dense.solve_at(res.frequency[i], u)
        assert ok
        R_k, J = _scaled_square(dense, u)
        R_d, _ = _scaled_square(dense, u_d)
        bound = 2 * np.abs(np.linalg.inv(J)).sum(axis=1).max() * (np.abs(R_d).max() + np.abs(R_k).max())
        assert np.abs(u - u_d)[:dense.n_x].max() <= max(bound, 1e-12)


def test_forced_linear_solver_switch():
    from mmshbm.methods.mms.forced_krylov import (
        FORCED_KRYLOV_MIN_UNKNOWNS,
        FORCED_MATRIX_FREE_MIN_UNKNOWNS,
        forced_harmonic_columns,
        resolve_forced_solver,
    )

    assert resolve_forced_solver("auto", FORCED_KRYLOV_MIN_UNKNOWNS - 1) == "dense"
    assert resolve_forced_solver("auto", FORCED_KRYLOV_MIN_UNKNOWNS) == "krylov"
    assert resolve_forced_solver("dense", 10**6) == "dense"
    assert resolve_forced_solver("auto", FORCED_MATRIX_FREE_MIN_UNKNOWNS, matrix_free=True) == "krylov"
    assert resolve_forced_solver("auto", FORCED_MATRIX_FREE_MIN_UNKNOWNS - 1, matrix_free=True) == "dense"
    assert resolve_forced_solver("auto", FORCED_MATRIX_FREE_MIN_UNKNOWNS, matrix_free=False) == "dense"
    with pytest.raises(ValueError, match="linear_solver"):
        resolve_forced_solver("lu", 10)
    # the harmonics' unknowns partition the rows, the tracked pair with harmonic 1
    cols = forced_harmonic_columns(3, 2, 3 * 5 + 2)
    assert np.array_equal(np.sort(np.concatenate(cols)), np.arange(17))
    assert cols[1].tolist() == [3, 4, 5, 6, 7, 8, 15, 16]
