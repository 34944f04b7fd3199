"""The solid beam's tip face in impact with friction (``solid_tip_friction_model``) marched by
the shooting stepper's exact per-step law (methods/shooting/friction_march.py), against
the physical-coordinate stepper and against MMS-HBM's orbits (docs/friction.md)."""

import numpy as np
import pytest

from mmshbm.methods.mms.friction_forced import FrictionForcedProblem
from mmshbm.methods.shooting.friction_impact import ImpactFrictionShooting
from mmshbm.methods.shooting.friction_march import ImpactFrictionMarch, march_to_steady

MU, PRE, FREQ = 0.3, 0.05, 46.0


@pytest.fixture(scope="module")
def point():
    from mmshbm.fe.damper import solid_tip_friction_model
    from mmshbm.fe.solid import solid_force

    model = solid_tip_friction_model(mu=MU, preload=PRE, contact="point")  # 4 × 1 × 1, one contact node
    return model, solid_force(model, 20.0)


def _hbm_state(model, force, H):
    """(q_l, q_l', u_t) at τ = 0 of MMS-HBM's orbit at FREQ (the problem's own solve)."""
    p = FrictionForcedProblem(model, force, H)
    u, ok = p.solve_at(FREQ, p.linear_point(FREQ), 60, 1e-9)
    assert ok
    Q, om = p.coefficients(u), 2 * np.pi * FREQ
    q0, v0 = Q[:, 0] + Q[:, 1::2].sum(axis=1), om * (Q[:, 2::2] @ np.arange(1, H + 1))
    return np.concatenate([q0[model.l], v0[model.l], q0[[fc.dof for fc in model.friction]]])


@pytest.fixture(scope="module")
def hbm15(point):
    return _hbm_state(*point, 15)


def test_the_modal_march_is_the_physical_shooting_stepper(point, hbm15):
    """Newmark in the open modes equals Newmark in q_l: one period from the H = 15 orbit (an
    impact of 1.06 kN) at 512 steps, measured 1.0e-8 in q_l and 3.3e-8 in λ (relative); the
    modal damping's off-diagonal round-off (1.1e-8 of its diagonal) is dropped."""
    model, force = point
    e1, (q1, lam1, _, u1) = ImpactFrictionShooting(model, force, FREQ, 512).march(hbm15, record=True)
    e2, _, (q2, lam2, _, u2) = ImpactFrictionMarch(model, force, FREQ, 512).march(hbm15, record=True)
    n = len(model.l)
    assert lam1.max() > 500.0
    assert np.abs(e1[:n] - e2[:n]).max() <= 1e-7 * np.abs(e1[:n]).max()
    assert np.abs(q1 - q2).max() <= 1e-7 * np.abs(q1).max()
    assert np.abs(lam1 - lam2[:, 0]).max() <= 1e-5 * lam1.max()
    assert np.abs(u1 - u2[:, 0]).max() <= 1e-6 * np.abs(u1).max()


def test_mms_hbm_orbits_approach_a_period_of_the_exact_stepper(point, hbm15):
    """Relative change of q_l over one period of the exact stepper (8192 steps) started on
    MMS-HBM's orbit: measured 0.341, 1.98e-2, 1.00e-2 at H = 7, 15, 31; converged in Δt
    (32768 steps: 0.366, 1.99e-2, 9.83e-3; 131072: 0.364, 2.02e-2, 9.81e-3). Asserted: H = 15
    within 3e-2 and below H = 7's residual / 10."""
    model, force = point
    mr = ImpactFrictionMarch(model, force, FREQ, 8192)
    n = len(model.l)

    def residual(z):
        mr.reset()
        end, work = mr.march(z)
        return np.abs(end[:n] - z[:n]).max() / np.abs(z[:n]).max(), work

    r7, _ = residual(_hbm_state(model, force, 7))
    r15, work = residual(hbm15)
    assert work > 0
    assert r15 < 3e-2
    assert r15 < r7 / 10


@pytest.mark.slow
def test_the_march_from_rest_settles_on_a_period_doubled_orbit(point):
    """At 46 Hz the steady state of the exact stepper repeats after two periods, not one
    (MMS-HBM's T-periodic orbit is unstable there: Floquet multiplier 2.00 at H = 15).
    32768 steps (h ω_max = 2.5 on the tip layer's stiffest mode): from rest the change over
    two periods falls below 1e-7 after 85 periods, over one it stays 0.269; the periods'
    largest |q_l| 1.009515e-3 / 1.091223e-3 m (65536 steps: 1.009517e-3 / 1.091160e-3, so
    Δt moves it by 6e-5 relative: asserted within 5e-4 of 65536's), contact force peaks
    446.6 / 488.4 N (437.7 / 490.4), friction work 1.481e-4 / 2.046e-4 J (1.489e-4 /
    2.050e-4). At 8192 and 16384 steps the march does not settle (1e-3 over two periods)."""
    model, force = point
    orbit = march_to_steady(model, force, FREQ, 32768, max_periods=300, tol=1e-7, max_multiple=2)
    assert orbit.converged and orbit.multiple == 2
    assert orbit.change[-1, 0] > 0.2
    assert orbit.max_displacement == pytest.approx(1.091160e-3, rel=5e-4)
    assert 400.0 < orbit.contact_force_max < 600.0
    np.testing.assert_allclose(np.sort(orbit.work), [1.489e-4, 2.050e-4], rtol=2e-2)
