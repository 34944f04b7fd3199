"""The forced baselines (penalty harmonic balance, shooting) against the exact reference
on the one-DOF oscillator, and their Jacobians against finite differences."""

from __future__ import annotations

import numpy as np
import pytest
from finite_differences import assert_jacobian

import mmshbm
from mmshbm.core.bordered import bordered_solve
from mmshbm.core.continuation import newton
from mmshbm.methods.exact.forced import forced_orbit
from mmshbm.methods.mms.forced import ForcedResponseProblem
from mmshbm.methods.penalty.forced import PenaltyForcedProblem
from mmshbm.methods.shooting.forced import ShootingForcedProblem

F = np.array([0.1, 0.0])
FREQ = 0.185  # Hz: on the upper branch, one contact per period


@pytest.fixture(scope="module")
def osc():
    return mmshbm.OneDofOscillator(1, 1, 4, 1).model().with_damping(modal_ratio=0.02)


@pytest.fixture(scope="module")
def exact_orbit(osc):
    """The exact upper-branch orbit, started from MMS-HBM (H = 20) at FREQ."""
    resp = mmshbm.frequency_response(osc, F, (0.1, 0.2), harmonics=20, stability=False)
    i = int(np.flatnonzero((resp.frequency > FREQ - 0.004) & (resp.amplitude > 1.5))[0])
    p = ForcedResponseProblem(osc, F, harmonics=20, stability=False)
    u = _at_frequency(p, p.pack(resp.solver.unpack(resp.states[i])[0], 2 * np.pi * FREQ))
    Q = p.coefficients(u)
    k = np.arange(1, 21)
    w = 2 * np.pi * FREQ
    z0 = np.array([Q[0, 0] + Q[0, 1::2].sum(), w * (k * Q[0, 2::2]).sum()])
    orbit = forced_orbit(osc, F, FREQ, guess=z0)
    assert orbit.converged and orbit.n_contacts == 1
    return orbit


def _at_frequency(problem, u, tol=1e-10):
    """Newton at fixed frequency to a scaled residual of ``tol``: 1e-10 is above the
    round-off floor of the stiffest problem here (1e-12 to 4e-12 for penalty-HBM with
    k_p = 8e3 k_c, depending on the BLAS kernel and the start's last bits) and far below the
    accuracies these tests compare."""
    t = np.zeros(problem.n_unknowns)
    t[-1] = 1.0
    return newton(problem, u, t, u.copy(), tol, 40, 1e-12)[0]


def _fd(problem, u, h=1e-5):
    R, J = problem.evaluate(u)
    J = J.toarray() if hasattr(J, "toarray") else J
    assert_jacobian(lambda v: problem.evaluate(v, False), u, J, h)


def test_jacobians_match_finite_differences(osc):
    rng = np.random.default_rng(11)
    pen = PenaltyForcedProblem(osc, F, harmonics=4)
    u = pen.linear_point(0.17)
    u[:-1] += 0.3 * rng.standard_normal(len(u) - 1)
    u[2 + 1] += 2.0  # the contact DOF's cosine: into the stop
    _fd(pen, u)
    sh = ShootingForcedProblem(osc, F, steps_per_period=64)
    u = sh.linear_point(0.17)
    u[:-1] += 0.3 * rng.standard_normal(len(u) - 1)
    u[0] += 2.0
    _fd(sh, u)


def test_shooting_converges_at_order_two(osc, exact_orbit):
    errors, mults = [], []
    for N in (128, 256, 512):
        sh = ShootingForcedProblem(osc, F, steps_per_period=N)
        u = _at_frequency(sh, sh.pack(exact_orbit.z0, 2 * np.pi * FREQ))
        z, _ = sh.unpack(u)
        errors.append(np.abs(z - exact_orbit.z0).max() / np.abs(exact_orbit.z0).max())
        mults.append(np.abs(np.sort_complex(sh.floquet_multipliers(u))
                            - np.sort_complex(exact_orbit.multipliers)).max())
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(rates > 1.8) and errors[-1] < 2e-4  # measured rates 2.00, 2.00; 1.2e-4 at N = 512
    assert mults[-1] < mults[0] and mults[-1] < 1e-3


def test_penalty_approaches_the_exact_orbit(osc, exact_orbit):
    errs = []
    ref = exact_orbit.fourier(1, 20)
    for kp_factor in (1e2, 1e4):
        pen = PenaltyForcedProblem(osc, F, harmonics=20, penalty_stiffness=kp_factor * 0.8)
        Q = np.zeros(pen.n * pen.n_coef)
        Q.reshape(pen.n_coef, pen.n)[:, 1] = ref
        Q.reshape(pen.n_coef, pen.n)[:, 0] = exact_orbit.fourier(0, 20)
        # the penalty residual's round-off floor is 1e-12..4e-12 here, depending on the last
        # bits of the start: 1e-10 converges whatever they are (the errors compared are > 1e-4)
        u = _at_frequency(pen, pen.pack(Q, 2 * np.pi * FREQ), tol=1e-10)
        errs.append(np.abs(pen.coefficients(u)[1] - ref).max() / np.abs(ref).max())
    assert errs[1] < errs[0] < 0.1 and errs[1] < 0.01


def test_penalty_response_of_the_beam_covers_the_range():
    """8-element beam, 0.5 %, 2.3 N, 40–60 Hz, H = 5. With the sampled projection the
    response stopped at 57.6 Hz (`ds_min`: semismooth Newton cycling on a sample at the
    stop; 57.1 Hz on 21 elements); the exact one runs through. Below grazing penalty-HBM
    and MMS-HBM are both the linear response: equal to 1e-8, and each point converged to
    1e-8 of its amplitude (with rows scaled by |K| s the tolerance let points sit 1e-3 off)."""
    model = mmshbm.default_beam().model(8).with_damping(modal_ratio=0.005)
    force = np.zeros(model.n_dof)
    force[12] = 2.3
    pen = mmshbm.frequency_response(model, force, (40, 60), harmonics=5, method="penalty")
    assert pen.status == "bound:frequency" and pen.frequency[-1] == pytest.approx(60.0)
    assert pen.frequency.min() >= 40 * (1 - 1e-9)
    mms = mmshbm.frequency_response(model, force, (40, 60), harmonics=5, stability=False)
    p = pen.solver
    linear = PenaltyForcedProblem(model, force, harmonics=5, penalty_stiffness=1e-30 * p.penalty_stiffness[0])
    for resp in (pen, mms):
        below = np.arange(np.flatnonzero(resp.contact_force_max > 0)[0])
        assert len(below) >= 5
        ref = np.array([linear.monitor(linear.linear_point(f))["amplitude"] for f in resp.frequency[below]])
        assert np.abs(resp.amplitude[below] / ref - 1).max() < 1e-8
    # the grazing frequency, where the linear amplitude at the contact DOF reaches the gap
    f_g = pen.frequency[np.flatnonzero(pen.contact_force_max > 0)[0]]
    assert abs(p.monitor(pen.states[np.flatnonzero(pen.contact_force_max > 0)[0]])["amplitude"] - 1e-3) < 1e-5
    assert mms.frequency[np.flatnonzero(mms.contact_force_max > 0)[0] - 1] < f_g
    t = np.zeros(p.n_unknowns)
    t[-1] = 1.0
    for i in range(0, len(pen), 4):  # Newton at fixed Ω to the round-off floor
        u = pen.states[i].copy()
        for _ in range(4):
            R, J = p.evaluate(u)
            u -= bordered_solve(J, t, np.r_[R, t @ (u - pen.states[i])])
        assert abs(p.monitor(u)["amplitude"] / pen.amplitude[i] - 1) < 1e-8
