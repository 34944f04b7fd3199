"""The compiled corrector of the fused friction forced response
(:meth:`~mmshbm.methods.mms.friction_fused.FusedFrictionEvaluation.correct`) against the
Python loop it compiles (:func:`~mmshbm.methods.mms.corrector.corrector_to_roundoff`,
``compiled_corrector = False``), from the same predictors.

Both run the same Newton steps on the same bordered system; their evaluations and solves
agree to round-off, not to the bit, so the two points are two solutions of [R(u); t·(u −
u_pred)] = 0 each with merit m <= tol. Near a regular point two such solutions differ by at
most ‖[J; tᵀ]⁻¹‖ (m_1 + m_2) (to first order), the bound asserted (with a factor 2 for the
second-order term and the Jacobian taken at one of them). A wrong step, test or sign leaves
the compiled point a Newton step (≥ 1e-6 here) off, or fails to converge."""

import numpy as np
import pytest

import mmshbm
from mmshbm.fe.euler_bernoulli import cantilever
from mmshbm.methods.mms import friction_fused
from mmshbm.methods.mms.corrector import corrector_to_roundoff
from mmshbm.methods.mms.friction_forced import FrictionForcedProblem

TOL, MAX_ITER, STEP_TOL = 1e-10, 10, 1e-8  # the continuation's defaults (ContinuationOptions)


def _two_mass_damper():
    M = np.diag([1.0, 1.0])
    K = np.array([[2e4, -1e4], [-1e4, 1e4]])
    base = mmshbm.Model.from_matrices(M, K, [], [], [], amplitude_dof=1).with_damping(modal_ratio=0.01)
    return base.with_friction(1, 0.5, normal_load=10.0, tangential_stiffness=1e4), [10.0, 0.0, 0.0]


def _beam():
    """NLvib's example-08 beam, Coulomb behind k_t = 1e7 N/m at node 4, 0.2 N at the tip."""
    M, K, dofs = cantilever(2.0, 0.3, 0.1, 185e9, 7830.0, 8)
    node4, tip = int(dofs[3, 0]), int(dofs[-1, 0])
    model = mmshbm.Model.from_matrices(M, K, [], [], [], damping=1e-4 * K, amplitude_dof=tip)
    model = model.with_friction(node4, 1.0, normal_load=1.5, tangential_stiffness=1e7)
    force = np.zeros(model.n_dof)
    force[tip] = 0.2
    return model, force


def _tangent(J):
    """The unit null vector of J (n − 1, n), Ω increasing."""
    t = np.linalg.svd(J)[2][-1]
    return t if t[-1] > 0 else -t


def _merit(p, u, u_pred, t):
    return max(float(np.abs(p.residual(u)).max()), abs(float(t @ (u - u_pred))))


@pytest.mark.parametrize("case,H,ratios", [(_two_mass_damper, 15, (0.95, 1.0, 1.3)), (_beam, 13, (1.0, 1.1))])
def test_compiled_corrector_is_the_python_one(case, H, ratios):
    """From predictors at distances 1e-3 … 0.1 (scaled) along and across the tangent of
    converged orbits (stuck, stick-slip): the same point to the bound of the module
    docstring, the same Newton iterations give or take one (a round-off test at the end),
    and the Jacobian at the point returned."""
    model, force = case()
    p = FrictionForcedProblem(model, force, H)
    assert p.compiled_corrector
    f1 = p.linear_frequency
    rng = np.random.default_rng(3)
    failed = 0
    for ratio in ratios:
        u = p.start_point(ratio * f1)
        t = _tangent(p.residual_and_jacobian(u)[1])
        for ds in (1e-3, 1e-2, 1e-1):
            u_pred = u + ds * t
            start = u_pred + 0.1 * ds * rng.normal(size=u.shape)  # off the predictor too
            try:
                u_p, it_p, hist_p, J_p = corrector_to_roundoff(p, start, u_pred, t, TOL, MAX_ITER, STEP_TOL)
            except RuntimeError as err:  # no convergence from this start: neither converges
                with pytest.raises(RuntimeError, match=str(err).split(" (")[0]):
                    p.fast_newton(start, u_pred, t, TOL, MAX_ITER, STEP_TOL)
                failed += 1
                continue
            u_c, it_c, hist_c, J_c = p.fast_newton(start, u_pred, t, TOL, MAX_ITER, STEP_TOL)
            m_c, m_p = _merit(p, u_c, u_pred, t), _merit(p, u_p, u_pred, t)
            # accepted at the tolerance, or at the residual's floor above it (step <= step_tol)
            assert max(m_c, m_p) <= np.sqrt(TOL)
            inv = np.linalg.norm(np.linalg.inv(np.vstack([J_p, t])), np.inf)
            bound = 2 * inv * (m_c + m_p) + 16 * np.finfo(float).eps * np.abs(u_p).max()
            assert np.abs(u_c - u_p).max() <= bound, (ratio, ds)
            assert abs(it_c - it_p) <= 1
            assert abs(len(hist_c) - len(hist_p)) <= 1
            # the Jacobian returned is the one at the point (or one round-off step before it)
            J_at = p.residual_and_jacobian(u_c)[1]
            assert np.abs(J_c - J_at).max() <= 1e-6 * np.abs(J_at).max()
    assert failed <= len(ratios)  # most starts converge


def test_compiled_corrector_raises_as_the_python_one():
    """No convergence within the iterations allowed: RuntimeError from both."""
    model, force = _beam()
    p = FrictionForcedProblem(model, force, 13)
    u = p.start_point(1.1 * p.linear_frequency)
    t = _tangent(p.residual_and_jacobian(u)[1])
    u_pred = u + 0.3 * t
    with pytest.raises(RuntimeError, match="no convergence in 1 iterations"):
        p.fast_newton(u_pred, u_pred, t, TOL, 1, STEP_TOL)
    with pytest.raises(RuntimeError, match="no convergence in 1 iterations"):
        corrector_to_roundoff(p, u_pred, u_pred, t, TOL, 1, STEP_TOL)


def test_switch_and_fallback(monkeypatch):
    """The compiled loop serves the fused problems (one call per corrector); with
    ``compiled_corrector = False``, and where the evaluation is not fused, the Python loop."""
    calls = []
    correct = friction_fused.FusedFrictionEvaluation.correct

    def counted(self, *args):
        calls.append(1)
        return correct(self, *args)

    monkeypatch.setattr(friction_fused.FusedFrictionEvaluation, "correct", counted)
    model, force = _two_mass_damper()
    f1 = float(model.linear_frequencies(1)[0])
    r = mmshbm.frequency_response(model, force, (0.9 * f1, 1.1 * f1), harmonics=7)
    assert r.status == "bound:frequency" and len(calls) >= len(r.frequency) - 1
    calls.clear()
    monkeypatch.setattr(FrictionForcedProblem, "compiled_corrector", False)
    r_py = mmshbm.frequency_response(model, force, (0.9 * f1, 1.1 * f1), harmonics=7)
    assert r_py.status == "bound:frequency" and not calls
    monkeypatch.setattr(FrictionForcedProblem, "compiled_corrector", True)
    p = FrictionForcedProblem(model, force, 7)
    p._fused = False  # the stepwise evaluation: the Python loop
    u = p.start_point(f1)
    t = _tangent(p.residual_and_jacobian(u)[1])
    p.fast_newton(u + 1e-2 * t, u + 1e-2 * t, t, TOL, MAX_ITER, STEP_TOL)
    assert not calls
