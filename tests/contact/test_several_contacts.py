"""Several contacts and clearances in penalty-HBM, shooting and the exact reference.

Ground truths independent of the code under test: the closed-form period of the one-DOF
oscillator in a symmetric clearance (:class:`~mmshbm.fe.oscillator.ClearanceOscillator`,
itself checked against DOP853), two identical uncoupled oscillators (the backbone of one),
finite differences of the Jacobians, plain-NumPy references of the residuals and of the
time step, and an enumeration of the contact LCP. The figures are reported in
docs/penalty.md, docs/shooting.md and docs/exact.md.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import scipy.linalg as la
from finite_differences import assert_jacobian
from scipy.integrate import solve_ivp

import mmshbm
from mmshbm import ClearanceOscillator, Model, OneDofOscillator
from mmshbm.contact.lcp import lcp_solve
from mmshbm.core.continuation import ContinuationOptions, continue_branch
from mmshbm.methods import exact
from mmshbm.methods.penalty.hbm import PenaltyHBMProblem
from mmshbm.methods.shooting.conservative import ShootingProblem

CO = ClearanceOscillator(m=1.0, k1=1.0, k2=4.0, gap=1.0)
OSC = OneDofOscillator(m=1.0, k1=1.0, k2=4.0, gap=1.0)


def pair(osc: OneDofOscillator = OSC) -> Model:
    """Two identical uncoupled oscillators, one contact each, the amplitude at mass 0."""
    one = osc.model()
    M = la.block_diag(one.M.toarray(), one.M.toarray())
    K = la.block_diag(one.K.toarray(), one.K.toarray())
    return Model.from_matrices(M, K, contact_dof=[1, 3], gap=osc.gap, stop_side=1, amplitude_dof=0)


def chain2(gaps=(0.5, 0.4)) -> Model:
    """Four masses in a chain, a massless node with two DOFs (u, θ) coupled to each other
    and to the chain: a stop on each (u at +gap, θ at −gap), so the contacts are coupled
    through K_cc (a full Delassus matrix)."""
    n = 6
    springs = [((0,), (1.0,), 1.0), ((1, 0), (1, -1), 1.0), ((2, 1), (1, -1), 1.5),
               ((3, 2), (1, -1), 1.0), ((4, 3), (1, -1), 3.0), ((5, 2), (1, -1), 2.0),
               ((4, 5), (1, -1), 5.0)]
    K = np.zeros((n, n))
    for idx, coef, k in springs:
        b = np.zeros(n)
        b[list(idx)] = coef
        K += k * np.outer(b, b)
    M = np.diag([1.0, 1.2, 0.8, 1.0, 0.0, 0.0])
    return Model.from_matrices(M, K, contact_dof=[4, 5], gap=list(gaps), stop_side=[1, -1], amplitude_dof=3)


def mass_clearance(kp_gap=1.0) -> Model:
    """A mass on a spring in a clearance ±1 m: the contact DOF carries the mass (a penalty
    spring is the contact law, as in FE-package models)."""
    return Model.from_matrices([[1.0]], [[1.0]], contact_dof=[0, 0], gap=kp_gap, stop_side=[1, -1],
                               amplitude_dof=0)


# ============================================================================ the closed form
def test_clearance_closed_form_against_dop853():
    """The derived period against an independent integration of m x'' + k1 x + k2 (x ∓ g)
    beyond ±g (the massless node held at the stop), by DOP853 with events: half a period
    from the turning point x = A to the next one."""
    co = ClearanceOscillator(m=2.0, k1=3.0, k2=40.0, gap=0.1)
    x_star = co.centre

    def rhs(t, y):
        x, v = y
        f = -co.k1 * x
        if x > co.gap:
            f -= co.k2 * (x - co.gap)
        elif x < -co.gap:
            f -= co.k2 * (x + co.gap)
        return [v, f / co.m]

    def turning(t, y):
        return y[1]

    turning.terminal, turning.direction = True, 1
    for A in (0.1001, 0.15, 0.4, 3.0):
        # start a hair after the turning point so the event at t = 0 is not caught
        sol = solve_ivp(rhs, (0, 10 * co.period(A)), [A, 0.0], method="DOP853", events=turning,
                        rtol=1e-13, atol=1e-15 * A, first_step=1e-9)
        T = 2 * sol.t_events[0][0]
        assert abs(T / co.period(A) - 1) < 1e-8, A
        assert abs(sol.y_events[0][0][0] + A) < 1e-8 * A  # the other turning point is −A
    # the limits: grazing and the contact spring always engaged
    assert co.period(co.gap) == pytest.approx(2 * np.pi / co.omega_open, rel=1e-15)
    assert co.period(co.gap * (1 + 1e-12)) == pytest.approx(2 * np.pi / co.omega_open, rel=1e-5)
    assert co.period(1e6 * co.gap) == pytest.approx(2 * np.pi / co.omega_closed, rel=1e-3)
    assert x_star == pytest.approx(co.k2 * co.gap / (co.k1 + co.k2))


# ============================================================================ exact
@pytest.mark.parametrize("co", [CO, ClearanceOscillator(2.5, 3.0, 300.0, 0.01),
                                ClearanceOscillator(1, 1, 1e4, 1)], ids=["soft", "stiff", "very-stiff"])
def test_exact_clearance_matches_closed_form(co):
    model = co.model()
    for ratio in (1.0001, 1.001, 1.01, 1.2, 2.0, 5.0, 20.0, 100.0):
        A = ratio * co.gap
        orbit = exact.periodic_orbit(model, A)
        assert orbit.converged and orbit.n_contacts == 2, ratio
        assert abs(orbit.period / co.period(A) - 1) < 1e-12, ratio
        assert abs(orbit.max_excursion / A - 1) < 1e-13
        # t = 0 at −A against the lower stop: the first switch opens contact 1 (the −gap stop)
        assert (orbit.events[0].kind, orbit.events[0].contact) == ("open", 1)
        assert orbit.max_contact_force == pytest.approx(co.k2 * (A - co.gap), rel=1e-9)
    T_lin = 2 * np.pi / co.omega_open
    for ratio in (0.3, 1.0):
        orbit = exact.periodic_orbit(model, ratio * co.gap)
        assert orbit.converged and orbit.n_contacts == 0
        assert abs(orbit.period / T_lin - 1) < 1e-14


def test_exact_clearance_backbone_and_energy():
    model = CO.model()
    amplitudes = [0.5, 1.01, 1.5, 3.0, 10.0]
    bb = exact.backbone(model, amplitudes)
    assert bb.converged.all() and list(bb.n_contacts) == [0, 2, 2, 2, 2]
    np.testing.assert_allclose(bb.frequency, CO.frequency(amplitudes), rtol=1e-12)
    S = exact.PiecewiseLinearSystem.of(model)
    orbit = bb.orbits[3]
    t = np.linspace(0, orbit.period, 301)
    q_l, v_l = orbit.trajectory.state_l(t)
    E = S.energy(q_l, v_l)
    # ½ k1 A² + ½ k2 (A − g)² at the turning point
    assert E[0] == pytest.approx(0.5 * CO.k1 * 9 + 0.5 * CO.k2 * 4, rel=1e-14)
    assert np.abs(E / E[0] - 1).max() < 1e-13
    # the node stays in [−g, g] and each stop pushes only when the node is on it
    q, _, lam = orbit.trajectory.evaluate(t)
    assert lam.shape == (2, len(t)) and np.all(lam >= 0)
    assert np.abs(q[1]).max() <= CO.gap * (1 + 1e-14)
    assert np.all((lam[0] == 0) | (abs(q[1] - CO.gap) < 1e-13))
    assert np.all((lam[1] == 0) | (abs(q[1] + CO.gap) < 1e-13))


# ============================================================================ penalty-HBM
def _penalty_frequency(model, H, A, fac, kc, **kw):
    br = mmshbm.backbone(model, harmonics=H, method="penalty", max_amplitude=A, penalty_stiffness=fac * kc,
                         **kw)
    assert br.status == "bound:amplitude", br.status
    return br.frequency[-1]


def test_penalty_clearance_converges_to_closed_form():
    """H = 20 at 2 gaps: the error falls about tenfold per decade of k_p, |e| ≈ 1.5 k_c/k_p
    (measured 1.4e-2, 1.5e-3, 2.1e-4 for 10², 10³, 10⁴ k_c; docs/penalty.md); and at
    k_p = 10⁴ k_c the truncation of the penalty formulation shrinks as H grows (2.9e-3 at
    H = 5)."""
    model, kc, A = CO.model(), CO.contact_stiffness, 2.0
    f_exact = float(CO.frequency(A))
    err = {fac: _penalty_frequency(model, 20, A, fac, kc) / f_exact - 1 for fac in (1e2, 1e3, 1e4)}
    assert abs(err[1e2]) > abs(err[1e3]) > abs(err[1e4])
    for fac, e in err.items():
        assert 0.5 / fac < abs(e) < 2.0 / fac + 2.5e-4, (fac, e)
    e5 = _penalty_frequency(model, 5, A, 1e4, kc) / f_exact - 1
    assert abs(e5) > 5 * abs(err[1e4])


def test_penalty_monitor_several_contacts():
    model = CO.model()
    p = PenaltyHBMProblem(model, harmonics=10)
    np.testing.assert_allclose(p.penalty_stiffnesses, [1e3 * CO.contact_stiffness] * 2, rtol=1e-14)
    br = mmshbm.backbone(model, harmonics=10, method="penalty", max_amplitude=3.0)
    rec = {k: br.records[k][-1] for k in ("contact_force_max_0", "contact_force_max_1")}
    # odd-symmetric orbit: both stops take the same peak force, k2 (A − g) = 8 N exactly;
    # the penalty's peak is that of k_p times a penetration of ~1 % of the gap, sensitive to
    # the truncation of the node's motion (measured 8.94 N at H = 10)
    assert rec["contact_force_max_0"] == pytest.approx(rec["contact_force_max_1"], rel=1e-9)
    assert br.contact_force_max[-1] == pytest.approx(CO.k2 * 2.0, rel=0.15)
    assert br.amplitude[-1] == pytest.approx(3.0, rel=1e-9)
    t, lam = br.solver.contact_force(br.states[-1], 64)
    assert lam.shape == (2, 64) and np.all((lam[0] == 0) | (lam[1] == 0))


# ============================================================================ shooting
@pytest.mark.parametrize("scheme", ["avf", "trapezoidal"])
def test_shooting_clearance_converges_at_order_two(scheme):
    amplitudes = [0.9, 1.2, 1.6, 2.0, 3.0]
    Ns = np.array([32, 64, 128, 256, 512])
    err = []
    for N in Ns:
        p = ShootingProblem(CO.model(), steps_per_period=N, scheme=scheme)
        u, e = None, []
        for A in amplitudes:
            u = p.solve_at_amplitude(A, guess=u)
            e.append(p.monitor(u)["frequency"] / CO.frequency(A) - 1)
        err.append(np.abs(e[1:]).max())
    slope = np.polyfit(np.log(Ns), np.log(err), 1)[0]
    assert slope == pytest.approx(-2.0, abs=0.15)
    assert err[-1] < 3e-5  # measured 2.3e-5 (avf), 1.3e-5 (trapezoidal)


def test_shooting_clearance_backbone_and_signals():
    br = mmshbm.backbone(CO.model(), method="shooting", steps_per_period=256, max_amplitude=10.0)
    assert br.status == "bound:amplitude"
    err = np.abs(br.frequency / CO.frequency(br.amplitude) - 1)
    assert err.max() < 1.2e-4  # measured 9.2e-5
    p, u = br.solver, br.states[-1]
    rec = p.monitor(u)
    A = rec["amplitude"]  # 10 m to the bound's refinement (1e-9)
    assert rec["contact_force_max"] == pytest.approx(CO.k2 * (A - 1), rel=1e-12)  # at the turning point
    assert rec["contact_force_max_0"] == pytest.approx(rec["contact_force_max_1"], rel=1e-12)
    assert rec["energy"] == pytest.approx(0.5 * CO.k1 * A**2 + 0.5 * CO.k2 * (A - 1) ** 2, rel=1e-12)
    _, q = p.time_signals(u, n_samples=256)
    assert np.abs(q[1]).max() <= CO.gap * (1 + 1e-12)
    t, lam = p.contact_force(u, 256)
    assert lam.shape == (2, 256) and np.all((lam[0] == 0) | (lam[1] == 0))


# ============================================================================ the uncoupled pair
A_PAIR = 3.0


def _embed(single_u, single_problem, pair_problem, both: bool):
    """Scaled unknowns of the pair with the single's motion on oscillator 0 and on
    oscillator 1 too (``both``) or oscillator 1 at rest."""
    x, omega = single_problem.unpack(single_u)
    if isinstance(single_problem, PenaltyHBMProblem):
        Q = np.concatenate([x, x if both else 0 * x], axis=1)
        return pair_problem.pack(Q, omega)
    return pair_problem.pack(np.concatenate([x, x if both else 0 * x]), omega)


def test_pair_exact_equals_one():
    model = pair()
    for A in (1.01, 2.0, A_PAIR):
        T = float(OSC.period(A))
        for guess in (None, (np.array([-A, -A]), 0.5 * T)):  # oscillator 1 at rest, or both moving
            orbit = exact.periodic_orbit(model, A, guess)
            assert orbit.converged
            assert abs(orbit.period / T - 1) < 1e-12
            assert orbit.n_contacts == (1 if guess is None else 2)
            assert abs(orbit.max_excursion / A - 1) < 1e-13


@pytest.mark.parametrize("method", ["penalty", "shooting"])
def test_pair_backbone_equals_one(method):
    """The pair continued from the single's orbit at 1.5 gaps put on both oscillators (both
    contacts active) reaches 3 gaps at the single's frequency; shooting from the linear
    mode (oscillator 1 at rest: the combination of the degenerate mode that moves the
    amplitude DOF) as well."""
    single = OSC.model().with_amplitude_dof(0)
    opts = dict(harmonics=10) if method == "penalty" else dict(steps_per_period=128)
    b1 = mmshbm.backbone(single, method=method, max_amplitude=A_PAIR, **opts)
    assert b1.status == "bound:amplitude"
    p1 = b1.solver
    p2 = type(p1)(pair(), **{k: v for k, v in opts.items()})
    k = int(np.searchsorted(b1.amplitude, 1.5))
    u0 = _embed(b1.states[k], p1, p2, both=True)
    t0 = _embed(b1.states[k + 1], p1, p2, both=True) - u0
    res = continue_branch(p2, u0, t0, ContinuationOptions(bounds={"amplitude": (0.0, A_PAIR)}))
    assert res.status == "bound:amplitude"
    assert res.records["amplitude"][-1] == pytest.approx(A_PAIR, rel=1e-9)
    assert res.records["frequency"][-1] == pytest.approx(b1.frequency[-1], rel=1e-9)
    x, _ = p2.unpack(res.u[-1])
    x = x.T if method == "penalty" else x[:, None]  # penalty: all DOFs; shooting: the masses
    half = len(x) // 2
    np.testing.assert_allclose(x[:half], x[half:], atol=1e-9 * abs(x).max())  # both move alike
    if method == "shooting":
        b2 = mmshbm.backbone(pair(), method=method, max_amplitude=A_PAIR, **opts)
        assert b2.status == "bound:amplitude"
        assert b2.frequency[-1] == pytest.approx(b1.frequency[-1], rel=1e-9)


# ============================================================================ Jacobians
def _fd_check(problem, u, eps=1e-6, n_dir=3):
    R, J = problem.evaluate(u)
    J = J.toarray() if hasattr(J, "toarray") else J
    np.testing.assert_allclose(problem.evaluate(u, jacobian=False), R, rtol=0, atol=1e-14 * np.abs(R).max())
    rng = np.random.default_rng(7)
    directions = [rng.normal(size=len(u)) for _ in range(n_dir)]
    assert_jacobian(lambda v: problem.evaluate(v, False), u, J, eps, directions=directions,
                    scale=max(np.abs(J @ d).max() for d in directions))


def _perturbed(problem, amplitude, seed=0):
    rng = np.random.default_rng(seed)
    u = problem.linear_point(amplitude)
    u[:-1] *= 1 + 0.01 * rng.standard_normal(len(u) - 1)
    u[-1] *= 1.05
    return u


@pytest.mark.parametrize("make", [CO.model, chain2, mass_clearance], ids=["clearance", "chain2", "mass"])
def test_penalty_jacobian_finite_differences(make):
    model = make()
    p = PenaltyHBMProblem(model, harmonics=6, penalty_stiffness=None if make is not mass_clearance else 30.0)
    u = _perturbed(p, 1.6 * model.gap)
    R = p.evaluate(u, False)
    assert np.abs(R).max() > 0
    _fd_check(p, u)


def test_penalty_residual_equals_dense_reference():
    """Residual and Jacobian of a model with two coupled contacts against explicit cosine
    sums with per-contact springs (and different k_p)."""
    model = chain2()
    kp = np.array([40.0, 25.0])
    p = PenaltyHBMProblem(model, harmonics=4, n_samples=64, penalty_stiffness=kp)
    u = _perturbed(p, 1.7 * model.gap, seed=2)
    Q, om = p.unpack(u)
    K, M = model.K.toarray(), model.M.toarray()
    H, N, n = p.H, p.N, p.n
    tau = 2 * np.pi * np.arange(N) / N
    C = np.cos(np.outer(np.arange(H + 1), tau))
    w = np.full(H + 1, 2.0 / N)
    w[0] = 1.0 / N
    R = np.array([(K - (k * om) ** 2 * M) @ Q[k] for k in range(H + 1)])
    J = np.zeros((n * (H + 1), n * (H + 1) + 1))
    active = 0
    for i, c in enumerate(model.contacts):
        q = Q[:, c.dof] @ C
        pen = c.side * q - c.gap
        s = (pen > 0).astype(float)
        active += s.sum()
        R[:, c.dof] += c.side * w * (C @ (kp[i] * np.maximum(pen, 0)))
        for m_ in range(H + 1):
            for k in range(H + 1):
                J[m_ * n + c.dof, k * n + c.dof] += kp[i] * w[m_] * np.sum(s * C[m_] * C[k])
    for m_ in range(H + 1):
        J[m_ * n:(m_ + 1) * n, m_ * n:(m_ + 1) * n] += K - (m_ * om) ** 2 * M
        J[m_ * n:(m_ + 1) * n, -1] = -2 * m_**2 * om * (M @ Q[m_])
    assert active > 0
    R_p, J_p = p.evaluate(u)
    np.testing.assert_allclose(R_p, R.ravel() / p.rowscale, rtol=1e-10, atol=1e-12 * np.abs(R_p).max())
    J = J * p.colscale[None, :] / p.rowscale[:, None]
    np.testing.assert_allclose(J_p.toarray(), J, rtol=1e-10, atol=1e-12 * np.abs(J).max())


@pytest.mark.parametrize("scheme", ["avf", "trapezoidal"])
@pytest.mark.parametrize("make", [CO.model, chain2, mass_clearance], ids=["clearance", "chain2", "mass"])
def test_shooting_jacobian_finite_differences(make, scheme):
    model = make()
    kw = dict(penalty_stiffness=30.0) if make is mass_clearance else {}
    p = ShootingProblem(model, steps_per_period=64, scheme=scheme, **kw)
    u = _perturbed(p, 1.6 * model.gap)
    x, omega = p.unpack(u)
    _, _, closed, (_, _, LAM) = p._integrate(x, omega, p.N // 2, store=True)
    assert closed > 0 and (LAM.max(axis=0) > 0).all()  # every contact closes in the half period
    _, J = p.evaluate(u)
    assert J.shape == (p.n_l, p.n_l + 1)
    _fd_check(p, u)


# ============================================================================ the time step
def _lcp_enumerate(G, h):
    """Plain enumeration: the λ of the (unique) complementary solution."""
    m = len(h)
    for size in range(m + 1):
        for J in itertools.combinations(range(m), size):
            lam = np.zeros(m)
            if size:
                try:
                    lam[list(J)] = -np.linalg.solve(G[np.ix_(J, J)], h[list(J)])
                except np.linalg.LinAlgError:
                    continue
            g = h + G @ lam
            if lam.min() >= -1e-12 and g.min() >= -1e-12:
                return lam
    raise AssertionError("no solution")


def test_lcp_solver_against_enumeration():
    rng = np.random.default_rng(3)
    for m in (1, 2, 3, 5):
        B = rng.normal(size=(m, m))
        G = B @ B.T + 0.1 * np.eye(m)
        H = rng.normal(size=(m, 40))
        lam, act = lcp_solve(G, H)
        for j in range(H.shape[1]):
            np.testing.assert_allclose(lam[:, j], _lcp_enumerate(G, H[:, j]), rtol=1e-10, atol=1e-12)
        g = H + G @ lam
        assert lam.min() >= 0 and g.min() > -1e-12 and np.abs(lam * g).max() < 1e-12
        assert np.array_equal(act, lam > 0)
    # a clearance: G singular (the two stops of one DOF), never both closed
    G = np.array([[2.0, -2.0], [-2.0, 2.0]])
    h = np.array([[-0.3, 0.5, 1.2], [1.3, -0.5, 0.2]])
    lam, _ = lcp_solve(G, h)
    np.testing.assert_allclose(lam, [[0.15, 0.0, 0.0], [0.0, 0.25, 0.0]], atol=1e-15)
    # and the exact reference's enumeration agrees with the path-following solver
    from mmshbm.methods.exact.system import _lcp_active_sets

    B = rng.normal(size=(3, 3))
    G = B @ B.T + 0.1 * np.eye(3)
    H = rng.normal(size=(3, 30))
    sets = _lcp_active_sets(G, H, np.arange(3))
    _, act = lcp_solve(G, H)
    assert [tuple(np.flatnonzero(a)) for a in act.T] == sets


def test_trapezoidal_step_against_dense_reference():
    """Several contacts, plain trapezoidal rule: the kernel's steps against dense solves and
    the step's contact problem h1 = hy + A S⁻¹Aᵀ (λ0 + λ1), λ1 = λ(h1), written as the LCP
    g1 = hy + A Z λ0 + (A Z + G) λ1 and solved by enumeration."""
    model = chain2()
    N, n_steps = 64, 40
    p = ShootingProblem(model, steps_per_period=N, scheme="trapezoidal")
    u = _perturbed(p, 1.7 * model.gap)
    x, omega = p.unpack(u)
    h = 2 * np.pi / omega / N
    inv = np.argsort(p.perm)
    M, K = model.blocks["M_ll"].toarray(), model.reduced_stiffness.toarray()
    A, G, gap = p._A[:, inv], p._G, p._gaps
    S = 4 / h**2 * M + K
    Z = np.linalg.solve(S, A.T)
    q, v = x.copy(), np.zeros_like(x)
    lam0 = _lcp_enumerate(G, gap + A @ q)
    Q, LAMS = [q], [lam0]
    for _ in range(n_steps):
        y = np.linalg.solve(S, (4 / h**2 * M - K) @ q + 4 / h * M @ v)
        hy = gap + A @ y
        lam1 = _lcp_enumerate(A @ Z + G, hy + A @ Z @ lam0)
        q_new = y + Z @ (lam0 + lam1)
        v = 2 / h * (q_new - q) - v
        q, lam0 = q_new, lam1
        Q.append(q)
        LAMS.append(lam1)
    Q, LAMS = np.array(Q), np.array(LAMS)
    assert (LAMS.max(axis=0) > 0).all()
    _, _, _, (Qk, _, LAMk) = p._integrate(x, omega, n_steps, store=True)
    np.testing.assert_allclose(Qk[:, inv], Q, rtol=0, atol=1e-9 * np.abs(Q).max())
    np.testing.assert_allclose(LAMk, LAMS, rtol=0, atol=1e-9 * np.abs(LAMS).max())


@pytest.mark.parametrize("make", [chain2, mass_clearance], ids=["chain2", "mass"])
def test_avf_conserves_energy_with_several_contacts(make):
    """The averaged-vector-field step is a discrete gradient of ½vᵀMv + ½qᵀK_open q + ½λᵀGλ
    when its force is the exact path average of the LCP solution: conservation to round-off
    tests that average (an error in the pieces of the path would show)."""
    model = make()
    kw = dict(penalty_stiffness=30.0) if make is mass_clearance else {}
    for scheme, bound in (("avf", 1e-12), ("trapezoidal", None)):
        p = ShootingProblem(model, steps_per_period=48, scheme=scheme, **kw)
        u = _perturbed(p, 2.5 * model.gap, seed=4)
        x, omega = p.unpack(u)
        _, _, closed, (Q, V, LAM) = p._integrate(x, omega, 96, store=True)
        assert closed > 0 and (LAM.max(axis=0) > 0).all()
        Mll = model.blocks["M_ll"].toarray()[np.ix_(p.perm, p.perm)]
        E = np.array([0.5 * v @ Mll @ v + 0.5 * q @ (p._K @ q) + 0.5 * lam @ p._G @ lam
                      for q, v, lam in zip(Q, V, LAM, strict=True)])
        drift = np.abs(E / E[0] - 1).max()
        if bound:
            assert drift < bound, drift
        else:
            assert drift > 1e-6  # the trapezoidal rule does not conserve it across contact


# ============================================================================ bad input
def test_bad_input_several_contacts():
    M, K = np.diag([1.0, 0.0]), np.array([[5.0, -4.0], [-4.0, 4.0]])
    no_amp = Model.from_matrices(M, K, contact_dof=[1, 1], gap=1.0, stop_side=[1, -1])
    assert no_amp.amplitude_dof == 0  # the DOF with mass, by default
    model = CO.model()
    with pytest.raises(ValueError, match="penalty_stiffness must be one number or one per contact"):
        PenaltyHBMProblem(model, penalty_stiffness=[1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match=r"penalty_stiffness\[1\]"):
        PenaltyHBMProblem(model, penalty_stiffness=[1.0, -2.0])
    with pytest.raises(ValueError, match="penalty_stiffness applies to contact DOFs with mass"):
        ShootingProblem(model, penalty_stiffness=10.0)
    with pytest.raises(ValueError, match=r"penalty_stiffness\[0\]"):
        ShootingProblem(mass_clearance(), penalty_stiffness=[0.0, 1.0])
    with pytest.raises(ValueError, match="with_contact_layer"):
        exact.periodic_orbit(mass_clearance(), 2.0)
    with pytest.raises(ValueError, match="close both stops of one DOF"):
        exact.PiecewiseLinearSystem.of(model).phase((0, 1))
    # two different uncoupled oscillators: mode 2 does not move the amplitude DOF (mass 0)
    one, two = OSC.model(), OneDofOscillator(1.0, 2.0, 4.0, 1.0).model()
    M2 = la.block_diag(one.M.toarray(), two.M.toarray())
    K2 = la.block_diag(one.K.toarray(), two.K.toarray())
    m2 = Model.from_matrices(M2, K2, contact_dof=[1, 3], gap=1.0, amplitude_dof=0)
    for cls in (PenaltyHBMProblem, ShootingProblem):
        with pytest.raises(ValueError, match="does not move the amplitude DOF 0"):
            cls(m2, mode=2)
