"""The forced response's Jacobian as an operator (mmshbm.methods.mms.forced_operator) against
the assembled Jacobian of the dense path and against finite differences of the residual."""

from __future__ import annotations

import numpy as np
import pytest

from mmshbm.methods.mms.forced_operator import (
    condensed_product,
    evaluate_matrix_free,
    real_blocks,
    square_operator,
    supports_matrix_free,
)

EPS = np.finfo(float).eps


@pytest.fixture(scope="module")
def problems():
    from mmshbm.fe.lap_joint import lap_joint
    from mmshbm.methods.mms.friction_forced import FrictionForcedProblem

    joint = lap_joint(8, tip_load=1.0)
    dense = FrictionForcedProblem(joint.model, joint.force, harmonics=3, linear_solver="dense")
    krylov = FrictionForcedProblem(joint.model, joint.force, harmonics=3, linear_solver="krylov")
    f = 0.97 * joint.bending_frequency
    u, ok = dense.solve_at(f, dense.linear_response_point(f))
    assert ok
    x, omega = dense.unpack(u)
    assert 0.05 < dense._record(x, omega, 1.0)["slip_fraction"] < 0.999  # stick and slip
    return joint, dense, krylov, u


def test_condensed_product_is_the_real_blocks():
    rng = np.random.default_rng(1)
    H, n_c = 3, 5
    D = rng.standard_normal((H + 1, n_c, n_c)) + 1j * rng.standard_normal((H + 1, n_c, n_c))
    D[0] = D[0].real
    x = rng.standard_normal(n_c * (2 * H + 1))
    ref = real_blocks(D) @ x
    bound = 4 * n_c * EPS * (np.abs(real_blocks(D)) @ np.abs(x)).max()
    assert np.abs(condensed_product(D, x) - ref).max() <= bound


def test_operator_is_the_assembled_jacobian(problems):
    """Residual, Jacobian (every column), the Ω column and the harmonics' blocks equal the
    dense path's (the compiled rows of the assembled Jacobian) to round-off: entries are
    sums of at most n_x products, bound 4 n_x ε times the row's |J| sum."""
    _, dense, krylov, u = problems
    assert krylov._matrix_free and not dense._matrix_free
    v = u + 1e-3 * np.random.default_rng(0).standard_normal(u.shape)  # off the branch
    R_d, J_d = dense._evaluate(v, True)
    R_k, J_k = evaluate_matrix_free(krylov, v, True)
    n = J_d.shape[1]
    tol_R = 4 * n * EPS * np.abs(J_d).sum(axis=1).max() * np.abs(v).max()
    assert np.abs(R_k - R_d).max() <= tol_R
    A = J_k.toarray()
    row = np.abs(J_d).sum(axis=1)
    assert np.all(np.abs(A - J_d).max(axis=1) <= 4 * n * EPS * row)
    assert J_k.inf_norm_bound() >= row.max() * (1 - 1e-12)
    for k in range(krylov.H + 1):
        idx = J_k._blocks[k]
        diff = np.abs(J_k.harmonic_block(k) - J_d[np.ix_(idx, idx)]).max(axis=1)
        assert np.all(diff <= 4 * n * EPS * row[idx])
    # the fixed-frequency operator in physical units
    x, omega = krylov.unpack(v)
    _, op = square_operator(krylov, x, omega)
    _, Jx, _, _ = dense.residual_parts(x, omega, 1.0, True)
    rowx = np.abs(Jx).sum(axis=1)
    assert np.all(np.abs(op.toarray() - Jx).max(axis=1) <= 4 * n * EPS * rowx)
    e = np.random.default_rng(2).standard_normal(op.n_x)
    assert np.all(np.abs(op.matvec(e) - Jx @ e) <= 4 * n * EPS * (np.abs(Jx) @ np.abs(e)))


def test_operator_against_finite_differences(problems):
    """J v against central differences of the residual in a random direction, at a point
    with stick and slip: the difference at step h is within its truncation error, estimated
    from the steps h and 2h (Richardson: |D_h − J v| <= |D_2h − D_h|/3 for a smooth
    residual; bound 2× that), plus the round-off of the residual over h."""
    _, _, krylov, u = problems
    rng = np.random.default_rng(3)
    d = rng.standard_normal(u.shape)
    d /= np.abs(d).max()
    _, J = evaluate_matrix_free(krylov, u, True)
    Jv = J @ d

    def R(w):
        return evaluate_matrix_free(krylov, w, False)

    for h in (1e-6, 1e-5):
        D1 = (R(u + h * d) - R(u - h * d)) / (2 * h)
        D2 = (R(u + 2 * h * d) - R(u - 2 * h * d)) / (4 * h)
        roundoff = 1e3 * EPS * (np.abs(R(u)).max() + J.inf_norm_bound() * np.abs(u).max()) / h
        err = np.abs(D1 - Jv).max()
        assert err <= 2 * np.abs(D2 - D1).max() / 3 + roundoff, (h, err)
    assert np.abs(Jv).max() > 1e3 * roundoff  # the check is not vacuous


def test_matrix_free_only_where_the_structure_holds():
    """Unilateral contacts (the pairs' normal stops) keep the assembled Jacobian."""
    from mmshbm.fe.lap_joint import lap_joint
    from mmshbm.methods.mms.friction_forced import FrictionForcedProblem

    joint = lap_joint(4, tip_load=1.0, normal="unilateral")
    P = FrictionForcedProblem(joint.model, joint.force, harmonics=2, linear_solver="krylov")
    assert not supports_matrix_free(P) and not P._matrix_free
