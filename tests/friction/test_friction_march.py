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


def _all_consistent(c, R, side, gap, mu, pre, u_old):
    """Every (λ, g) of a few contacts whose combination of {open, closed} × {stick, slip ±}
    per contact keeps every law: the 6^n_k linear solves, enumerated in plain NumPy."""
    import itertools

    nk = len(side)
    B = R * np.repeat(np.stack([-side, np.ones(nk)], axis=1).ravel()[None, :], 2 * nk, axis=0)
    found = []
    for combo in itertools.product(range(6), repeat=nk):
        E, r = np.zeros((2 * nk, 2 * nk)), np.zeros(2 * nk)
        for k, cb in enumerate(combo):
            n, t = 2 * k, 2 * k + 1
            if cb // 3 == 0:
                E[n, n] = 1.0
            else:
                E[n], r[n] = -side[k] * B[n], side[k] * c[n] - gap[k]
            if cb % 3 == 0:
                E[t], r[t] = B[t], u_old[k] - c[t]
            else:
                sg = 1.0 if cb % 3 == 1 else -1.0
                E[t, n], E[t, t], r[t] = -sg * mu[k], 1.0, sg * mu[k] * pre[k]
        x = np.linalg.solve(E, r)
        q = c + B @ x
        lam, g, ut = x[0::2], x[1::2], q[1::2]
        S, tol = mu * (pre + lam), 1e-12 * max(1.0, np.abs(x).max())
        ok = np.all(lam >= -tol) and np.all(gap - side * q[0::2] >= -1e-14 * gap)
        ok &= np.all(np.abs(lam * (gap - side * q[0::2])) <= 1e-9 * max(1.0, lam.max()) * gap)
        ok &= np.all(np.abs(g) <= S + tol)
        for k, cb in enumerate(combo):
            if cb % 3:
                sg = 1.0 if cb % 3 == 1 else -1.0
                ok &= bool(-sg * (ut[k] - u_old[k]) >= -1e-14 * max(abs(ut[k]), 1e-300))
        if ok:
            found.append(x)
    return found


def test_the_face_contacts_active_set_is_the_unique_consistent_state():
    """Three tip-face contacts (a corner, the centre, the opposite corner; their compliance
    in the face model at 8192 steps), random predictors that press about half the stops,
    stick and slip both: the primal–dual active set of the march returns the one combination
    of the 6³ whose laws all hold (enumerated in plain NumPy; each case has exactly one)."""
    from mmshbm.fe.damper import solid_tip_friction_model
    from mmshbm.fe.solid import solid_force
    from mmshbm.methods.shooting._march_kernels import _active_set

    model = solid_tip_friction_model(mu=MU, preload=PRE)
    mr = ImpactFrictionMarch(model, solid_force(model, 20.0), FREQ, 8192)
    pick = [0, 4, 8]
    idx = np.ravel([[2 * k, 2 * k + 1] for k in pick])
    R = np.ascontiguousarray(mr.R[np.ix_(idx, idx)])
    side, gap, mu, pre = (np.ascontiguousarray(a[pick]) for a in (mr.side, mr.gap, mr.mu, mr.pre))
    rng = np.random.default_rng(3)
    closed, slid = 0, 0
    for _ in range(15):
        c = np.empty(6)
        c[0::2] = side * gap + rng.normal(0.0, 2e-7, 3)
        c[1::2] = rng.normal(0.0, 1e-7, 3)
        u_old = rng.normal(0.0, 1e-7, 3)
        lam, g, ut = np.zeros(3), np.zeros(3), np.zeros(3)
        combo = np.zeros(3, dtype=np.int64)
        assert _active_set(c, R, side, gap, mu, pre, u_old, lam, g, ut, combo, 100) > 0
        found = _all_consistent(c, R, side, gap, mu, pre, u_old)
        assert len(found) == 1
        scale = max(np.abs(found[0]).max(), 1e-300)
        assert np.abs(lam - found[0][0::2]).max() <= 1e-9 * scale
        assert np.abs(g - found[0][1::2]).max() <= 1e-9 * scale
        closed += int(np.sum(lam > 0))
        slid += int(np.sum(combo % 3 > 0))
    assert closed > 10 and slid > 10
