"""The Jenkins (penalty) baseline with friction: the AFT hysteresis against its definition
and central differences; on the Jenkins oscillator, where the model's own spring makes
the Jenkins element exact, the linear limits in closed form and agreement with MMS-HBM at
equal H (both are Galerkin solutions of the same law; the AFT's sampling error vanishes as
N grows); as a penalty on a rigid contact, convergence toward the exact orbit as k_t grows."""

import numpy as np
import pytest

import mmshbm
from mmshbm.contact.coulomb import jenkins_hysteresis
from mmshbm.methods.exact.friction import friction_orbit
from mmshbm.methods.mms.friction_forced import FrictionForcedProblem
from mmshbm.methods.penalty.jenkins import JenkinsForcedProblem

M_, K1, K2, C_, F_ = 1.0, 1.0, 2.0, 0.05, 0.1


def jenkins(normal_load, mu=0.5):
    M = np.diag([M_, 0.0])
    K = np.array([[K1 + K2, -K2], [-K2, K2]])
    base = mmshbm.Model.from_matrices(M, K, [], [], [], damping=np.diag([C_, 0.0]), amplitude_dof=0)
    return base.with_friction(1, mu, normal_load=normal_load)


def test_hysteresis_is_periodic_bounded_and_differentiated_exactly():
    N = 64
    t = 2 * np.pi * np.arange(N) / N
    u = np.sin(t) + 0.3 * np.cos(3 * t)
    s, k = 0.5, 2.0
    f, df = jenkins_hysteresis(u, s, k)
    assert np.all(np.abs(f) <= s)
    g, fp = np.empty(N), f[-1]  # a third pass changes nothing
    for j in range(N):
        fp = np.clip(fp + k * (u[j] - u[j - 1]), -s, s)
        g[j] = fp
    assert np.abs(g - f).max() <= 8 * np.finfo(float).eps * s
    h = 1e-6
    J = np.empty((N, N))
    for i in range(N):
        e = np.zeros(N)
        e[i] = h
        J[:, i] = (jenkins_hysteresis(u + e, s, k)[0] - jenkins_hysteresis(u - e, s, k)[0]) / (2 * h)
    # piecewise linear in u away from switches: the differences are exact up to round-off
    assert np.abs(J - df).max() < 1e-8 * k
    small, _ = jenkins_hysteresis(0.1 * u, s, k)  # never slips: the symmetric stuck position
    assert np.abs(small - k * (0.1 * u - 0.1 * u.mean())).max() < 1e-15
    with pytest.raises(ValueError, match="stiffness"):
        jenkins_hysteresis(u, s, 0.0)


@pytest.mark.parametrize("normal_load, k", [(0.0, K1), (1000.0, K1 + K2)])
def test_physical_jenkins_limits_equal_the_linear_closed_forms(normal_load, k):
    f = 0.25
    w = 2 * np.pi * f
    X = F_ / (k - M_ * w**2 + 1j * C_ * w)
    p = JenkinsForcedProblem(jenkins(normal_load), [F_, 0.0], 5, tangential_stiffness="physical")
    Q = p.coefficients(p.start_point(f))
    assert Q.shape == (2, 11)
    np.testing.assert_allclose([Q[0, 1], -Q[0, 2]], [X.real, X.imag], atol=1e-10 * abs(X))
    assert np.abs(Q[0, 3:]).max() < 1e-10 * abs(X)


def test_physical_jenkins_agrees_with_mmshbm_at_equal_harmonics():
    """Measured against MMS-HBM at H = 7 (0.2 Hz, μN = 0.1 N): 1e-3 at N = 128, 4e-6 at
    1024, 3e-8 at 4096 relative in max|x|; both 7.0e-5 from the exact orbit."""
    model = jenkins(0.2)
    f, H = 0.2, 7
    mms = FrictionForcedProblem(model, [F_, 0.0], H)
    u, ok = mms.solve_at(f, mms.start_point(f))
    assert ok
    a_mms = mms.monitor(u)["amplitude"]
    diff = {}
    for N in (128, 1024, 4096):
        p = JenkinsForcedProblem(model, [F_, 0.0], H, tangential_stiffness="physical", n_samples=N)
        diff[N] = abs(p.monitor(p.start_point(f))["amplitude"] / a_mms - 1)
    assert diff[4096] < diff[1024] < diff[128]
    assert diff[4096] < 1e-6, diff
    exact = friction_orbit(model, [F_, 0.0], f).amplitude(0)
    assert abs(a_mms / exact - 1) < 1e-4


def test_penalty_tends_to_the_rigid_contact_as_the_spring_stiffens():
    """Jenkins spring k_t in series with the model's k2 = 2 N/m at H = 31: the orbit's error
    falls from 6.5e-2 (k_t = 20 N/m: the series stiffness is 9 % soft) to 3.7e-3 (200 N/m);
    beyond, the truncated node motion limits it (2.2e-3 at 2000 N/m, as the velocity form of
    MMS-HBM: a stiff spring asks the degree-H node displacement to stay put on stick arcs)."""
    model = jenkins(0.2)
    f = 0.2
    exact = friction_orbit(model, [F_, 0.0], f).amplitude(0)
    err = {}
    for kt in (20.0, 200.0):
        p = JenkinsForcedProblem(model, [F_, 0.0], 31, tangential_stiffness=kt, n_samples=1024)
        u, ok = p.solve_at(f, p.start_point(f))
        assert ok
        err[kt] = abs(p.monitor(u)["amplitude"] / exact - 1)
    assert err[200.0] < 0.1 * err[20.0] and err[200.0] < 5e-3, err


def test_penalty_method_of_frequency_response():
    model = jenkins(0.2)
    r = mmshbm.frequency_response(model, [F_, 0.0], (0.15, 0.25), harmonics=7, method="penalty",
                                  tangential_stiffness="physical", n_samples=1024)
    assert r.status.startswith("bound")
    m = mmshbm.frequency_response(model, [F_, 0.0], (0.15, 0.25), harmonics=7)
    f = r.frequency[len(r.frequency) // 2]
    assert np.interp(f, r.frequency, r.amplitude) == pytest.approx(np.interp(f, m.frequency, m.amplitude),
                                                                   rel=1e-3)
    work = np.asarray(r.records["friction_dissipation"])  # zero (round-off) while stuck
    assert work.min() > -1e-15 and work.max() > 0
