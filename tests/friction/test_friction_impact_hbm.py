"""Impact with friction by MMS-HBM (contact/coulomb_coupled.py, FrictionRows with
normal_contact=): the projection against a sampled sweeping process and its Jacobian against
central differences; the forced response in its limits (μ = 0 is the impact-only MMS-HBM, a
stop never reached is constant-load friction) and against shooting with the node's exact
prox per step (methods/friction_impact.py, converging as Δt²)."""

import numpy as np
import pytest

import mmshbm
from mmshbm.contact.coulomb_coupled import coupled_play_pieces, project_coulomb_play_coupled
from mmshbm.methods.mms.forced import ForcedResponseProblem
from mmshbm.methods.mms.friction_forced import FrictionForcedProblem
from mmshbm.methods.shooting.friction_impact import impact_friction_orbit

EPS = np.finfo(float).eps
RHO, MU, PRE, RN = 2.0, 0.3, 0.5, 4.0

# two masses: x1 drives the node's normal DOF (stop), x2 its tangential DOF (friction)
M = np.diag([1.0, 1.0, 0.0, 0.0])
K = np.array([[1 + 0.5 + 4, -0.5, -4, 0], [-0.5, 1 + 0.5 + 2, 0, -2], [-4, 0, 4, 0], [0, -2, 0, 2]], float)
C = np.diag([0.05, 0.05, 0.0, 0.0])
F = np.array([0.1, 0.1, 0.0, 0.0])


def model(gap, mu, preload):
    base = mmshbm.Model.from_matrices(M, K, [2], [gap], [+1], damping=C, amplitude_dof=0)
    return base.with_friction(3, mu, normal_contact=0, preload=preload)


def _signals(H=7, seed=1):
    rng = np.random.default_rng(seed)
    y = np.zeros(2 * H + 1)
    y[1], y[2] = 1.0, 0.3
    y[3:] = 0.05 * rng.standard_normal(2 * H - 2)
    z = np.zeros(2 * H + 1)
    z[0], z[1], z[2] = 0.2, 0.8, -0.4
    z[3:] = 0.03 * rng.standard_normal(2 * H - 2)
    return y, z


def _sampled_sweep(y, z, gap, n):
    """Projection of ρ (u − y) with u the sampled sweeping process u_j = clip(u_{j−1}, α_j, β_j)
    in the band y ± μ (N0 + r_n (z − gap)₊)/ρ, three passes over the period (plain NumPy)."""
    H = (len(y) - 1) // 2
    tau = 2 * np.pi * np.arange(n) / n
    k = np.arange(1, H + 1)
    E = np.empty((n, 2 * H + 1))
    E[:, 0], E[:, 1::2], E[:, 2::2] = 1.0, np.cos(np.outer(tau, k)), np.sin(np.outer(tau, k))
    ys, zs = E @ y, E @ z
    w = MU * (PRE + RN * np.maximum(zs - gap, 0.0)) / RHO
    lo, hi = ys - w, ys + w
    u, us = ys[0], np.empty(n)
    for _ in range(3):
        for j in range(n):
            u = min(max(u, lo[j]), hi[j])
            us[j] = u
    c = E.T @ (RHO * (us - ys)) / n
    c[1:] *= 2
    band_speed = np.abs(np.diff(np.concatenate([lo, hi]))).max()  # per sample, both edges
    return c, band_speed


@pytest.mark.parametrize("gap", [0.3, 0.6, 0.9, 10.0])
def test_projection_is_the_sampled_sweeping_process(gap):
    """The sampled process lags the exact one by at most one sample's motion of the band, so
    the projections differ by at most 2ρ × (largest band change per sample) (coefficients
    carry a factor 2). gap = 0.3 includes a stick set at a closing instant (a kink of α)."""
    y, z = _signals()
    g = project_coulomb_play_coupled(y, z, RHO, MU, PRE, RN, gap)[0]
    ref, speed = _sampled_sweep(y, z, gap, 2**15)
    assert np.abs(g - ref).max() <= 2 * RHO * speed


def test_projection_far_from_the_stop_is_constant_load_play():
    from mmshbm.contact.coulomb import project_coulomb_play

    y, z = _signals()
    g, Jy, Jz, slip = project_coulomb_play_coupled(y, z, RHO, MU, PRE, RN, 10.0)
    g0, J0, slip0 = project_coulomb_play(y, MU * PRE, RHO)
    assert np.abs(g - g0).max() <= 64 * EPS * RHO * np.abs(y).max()
    assert np.abs(Jy - J0).max() <= 64 * EPS * RHO and np.abs(Jz).max() == 0.0
    assert slip == pytest.approx(slip0, abs=1e-14)


def _g(x, n, gap):
    return project_coulomb_play_coupled(x[:n], x[n:], RHO, MU, PRE, RN, gap, jacobian=False)[0]


@pytest.mark.parametrize("gap", [0.3, 0.6, 0.9])
def test_jacobian_is_exact(gap):
    """Against central differences in (y, z): truncation by Richardson, (D(2h) − D(h))/3,
    round-off by 64 ε max|g| / h; the exact Jacobian within twice their sum. At gap = 0.3
    one stick arc starts where the contact closes: its ∂u_s/∂z = −(y′/z′) φ(τ_e) is tested."""
    y, z = _signals()
    if gap == 0.3:
        kinks = [p for p in coupled_play_pieces(y, z, MU * PRE / RHO, MU * RN / RHO, gap)
                 if p[2] == 0 and p[5] not in (0.0, -MU * RN / RHO)]
        assert kinks
    g0, Jy, Jz, _ = project_coulomb_play_coupled(y, z, RHO, MU, PRE, RN, gap)
    J = np.hstack([Jy, Jz])
    x0 = np.concatenate([y, z])
    n = len(y)

    def central(h):
        D = np.empty((n, 2 * n))
        for j in range(2 * n):
            e = np.zeros(2 * n)
            e[j] = h
            D[:, j] = (_g(x0 + e, n, gap) - _g(x0 - e, n, gap)) / (2 * h)
        return D

    h = 1e-5
    D1, D2 = central(h), central(2 * h)
    bound = np.abs(D2 - D1).max() / 3 + 64 * EPS * (np.abs(g0).max() + RHO * np.abs(x0).max()) / h
    assert np.abs(D1 - J).max() <= 2 * bound


@pytest.mark.parametrize("H", [7, 15])
def test_without_friction_it_is_the_impact_only_response(H):
    """μ = 0: the friction rows say F_t = 0, those of a free massless DOF; the converged
    coefficients solve the impact-only MMS-HBM equations to round-off (scaled residual)."""
    f = 0.18
    pr = FrictionForcedProblem(model(0.05, 0.0, 0.05), F, harmonics=H)
    u = pr.start_point(f)
    assert np.abs(pr.evaluate(u, jacobian=False)).max() < 1e-11
    x, omega = pr.unpack(u)
    impact_only = mmshbm.Model.from_matrices(M, K, [2], [0.05], [+1], damping=C, amplitude_dof=0)
    plain = ForcedResponseProblem(impact_only, F, harmonics=H, stability=False)
    assert np.abs(plain.evaluate(plain.pack(x, omega), jacobian=False)).max() < 1e-11
    assert pr.monitor(u)["contact_force_max"] > 1.0  # the stop does close


@pytest.mark.parametrize("H", [7, 15])
def test_an_unreachable_stop_is_constant_load_friction(H):
    f = 0.18
    pr = FrictionForcedProblem(model(10.0, 0.3, 0.05), F, harmonics=H)
    base = mmshbm.Model.from_matrices(M, K, [2], [10.0], [+1], damping=C, amplitude_dof=0)
    pc = FrictionForcedProblem(base.with_friction(3, 0.3, normal_load=0.05), F, harmonics=H)
    x = pr.unpack(pr.start_point(f))[0]
    xc = pc.unpack(pc.start_point(f))[0]
    assert np.abs(x - xc).max() <= 1e-12 * np.abs(xc).max()


@pytest.mark.parametrize("coupled", [False, True])
def test_against_shooting(coupled):
    """μ = 0.3, preload 0.05 N, 0.18 Hz (λ up to 1.14 N, slip 87 % of the period). Shooting
    at 1024 and 2048 steps extrapolated (Δt², its remaining error bounded by the Richardson
    correction itself); MMS-HBM at H = 63, its truncation error bounded by its change from
    H = 31. Measured: 4e-6 (x1) and 1.3e-5 (x2) relative. ``coupled``: a spring of 1 N/m
    between the node's normal and tangential DOFs (K_cc not diagonal, so y carries λ's
    kinks): 5.6e-6 and 2.0e-5."""
    f, m = 0.18, model(0.05, 0.3, 0.05)
    if coupled:
        Kc = K.copy()
        Kc[2, 2] += 1.0
        Kc[3, 3] += 1.0
        Kc[2, 3] = Kc[3, 2] = -1.0
        base = mmshbm.Model.from_matrices(M, Kc, [2], [0.05], [+1], damping=C, amplitude_dof=0)
        m = base.with_friction(3, 0.3, normal_contact=0, preload=0.05)
    ref = {}
    for n in (1024, 2048):
        _, ok, rec, _ = impact_friction_orbit(m, F, f, n)
        assert ok
        ref[n] = np.array([np.abs(rec[0][0]).max(), np.abs(rec[0][1]).max()])
    corr = (ref[2048] - ref[1024]) / 3
    extrap = ref[2048] + corr
    amp = {}
    for H in (31, 63):
        pr = FrictionForcedProblem(m, F, harmonics=H)
        u = pr.start_point(f)
        assert np.abs(pr.evaluate(u, jacobian=False)).max() < 1e-10
        _, q = pr.time_signals(u, dofs=[0, 1], n_samples=8192)
        amp[H] = np.abs(q).max(axis=1)
    bound = np.abs(amp[63] - amp[31]) + np.abs(corr)
    assert np.all(np.abs(amp[63] - extrap) <= bound), (amp, extrap, bound)
    assert np.all(np.abs(amp[63] / extrap - 1) < 1e-4)


def test_velocity_form_and_other_solvers_refuse_it():
    with pytest.raises(NotImplementedError, match="play form only"):
        FrictionForcedProblem(model(0.05, 0.3, 0.05), F, law="velocity")
    with pytest.raises(NotImplementedError, match="Jenkins"):
        mmshbm.frequency_response(model(0.05, 0.3, 0.05), F, (0.1, 0.2), method="penalty")


def test_problem_jacobian_against_central_differences():
    """The scaled Jacobian (with ∂/∂ the normal contact's coefficients and Ω) near a
    converged point where the stop closes and the node sticks and slips; tolerance:
    Richardson estimate of the truncation error plus 64 ε (max|R| + max|J| max|u|) / h."""
    p = FrictionForcedProblem(model(0.05, 0.3, 0.05), F, harmonics=5)
    u0 = p.start_point(0.18)
    u0 = u0 * (1 + 1e-4 * np.sin(np.arange(len(u0))))  # off the solution: R ≠ 0
    R0, J = p.evaluate(u0)
    n = len(u0)

    def central(h):
        D = np.empty((len(R0), n))
        for j in range(n):
            e = np.zeros(n)
            e[j] = h
            D[:, j] = (p.evaluate(u0 + e, jacobian=False) - p.evaluate(u0 - e, jacobian=False)) / (2 * h)
        return D

    h = 1e-6
    D1, D2 = central(h), central(2 * h)
    trunc = np.abs(D2 - D1).max() / 3
    roundoff = 64 * EPS * (np.abs(R0).max() + np.abs(J).max() * np.abs(u0).max()) / h
    assert np.abs(D1 - J).max() <= 2 * (trunc + roundoff)
    # the friction rows do depend on the normal DOF's coefficients
    c = p.model.c
    rows = p._coef_index[int(np.searchsorted(c, 3))]
    cols = p._coef_index[int(np.searchsorted(c, 2))]
    assert np.abs(J[np.ix_(rows, cols)]).max() > 1e-3
