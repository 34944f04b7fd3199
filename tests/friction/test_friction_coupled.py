"""Impact with friction (``normal_contact=``) beyond the forced MMS-HBM response: the EPMC
(damped nonlinear modes) against the shooting stepper's period map, the Jenkins baseline's
refusal, and the solid beam's tip face (fe/damper.py ``solid_tip_friction_model``)."""

import warnings

import numpy as np
import pytest

import mmshbm
from mmshbm.methods.mms.friction_epmc import FrictionEPMCProblem
from mmshbm.methods.mms.friction_forced import FrictionForcedProblem
from mmshbm.methods.shooting.friction_impact import ImpactFrictionShooting

# two masses: x1 drives the node's normal DOF (stop at 0.05 m), x2 its tangential DOF
M = np.diag([1.0, 1.0, 0.0, 0.0])
K = np.array([[1 + 0.5 + 4, -0.5, -4, 0], [-0.5, 1 + 0.5 + 2, 0, -2], [-4, 0, 4, 0], [0, -2, 0, 2]], float)
C = np.diag([0.05, 0.05, 0.0, 0.0])
MU, PRE, GAP = 0.3, 0.05, 0.05


def two_mass(gap=GAP, damping=C, **friction):
    base = mmshbm.Model.from_matrices(M, K, [2], [gap], [+1], damping=damping, amplitude_dof=0)
    return base.with_friction(3, MU, **(friction or {"normal_contact": 0, "preload": PRE}))


def _backbone(model, H, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mmshbm.BranchWarning)
        return mmshbm.backbone(model, harmonics=H, **kw)


def _period_map_residual(H):
    """Relative change of (q_l, q_l′/Ω) over one period of the shooting stepper (2048 steps,
    the node's exact prox per step) started on the EPMC orbit at amplitude 0.5 m and run with
    damping C − ξM and no force: 0 for an exact periodic orbit of the EPMC's equations."""
    model = two_mass()
    branch = _backbone(model, H, max_amplitude=0.5)
    p = FrictionEPMCProblem(model, H)
    u = branch.states[-1]
    _, _, _, xi, om = p.unpack(u)
    Q = p.coefficients(u)
    k = np.arange(1, H + 1)
    q0, v0 = Q[:, 0] + Q[:, 1::2].sum(axis=1), om * (Q[:, 2::2] @ k)
    sh = ImpactFrictionShooting(two_mass(damping=C - xi * M), np.array([1e-300, 0, 0, 0]), om / (2 * np.pi),
                                2048)
    z = np.concatenate([q0[:2], v0[:2], [q0[3]]])
    end, (_, lam, _, _) = sh.march(z, record=True)
    amp = np.abs(z[:2]).max()
    return max(np.abs(end[:2] - z[:2]).max(), np.abs(end[2:4] - z[2:4]).max() / om) / amp, lam.max()


def test_epmc_with_impact_and_friction_is_a_periodic_orbit_of_the_shooting_stepper():
    """Measured 7.6e-4, 1.8e-4, 3.7e-5, 2.1e-6 (q) at H = 7, 15, 31, 63 (1.0e-3, 5.6e-4, 1.4e-4,
    6.0e-6 in q′/Ω); the stepper's own error at 2048 steps is below 1e-6 (1024 steps agree to
    2e-7 at H = 31). Asserted: H = 15 within 8e-4, and H = 15 below H = 7's residual / 1.3."""
    r7, lam7 = _period_map_residual(7)
    r15, lam15 = _period_map_residual(15)
    assert lam7 > 0.1 and lam15 > 0.1  # the stop closes on the orbit (λ up to ~1 N)
    assert r15 < 8e-4
    assert r15 < r7 / 1.3


def test_epmc_with_a_stop_never_reached_is_constant_load_friction():
    far = dict(max_amplitude=0.5, start_amplitude=0.01, max_steps=30)
    coupled = _backbone(two_mass(gap=5.0), 7, **far)
    constant = _backbone(two_mass(gap=5.0, normal_load=PRE), 7, **far)
    assert len(coupled.frequency) == len(constant.frequency) > 10
    np.testing.assert_allclose(coupled.frequency, constant.frequency, rtol=1e-12)
    np.testing.assert_allclose(coupled.damping_ratio, constant.damping_ratio, rtol=1e-10)


def test_epmc_refuses_a_coupled_contact_without_preload():
    with pytest.raises(ValueError, match="preload > 0"):
        FrictionEPMCProblem(two_mass(normal_contact=0, preload=0.0), 5)


def test_jenkins_baseline_refuses_normal_contact_by_name():
    with pytest.raises(NotImplementedError, match="normal_contact=.*Jenkins baseline"):
        mmshbm.frequency_response(two_mass(), [0.1, 0.1, 0, 0], (0.15, 0.2), method="penalty")


# ---------------------------------------------------------------------- the solid beam's tip face
@pytest.fixture(scope="module")
def solid():
    from mmshbm.fe.damper import solid_tip_friction_model

    return solid_tip_friction_model(mu=MU, preload=PRE)  # 4 × 1 × 1 order-2 elements, f_1 = 49.7 Hz


def test_solid_tip_friction_model_couples_each_tangential_dof_to_its_own_contact(solid):
    from mmshbm.fe.solid import _kept_locations

    d = solid.description
    loc, comp = _kept_locations(mmshbm.default_beam(), d)
    assert len(solid.contacts) == 9 and len(solid.friction) == 9  # order 2, 1 × 1 elements: 3 × 3 face nodes
    massless = set(solid.c.tolist())
    for fc in solid.friction:
        ct = solid.contacts[fc.normal_contact]
        assert fc.dof in massless and comp[fc.dof] == 0 and comp[ct.dof] == 2
        np.testing.assert_array_equal(loc[:, fc.dof], loc[:, ct.dof])
        assert loc[0, fc.dof] == pytest.approx(mmshbm.default_beam().length)
    assert [t["name"] for t in d["transforms"]] == ["with_damping"] + ["with_friction"] * 9


def test_solid_tip_face_with_a_stop_never_reached_is_constant_load_friction(solid):
    """With the plane far away the coupled rows are those of constant loads μ·preload: the
    same solution (measured 1.7e-15 relative; both solved to the scaled tolerance 1e-9)."""
    from dataclasses import replace

    from mmshbm.fe.solid import solid_force

    far = replace(solid, contacts=tuple(replace(ct, gap=1.0) for ct in solid.contacts))
    const = replace(far, friction=())  # the same model with constant loads
    for fc in solid.friction:
        const = const.with_friction(fc.dof, MU, normal_load=PRE)
    F = solid_force(solid, 1.0)
    a, b = FrictionForcedProblem(far, F, 3), FrictionForcedProblem(const, F, 3)
    ua, oka = a.solve_at(45.0, a.linear_point(45.0), 60, 1e-9)
    ub, okb = b.solve_at(45.0, b.linear_point(45.0), 60, 1e-9)
    assert oka and okb
    xa, xb = a.unpack(ua)[0], b.unpack(ub)[0]
    assert np.abs(xa - xb).max() <= 1e-9 * np.abs(xb).max()


def test_solid_tip_face_impact_with_friction_forced_response(solid):
    """At 46 Hz (0.93 f_1, 20 N at mid-span) the stop closes (contact force ~22 N), the tip face
    slides in x over most of the period and dissipates."""
    from mmshbm.fe.solid import solid_force

    F = solid_force(solid, 20.0)
    p = FrictionForcedProblem(solid, F, 7)
    u, ok = p.solve_at(46.0, p.linear_point(46.0), 60, 1e-9)
    assert ok
    mon, rec = p.monitor(u), p.friction_records(*p.unpack(u))
    assert mon["contact_force_max"] > 1.0
    assert rec["friction_dissipation"] > 0 and 0.5 < rec["slip_fraction"] <= 1.0
