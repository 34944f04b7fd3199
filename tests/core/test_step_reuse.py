"""The continuation step's shortcuts give the numbers of the plain computation: the turn
t_new·t computed once (the turn test, the corner test and the curvature reuse it), the
tangent's dot products by ndarray.dot (matmul's to its round-off), and the MMS-HBM
monitor's kernel arguments kept with its compiled entry (a problem's later monitors against
a fresh problem's first)."""

import warnings

import numpy as np
from roundoff import assert_roundoff_close

import mmshbm
from mmshbm.core.continuation import ContinuationOptions
from mmshbm.core.steps import _advance_turn, _curvature, _tangent_sign, _tangent_sign_turn
from mmshbm.methods.registry import make_problem


def _beam_branch():
    model = mmshbm.default_beam().model(9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return model, mmshbm.backbone(model, harmonics=3)


def test_dot_is_matmul_to_its_roundoff_and_negation_is_exact():
    rng = np.random.default_rng(1)
    for n in (2, 7, 15, 16, 33, 64):
        for _ in range(50):
            t, p = rng.standard_normal(n), rng.standard_normal(n) * rng.uniform(1e-6, 1e6)
            # two paths to one dot product (ndarray.dot, matmul): its round-off apart
            assert_roundoff_close(t.dot(p), t @ p, np.abs(t) @ np.abs(p), terms=n)
            assert (-t).dot(p) == -t.dot(p)  # one path, the inputs negated: rounding is symmetric


def test_turn_is_the_tangents_product_and_the_curvature_the_same():
    model, branch = _beam_branch()
    opt = ContinuationOptions(step_control="residual")
    p = make_problem(model, "mmshbm", harmonics=3)
    assert p._fast_setup()  # the compiled corrector's path (its solved tangent)
    u, t = branch.states[3], branch.states[4] - branch.states[3]
    t = t / np.linalg.norm(t)
    ds = 0.5 * float(np.linalg.norm(branch.states[4] - branch.states[3]))
    u_new, _, _, J, t_new, sign, _, turn = _advance_turn(p, u, t, ds, opt, None)
    assert_roundoff_close(turn, float(t_new @ t), np.abs(t_new) @ np.abs(t), terms=len(t))
    assert turn >= 0
    for got, want in ((_curvature(t, t_new, ds, turn), _curvature(t, t_new, ds)),):
        assert got is not None and np.array_equal(got, (t_new - t) / ds) and np.array_equal(got, want)
    # the tangent and its sign as the two-value form gives them (solved again from J)
    t2, s2, turn2 = _tangent_sign_turn(J, t)
    t3, s3 = _tangent_sign(J, t)
    assert np.array_equal(t2, t3) and s2 == s3  # one solve (the two-value form calls the three-value one)
    assert_roundoff_close(turn2, float(t3 @ t), np.abs(t3) @ np.abs(t), terms=len(t))


def test_monitor_with_kept_arguments_is_a_fresh_problems():
    model, branch = _beam_branch()
    warm = make_problem(model, "mmshbm", harmonics=3)
    for u in branch.states[::5]:
        warm.monitor(u)
    assert warm._monitor_args is not None  # the kept arguments are in use
    for u in branch.states[1::7]:
        fresh = make_problem(model, "mmshbm", harmonics=3)
        got, want = warm.monitor(u), fresh.monitor(u)
        assert got.keys() == want.keys()
        assert all(np.array_equal(got[k], want[k], equal_nan=True) for k in want), u
