"""Floquet multipliers of friction orbits (methods/friction_stability.py) against the
Jacobian of the exact event-driven period map (methods/exact/friction.py) by central
differences, the full-stick limit, and the forced response's stability records."""

import numpy as np
import pytest

import mmshbm
from mmshbm.methods.exact.friction import friction_orbit
from mmshbm.methods.mms.friction_forced import FrictionForcedProblem
from mmshbm.methods.mms.friction_stability import EIGEN_CONDITION_LIMIT, PhaseExponentials

# Jenkins oscillator: mass on k1 to ground and k2 to a massless node with Coulomb friction
M_, K1, K2, C_, F_ = 1.0, 1.0, 2.0, 0.05, 0.1


def jenkins(normal_load, mu=0.5):
    M = np.diag([M_, 0.0])
    K = np.array([[K1 + K2, -K2], [-K2, K2]])
    base = mmshbm.Model.from_matrices(M, K, [], [], [], damping=np.diag([C_, 0.0]), amplitude_dof=0)
    return base.with_friction(1, mu, normal_load=normal_load)


def _exact_multipliers(model, f):
    """Eigenvalues of the central-difference Jacobian of the exact period map of the state
    (q, q', u) at t = 0, sorted by decreasing modulus (step 1e-6; the map is smooth near a
    slipping orbit whose switches are transversal)."""
    orb = friction_orbit(model, [F_, 0.0], f)
    assert orb.converged
    y0, n = orb.y0, len(orb.y0)
    J = np.empty((n, n))
    for j in range(n):
        h = 1e-6 * max(1.0, abs(y0[j]))
        e = np.zeros(n)
        e[j] = h
        J[:, j] = (orb.system.period_map(y0 + e) - orb.system.period_map(y0 - e)) / (2 * h)
    mu = np.linalg.eigvals(J)
    return mu[np.argsort(-np.abs(mu), kind="stable")]


@pytest.mark.parametrize("f", [0.2, 0.25])
def test_multipliers_against_the_exact_period_map(f):
    """Slipping orbits (64 % and 54 % slip): the multipliers of the flow linearised about the
    HBM orbit converge to those of the exact period map as the orbit does. Measured
    |μ_H − μ_exact| (largest pair): 9.0e-4 / 1.6e-5 / 1.0e-5 (0.2 Hz) and 7.7e-5 / 4.9e-5 /
    6.6e-6 (0.25 Hz) at H = 7 / 15 / 31. Asserted: below 1e-4 at H = 31 (the orbit itself is
    5e-7 off at H = 31, the stick arcs' ends less precisely), and the stuck position's
    multiplier 0 (the node slips within the period: its position is forgotten)."""
    model = jenkins(0.2)
    ref = _exact_multipliers(model, f)
    p = FrictionForcedProblem(model, [F_, 0.0], 31, stability=True)
    u = p.start_point(f)
    mu = p.monitor(u)["floquet"]
    assert len(mu) == len(ref) == 3
    assert np.abs(mu[:2] - ref[:2]).max() < 1e-4 or np.abs(mu[:2] - ref[1::-1]).max() < 1e-4
    assert abs(mu[2]) < 1e-12 and abs(ref[2]) < 1e-6


def test_full_stick_is_the_clamped_linear_system():
    """N = 1000 N: the node sticks throughout. The multipliers are those of the linear
    structure with the node clamped (exp of its generator over T, closed form by eigvals)
    and 1 for the stuck position (history, neutral)."""
    f = 0.2
    p = FrictionForcedProblem(jenkins(1000.0), [F_, 0.0], 5, stability=True)
    u = p.start_point(f)
    rec = p.monitor(u)
    assert rec["slip_fraction"] == 0.0
    lam = np.roots([M_, C_, K1 + K2])
    ref = np.exp(lam * (1 / f))
    mu = rec["floquet"]
    assert abs(mu[0] - 1.0) < 1e-12
    assert np.abs(np.sort_complex(mu[1:]) - np.sort_complex(ref)).max() < 1e-12


def test_frequency_response_records_stability():
    """Every point is stable; where the node slips the largest multiplier is below 1, where
    it sticks throughout it is the stuck position's neutral 1."""
    r = mmshbm.frequency_response(jenkins(0.2), [F_, 0.0], (0.15, 0.3), harmonics=7, stability=True)
    assert r.completed and len(r.frequency) > 10 and np.all(r.stable)
    slipping = r.records["slip_fraction"] > 0
    assert slipping.any() and (~slipping).any()
    assert np.all(r.floquet_max[slipping] < 1.0)
    assert np.abs(r.floquet_max[~slipping] - 1.0).max() < 1e-12


# impact with friction: two masses driving a node's normal DOF (stop) and tangential DOF
M2 = np.diag([1.0, 1.0, 0.0, 0.0])
K2_ = np.array([[1 + 0.5 + 4, -0.5, -4, 0], [-0.5, 1 + 0.5 + 2, 0, -2], [-4, 0, 4, 0], [0, -2, 0, 2]], float)
C2 = np.diag([0.05, 0.05, 0.0, 0.0])
F2 = np.array([0.1, 0.1, 0.0, 0.0])


def impact_model(mu, preload=0.05):
    base = mmshbm.Model.from_matrices(M2, K2_, [2], [0.05], [+1], damping=C2, amplitude_dof=0)
    return base.with_friction(3, mu, normal_contact=0, preload=preload)


def test_coupled_without_friction_is_the_impact_floquet():
    """μ = 0: the multipliers are those of the impact-only orbit's piecewise-linear flow
    (methods/stability.py) and one 0 (the tangential node slips throughout)."""
    from mmshbm.methods.mms.forced import ForcedResponseProblem

    p = FrictionForcedProblem(impact_model(0.0), F2, 15, stability=True)
    u = p.start_point(0.18)
    mu = p.monitor(u)["floquet"]
    plain = mmshbm.Model.from_matrices(M2, K2_, [2], [0.05], [+1], damping=C2, amplitude_dof=0)
    q = ForcedResponseProblem(plain, F2, 15, stability=True)
    ref = q.floquet_multipliers(q.start_point(0.18))
    assert abs(mu[-1]) < 1e-12
    assert np.abs(np.sort_complex(mu[:-1]) - np.sort_complex(ref)).max() < 1e-9


def test_coupled_against_shooting():
    """μ = 0.3: against the eigenvalues of the shooting period map's Jacobian (2048 steps,
    central differences; 1024 steps differ by 4e-4). The contact phases are the exact flow's
    at the orbit's q_l(τ), the stick arcs the play pieces' (read on the truncated normal
    signal): measured 2.3e-3 (H = 31) and 4.9e-3 (H = 63) off, with a change of 5.8e-3
    from H = 31 to 63; asserted within twice that change plus the shooting's own change."""
    from mmshbm.methods.shooting.friction_impact import impact_friction_orbit

    m = impact_model(0.3)
    ref = {}
    for n in (1024, 2048):
        z, ok, _, sh = impact_friction_orbit(m, F2, 0.18, n)
        assert ok
        J = np.empty((len(z), len(z)))
        for j in range(len(z)):
            h = 1e-7 * max(1.0, abs(z[j]))
            e = np.zeros(len(z))
            e[j] = h
            J[:, j] = (sh.march(z + e) - sh.march(z - e)) / (2 * h)
        ref[n] = np.sort_complex(np.linalg.eigvals(J))
    mu = {}
    for H in (31, 63):
        p = FrictionForcedProblem(m, F2, H, stability=True)
        mu[H] = np.sort_complex(p.monitor(p.start_point(0.18))["floquet"])
    bound = 2 * np.abs(mu[63] - mu[31]).max() + np.abs(ref[2048] - ref[1024]).max()
    assert np.abs(mu[31] - ref[2048]).max() <= bound
    assert np.abs(mu[31] - ref[2048]).max() < 1e-2


class _Recorded(PhaseExponentials):
    """PhaseExponentials that keeps, per exponential taken, its norm and the bound on its
    error: eig's backward error (k u ‖AΔt‖, k the size, u the unit roundoff) and forming
    V e^{ΛΔt} V⁻¹ (k u κ(V)), relative to κ(V) max|e^{λΔt}| (≥ ‖e^{AΔt}‖); expm's own error
    (k u ‖AΔt‖) is inside the same bound."""

    def __init__(self, condition_limit=EIGEN_CONDITION_LIMIT):
        super().__init__(condition_limit)
        self.norms, self.errors = [], []

    def __call__(self, key, A, dt):
        E = super().__call__(key, A, dt)
        lam, V = np.linalg.eig(A)
        kappa, k, u = np.linalg.cond(V), A.shape[0], np.finfo(float).eps / 2
        self.norms.append(np.linalg.norm(E, 2))
        scale = kappa * np.abs(np.exp(lam * dt)).max()
        self.errors.append(k * u * (kappa + 2 * np.linalg.norm(A * dt, 2)) * scale)
        return E


@pytest.mark.parametrize("normal_load, f", [(0.2, 0.2), (0.2, 0.25), (0.2, 0.16), (1000.0, 0.2)])
def test_eigendecomposed_phases_agree_with_expm(normal_load, f):
    """The monodromy from each state's eigendecomposition equals the one from expm per phase
    (condition_limit 0 forces expm) to the error both bound: per exponential the bound of
    _Recorded, carried through the product of the factors (first order: each factor's error
    times the other factors' norms, the resets' included) and onto the multipliers by
    Bauer-Fike (κ of the monodromy's eigenvectors). Measured: 3e-16 to 5e-15, bounds 7e-14 to 1e-12."""
    p = FrictionForcedProblem(jenkins(normal_load), [F_, 0.0], 15, stability=True)
    u = p.start_point(f)
    fl = p._floquet
    resets, phis = [], []
    reset, monodromy = fl.reset, fl.monodromy
    fl.reset = lambda stuck, j: resets.append(reset(stuck, j)) or resets[-1]
    fl.monodromy = lambda arcs, omega: phis.append(monodromy(arcs, omega)) or phis[-1]
    fl.exponential = PhaseExponentials(condition_limit=0.0)
    mu_expm = p.floquet_multipliers(u)
    resets.clear()
    fl.exponential = rec = _Recorded()
    mu = p.floquet_multipliers(u)
    assert rec._eig and all(v is not False for v in rec._eig.values())  # the eigendecomposed path ran
    norms = np.maximum(rec.norms, 1.0)
    others = np.prod(norms) * np.prod([max(np.linalg.norm(R, 2), 1.0) for R in resets])
    bound_phi = others * np.sum(np.array(rec.errors) / norms)
    bound = np.linalg.cond(np.linalg.eig(phis[-1])[1]) * bound_phi
    distance = max(np.abs(mu_expm - m).min() for m in mu)
    assert len(mu) == 3 and distance <= bound, (distance, bound)


def test_phase_exponentials_against_closed_forms():
    """A damped oscillator's generator (diagonalisable) against its closed-form exponential,
    and a free mass's (defective: a Jordan block, κ(V) = ∞) taken by expm: exp([[0, 1],
    [0, 0]] t) = [[1, t], [0, 1]]. Tolerance: the eigendecomposition's κ(V)·ε with κ(V) ≈ 1/ζ
    (the eigenvectors of λ = −ζω ± iω_d are ζ apart) times the entries' scale ω, margin 100."""
    w, z, t = 2.0, 0.05, 3.7
    A = np.array([[0.0, 1.0], [-w * w, -2 * z * w]])
    wd = w * np.sqrt(1 - z * z)
    c, s, e = np.cos(wd * t), np.sin(wd * t), np.exp(-z * w * t)
    exact = e * np.array([[c + z * w / wd * s, s / wd], [-w * w / wd * s, c - z * w / wd * s]])
    ex = PhaseExponentials()
    got = ex("oscillator", A, t)
    assert ex._eig["oscillator"] is not False
    assert np.abs(got - exact).max() <= 100 * (1 / z) * np.finfo(float).eps * w
    free = ex("free", np.array([[0.0, 1.0], [0.0, 0.0]]), t)
    assert ex._eig["free"] is False
    np.testing.assert_allclose(free, [[1.0, t], [0.0, 1.0]], rtol=0, atol=4 * np.finfo(float).eps * t)
