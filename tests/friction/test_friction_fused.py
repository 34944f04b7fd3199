"""The fused evaluation and record of the friction forced response
(:mod:`mmshbm.methods.mms.friction_fused`) against the stepwise path (the condensation, the
fused unilateral residual, the friction rows, the tracked harmonic and the scaling called
one by one from Python; ``_fused = False``), to round-off (tests/roundoff.py).

Both paths evaluate the same formulas on the same numbers in different orders (the friction
rows' product (I + J_g/ρ) 𝔇 over 𝔇's nonzero blocks only, the scaling by one product
instead of two), so each entry is within ε times the magnitude of its terms times their
count: the terms of a row of R are those of F = 𝔇x − load and of the projection g
(s + ρ Σ|y|), of a Jacobian entry (1 + ‖J_g‖/ρ) max|𝔇| + ‖J_g‖, ‖J_g‖ <= 4ρ (the
derivation of test_friction_compiled.py), in the scaled units of the row and column."""

import numpy as np
import pytest
from roundoff import assert_roundoff_close, product_scale

import mmshbm
from mmshbm.fe.euler_bernoulli import cantilever
from mmshbm.methods.mms.friction_forced import FrictionForcedProblem
from mmshbm.methods.mms.friction_fused import FusedFrictionEvaluation


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


def _tolerances(p, u):
    """Per-entry scales (scaled units) of R (n_x + 2,) and J (n_x + 2, n_x + 3)."""
    x, omega = p.unpack(u)
    ch = p._condensed(omega, 0.0, True)
    s, ds = p.excitation.scale(omega)
    Dx, dDx = p.real_blocks(ch.D), p.real_blocks(ch.dD_domega)
    load = np.abs(p.first_harmonic_vector(s * ch.P[:, 0]))
    dload = np.abs(p.first_harmonic_vector(s * ch.dP_domega[:, 0] + ds * ch.P[:, 0]))
    scale = product_scale(Dx, x) + load
    for j, i in enumerate(p.friction_rows):
        idx = p._coef_index[i]
        scale[idx] += p.slip_force[j] + p.rho[j] * (np.abs(x[idx]).sum() + scale[idx].sum() / p.rho[j])
    z, y, dz, dy = p._tracker.at(omega, True)
    amp = np.abs(x).max()
    track = (np.abs(z).sum() * amp + abs(s * y)) / p.length
    r_scale = np.concatenate([scale / p.rowscale, [track, track + 1.0]])
    jx = 5.0 * max(np.abs(Dx).max(), float(np.max(p.rho))) * p.n_coef
    jw = 5.0 * (product_scale(dDx, x).max() + dload.max()) * p.n_coef
    jt = (np.abs(z).sum() + np.abs(dz).sum() * amp + abs(ds * y) + abs(s * dy)) * p.colscale.max() / p.length
    j_scale = np.empty((p.n_x + 2, p.n_x + 3))
    j_scale[:p.n_x, :p.n_x] = jx * p.xscale[None, :] / p.rowscale[:, None]
    j_scale[:p.n_x, p.n_x:p.n_x + 2] = 0.0
    j_scale[:p.n_x, -1] = jw * p.omega_ref / p.rowscale
    j_scale[p.n_x:] = jt + 1.0
    return r_scale, j_scale


@pytest.mark.parametrize("case,H,ratios", [(_two_mass_damper, 15, (0.6, 0.95, 1.0, 1.3, 1.9)),
                                           (_beam, 13, (1.0, 1.1))])
def test_fused_evaluation_is_the_stepwise_one(case, H, ratios):
    """Scaled residual and Jacobian at converged orbits (stuck, stick-slip) and at perturbed
    iterates (other stick-slip patterns)."""
    model, force = case()
    p = FrictionForcedProblem(model, force, H)
    f1 = p.linear_frequency
    rng = np.random.default_rng(5)
    for ratio in ratios:
        u0 = p.start_point(ratio * f1)
        for u in (u0, u0 * (1.0 + 0.3 * rng.normal(size=u0.shape))):
            p._fused = None
            R, J = p._evaluate(u, True)
            R_only = p._evaluate(u, False)
            assert isinstance(p._fused, FusedFrictionEvaluation)
            p._fused = False  # the stepwise path
            try:
                R0, J0 = p._evaluate(u, True)
            finally:
                p._fused = None
            r_scale, j_scale = _tolerances(p, u)
            terms = p.n_x + 8 * p.n_coef
            assert_roundoff_close(R, R0, r_scale, terms, err_msg=f"R at {ratio} f1")
            assert_roundoff_close(R_only, R0, r_scale, terms, err_msg=f"R alone at {ratio} f1")
            assert_roundoff_close(J, J0, j_scale, terms, err_msg=f"J at {ratio} f1")


@pytest.mark.parametrize("case,H,ratios", [(_two_mass_damper, 15, (0.8, 1.0, 1.5)), (_beam, 13, (0.8, 1.1))])
def test_fused_record_is_the_stepwise_one(case, H, ratios):
    """The per-point records of the fused path against the stepwise records: amplitude,
    phase and energy through the recovered coefficients (solves with S_k, within
    cond(S_k)·ε of each other), slip fraction (switching instants refined to round-off) and
    the friction work (a Parseval sum of 2H terms)."""
    model, force = case()
    p = FrictionForcedProblem(model, force, H)
    f1 = p.linear_frequency
    eps = np.finfo(float).eps
    slipped = 0.0
    for ratio in ratios:
        u = p.start_point(ratio * f1)
        x, omega = p.unpack(u)
        p._fused = None
        got = p.monitor(u)
        assert p._fused.record_parts(x, omega, 1.0) is not None
        p._fused = False
        try:
            ref = p.monitor(u)
        finally:
            p._fused = None
        tr = p._tracker
        cond = max(np.linalg.cond(tr.K_ll + 1j * k * omega * tr.C_ll - (k * omega) ** 2 * tr.M_ll)
                   for k in range(H + 1))
        rel = 64 * cond * eps * p.n_coef
        for key in ("amplitude", "energy"):
            assert abs(got[key] - ref[key]) <= rel * abs(ref[key]) * (2 if key == "energy" else 1), key
        assert abs(got["phase"] - ref["phase"]) <= rel
        assert abs(got["slip_fraction"] - ref["slip_fraction"]) <= 1e3 * eps
        F = p._needed(x, omega, 1.0)
        work_scale = np.pi * p.H * np.abs(F).max() * np.abs(x).max() * p.n_coef
        tol = 8 * p.n_coef * eps * work_scale
        assert abs(got["friction_dissipation"] - ref["friction_dissipation"]) <= tol
        assert got["frequency"] == ref["frequency"]  # Ω / 2π of the same Ω
        slipped = max(slipped, ref["slip_fraction"])
    assert slipped > 0.1  # stuck and slipping orbits both checked
