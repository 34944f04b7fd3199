"""Impact with friction on one massless node by shooting (methods/friction_impact): the
frictionless limit against the exact event-driven impact orbit, an unreachable stop against
constant-load friction, convergence in the step, and the refusal of the other solvers."""

import numpy as np
import pytest

import mmshbm
from mmshbm.methods.exact.forced import forced_orbit
from mmshbm.methods.shooting.friction import friction_shooting_orbit
from mmshbm.methods.shooting.friction_impact import impact_friction_orbit

# two masses: x1 drives the node's normal DOF (stop), x2 its tangential DOF (friction)
M = np.diag([1.0, 1.0, 0.0, 0.0])
K = np.array([[1 + 0.5 + 4, -0.5, -4, 0], [-0.5, 1 + 0.5 + 2, 0, -2], [-4, 0, 4, 0], [0, -2, 0, 2]], float)
C = np.diag([0.05, 0.05, 0.0, 0.0])
F = np.array([0.1, 0.1, 0.0, 0.0])


def model(gap, mu, preload):
    base = mmshbm.Model.from_matrices(M, K, [2], [gap], [+1], damping=C, amplitude_dof=0)
    return base.with_friction(3, mu, normal_contact=0, preload=preload)


def test_without_friction_it_is_the_exact_impact_orbit():
    """μ = 0: the tangential node carries no force; x1 against the exact event-driven
    orbit: the trapezoidal rule's O(Δt²) with the impacts located within a step (measured
    below 1e-3 at 512 steps; asserted to shrink 3-fold per halving of the step)."""
    f = 0.18
    plain = mmshbm.Model.from_matrices(M, K, [2], [0.05], [+1], damping=C, amplitude_dof=0)
    exact = forced_orbit(plain, F, f)
    assert exact.converged
    ref = exact.amplitude(0)
    err = {}
    for n in (256, 512, 1024):
        _, ok, rec, _ = impact_friction_orbit(model(0.05, 0.0, 0.0), F, f, n)
        assert ok
        err[n] = abs(np.abs(rec[0][0]).max() / ref - 1)
        assert np.abs(rec[2]).max() == 0.0
    assert err[1024] < err[512] / 3 < err[256] / 9, err


def test_an_unreachable_stop_is_constant_load_friction():
    """A stop 10 m away never closes: λ = 0 and the slip force is μ·preload, the orbit of the
    constant-load shooting (same steps) to round-off."""
    f = 0.18
    _, ok, rec, _ = impact_friction_orbit(model(10.0, 0.3, 0.05), F, f, 512)
    assert ok and rec[1].max() == 0.0
    base = mmshbm.Model.from_matrices(M, K, [], [], [], damping=C, amplitude_dof=0)
    orbit = friction_shooting_orbit(base.with_friction(3, 0.3, normal_load=0.05), F, f, 512)
    assert orbit.converged
    assert np.abs(rec[0][1]).max() == pytest.approx(orbit.amplitude(1), rel=1e-10)


def test_impact_with_friction_converges_in_the_step():
    """The stop closes (λ up to 1.14 N) and the slip force follows μ(preload + λ): the
    orbit's x1 changes by 6.7e-4 and 1.6e-4 relative between 256/512 and 512/1024 steps."""
    f = 0.18
    amp = {}
    for n in (256, 512, 1024):
        _, ok, rec, sh = impact_friction_orbit(model(0.05, 0.3, 0.05), F, f, n)
        assert ok
        lam, g = rec[1], rec[2]
        assert lam.max() > 0.5 and np.all(lam >= 0)
        assert np.all(np.abs(g) <= 0.3 * (0.05 + lam) * (1 + 1e-9) + 1e-15)
        gap = 0.05 - (np.linalg.inv(K[2:, 2:]) @ (np.vstack([-lam, g]) - K[2:, :2] @ rec[0]))[0]
        assert gap.min() > -1e-12 and np.abs(gap * lam).max() < 1e-12
        amp[n] = np.abs(rec[0][0]).max()
    d1, d2 = abs(amp[512] / amp[256] - 1), abs(amp[1024] / amp[512] - 1)
    assert d2 < d1 / 3 and d2 < 5e-4


def test_other_solvers_refuse_it():
    with pytest.raises(NotImplementedError, match="not yet"):
        mmshbm.frequency_response(model(0.05, 0.3, 0.05), F, (0.1, 0.2), method="penalty")
