"""Shooting baseline: against the one-DOF closed form, the trapezoidal rule's discrete
linear frequency, finite differences of its own residual, and conservation laws."""

from __future__ import annotations

import os

import numpy as np
import pytest
from finite_differences import assert_jacobian
from scipy.integrate import quad
from scipy.optimize import brentq

import mmshbm
from mmshbm.fe.oscillator import OneDofOscillator
from mmshbm.methods.shooting._kernels import band_cholesky, band_solve, band_symv
from mmshbm.methods.shooting.conservative import ShootingProblem

OSC = OneDofOscillator(m=1.0, k1=1.0, k2=4.0, gap=1.0)


def discrete_linear_frequency(f: float, N: int) -> float:
    """Frequency (Hz) of the trapezoidal rule's periodic orbit of a linear oscillator of
    frequency f with N steps per period: tan(ω̃h/2) = ωh/2 with ω̃h = 2π/N."""
    return f * np.pi / (N * np.tan(np.pi / N))


def frequency_error(N: int, amplitudes, scheme="avf") -> np.ndarray:
    """Relative frequency errors against the closed form along a chain of amplitudes."""
    p = ShootingProblem(OSC.model(), steps_per_period=N, scheme=scheme)
    u, errors = None, []
    for A in amplitudes:
        u = p.solve_at_amplitude(A, guess=u)
        errors.append(p.monitor(u)["frequency"] / OSC.frequency(A) - 1)
    return np.array(errors)


# ---------------------------------------------------------------------- kernels
def test_band_kernels_match_dense():
    rng = np.random.default_rng(0)
    n, p = 9, 2
    A = np.zeros((n, n))
    for d in range(p + 1):
        v = rng.normal(size=n - d)
        A += np.diag(v, -d) + (np.diag(v, d) if d else 0)
    A += 10 * np.eye(n)
    ab = np.array([np.concatenate([np.diag(A, -d), np.zeros(d)]) for d in range(p + 1)])
    x = rng.normal(size=n)
    np.testing.assert_allclose(band_symv(ab, x), A @ x, rtol=1e-13)
    L = band_cholesky(ab)
    B = rng.normal(size=(3, n))
    np.testing.assert_allclose(band_solve(L, B), np.linalg.solve(A, B.T).T, rtol=1e-11)
    with pytest.raises(ValueError, match="positive definite"):
        band_cholesky(-ab)


# ---------------------------------------------------------------------- one DOF
def test_backbone_reproduces_closed_form():
    N = 256
    branch = mmshbm.backbone(OSC.model(), method="shooting", steps_per_period=N, max_amplitude=10.0)
    assert branch.status == "bound:amplitude"
    assert branch.amplitude[-1] == pytest.approx(10.0, rel=1e-8)
    exact = OSC.frequency(branch.amplitude)
    err = np.abs(branch.frequency / exact - 1)
    # below the gap: the trapezoidal rule's discrete linear frequency, to round-off
    below = branch.amplitude < OSC.gap * (1 - 1e-6)
    assert below.sum() >= 2
    f_lin = OSC.omega_open / (2 * np.pi)
    np.testing.assert_allclose(branch.frequency[below], discrete_linear_frequency(f_lin, N), rtol=1e-12)
    # above: within the O(h²) error, ≈ (2π/N)²/12 = 5e-5 (measured 7e-5)
    assert err.max() < 2e-4
    assert branch.frequency[-1] > 1.3 * f_lin  # the branch did leave the linear mode
    # Floquet multipliers of a conservative orbit: on the unit circle (pair at +1)
    assert np.all(np.abs(np.asarray(branch.solver.monitor(branch.states[-1])["floquet_max"]) - 1) < 1e-5)
    # time signals: the contact DOF starts at its largest excursion away from the stop
    t, q = branch.time_signals(len(branch.frequency) - 1, dofs=[1], n_samples=64)
    assert t[0] == 0 and t[1] == pytest.approx(1 / branch.frequency[-1] / 64)
    assert q[0, 0] == pytest.approx(-10.0, rel=1e-9)


@pytest.mark.parametrize("scheme", ["avf", "trapezoidal"])
def test_convergence_order_two(scheme):
    amplitudes = [0.9, 1.2, 1.6, 2.0, 3.0]
    Ns = np.array([32, 64, 128, 256, 512])
    err = np.array([abs(frequency_error(N, amplitudes, scheme)[-2:]).max() for N in Ns])
    slope = np.polyfit(np.log(Ns), np.log(err), 1)[0]
    assert slope == pytest.approx(-2.0, abs=0.2)
    assert err[-1] < 2e-5


def test_contact_force_and_energy_closed_form():
    # largest mass excursion X toward the stop: ½k1 X² + ½k2 (X−g)² = ½k1 A²
    A = 2.0
    k1, k2, g = OSC.k1, OSC.k2, OSC.gap
    X = (k2 * g + np.sqrt((k2 * g) ** 2 - (k1 + k2) * (k2 * g * g - k1 * A * A))) / (k1 + k2)
    p = ShootingProblem(OSC.model(), steps_per_period=1024)
    u = p.solve_at_amplitude(A)
    rec = p.monitor(u)
    assert rec["energy"] == pytest.approx(0.5 * k1 * A * A, rel=1e-12)
    assert rec["contact_force_max"] == pytest.approx(k2 * (X - g), rel=1e-4)
    assert rec["amplitude"] == pytest.approx(A, rel=1e-12)
    t, lam = p.contact_force(u, 512)
    assert lam.min() == 0.0 and lam.max() == pytest.approx(k2 * (X - g), rel=1e-3)
    # the massless node never penetrates the stop, and reaches it
    _, q = p.time_signals(u, n_samples=512)
    assert q[1].max() <= g * (1 + 1e-12) and q[1].max() == pytest.approx(g, rel=1e-12)


def test_avf_conserves_energy_trapezoidal_does_not():
    p = {s: ShootingProblem(OSC.model(), steps_per_period=64, scheme=s) for s in ("avf", "trapezoidal")}
    drift = {}
    for s, prob in p.items():
        u = prob.solve_at_amplitude(3.0)
        _, Q, V, _ = prob.trajectory(u)
        x, v = Q[:, 0], V[:, 0]
        E = 0.5 * OSC.m * v**2 + 0.5 * OSC.k1 * x**2 + 0.5 * OSC.k2 * np.minimum(0.0, OSC.gap - x) ** 2
        drift[s] = np.abs(E / E[0] - 1).max()
    assert drift["avf"] < 1e-12
    assert drift["trapezoidal"] > 1e-4


@pytest.mark.parametrize("scheme", ["avf", "trapezoidal"])
def test_step_matches_naive_dense_integration(beam8, scheme):
    """The kernel's trajectory against a plain loop: dense solves, the contact force sum by
    numerical quadrature (avf) and the scalar equation for the new free gap by brentq."""
    N, n_steps = 64, 48
    p = ShootingProblem(beam8, steps_per_period=N, scheme=scheme)
    u = p.linear_point(1.5 * beam8.gap)
    u[-1] *= 1.1  # off the orbit: the contact closes and opens again within the steps
    x, omega = p.unpack(u)
    h = 2 * np.pi / omega / N
    b = beam8.blocks
    M, K = b["M_ll"].toarray(), beam8.reduced_stiffness.toarray()
    a = p.a[np.argsort(p.perm)]
    kc, gap = p.contact_stiffness, beam8.gap
    lam = lambda g: kc * max(0.0, -g)  # noqa: E731

    def force_sum(g0, g1):
        if scheme == "trapezoidal":
            return lam(g0) + lam(g1)
        kink = [g0 / (g0 - g1)] if g0 * g1 < 0 else None
        return 2 * quad(lambda s: lam(g0 + s * (g1 - g0)), 0, 1, points=kink, epsabs=0, epsrel=1e-13)[0]

    S = 4 / h**2 * M + K
    q, v = x.copy(), np.zeros_like(x)
    y_a = np.linalg.solve(S, a)
    Q = [q]
    for _ in range(n_steps):
        y = np.linalg.solve(S, (4 / h**2 * M - K) @ q + 4 / h * M @ v)
        g0, gy, alpha = gap + a @ q, gap + a @ y, a @ y_a
        g1 = brentq(lambda g, g0=g0, gy=gy, al=alpha: g - gy - al * force_sum(g0, g), gy - 1.0, gy + 1.0,
                    xtol=1e-17, rtol=1e-15)
        q_new = y + force_sum(g0, g1) * y_a
        v = 2 / h * (q_new - q) - v
        q = q_new
        Q.append(q)
    Q = np.array(Q)
    _, _, _, (Qk, _, LAM) = p._integrate(x, omega, n_steps, store=True)
    assert LAM.max() > 0 and LAM[-1] == 0  # the contact closed and opened again
    # round-off of band vs dense solves over 48 steps: ~1e-10 of the largest entry
    np.testing.assert_allclose(Qk[:, np.argsort(p.perm)], Q, rtol=0, atol=1e-9 * np.abs(Q).max())


# ---------------------------------------------------------------------- Jacobian
@pytest.mark.parametrize("scheme", ["avf", "trapezoidal"])
@pytest.mark.parametrize("amplitude_gaps", [0.7, 1.3])
def test_jacobian_matches_finite_differences(beam8, scheme, amplitude_gaps):
    p = ShootingProblem(beam8, steps_per_period=64, scheme=scheme)
    u = p.linear_point(amplitude_gaps * beam8.gap)
    u[-1] *= 1.05
    u[:-1] *= 1 + 0.01 * np.sin(np.arange(len(u) - 1))
    R, J = p.evaluate(u)
    assert R.shape == (p.n_unknowns - 1,) and J.shape == (p.n_unknowns - 1, p.n_unknowns)
    np.testing.assert_allclose(p.evaluate(u, jacobian=False), R, rtol=0, atol=1e-14 * np.abs(R).max())
    rng = np.random.default_rng(1)
    directions = [rng.normal(size=len(u)) for _ in range(3)]
    assert_jacobian(lambda v: p.evaluate(v, False), u, J, 1e-6, directions=directions,
                    scale=max(np.abs(J @ d).max() for d in directions))


# ---------------------------------------------------------------------- beam
def test_beam_linear_part(beam8):
    N = 128
    p = ShootingProblem(beam8, steps_per_period=N, floquet=True)
    u = p.solve_at_amplitude(0.5 * beam8.gap)
    rec = p.monitor(u)
    f_lin = beam8.linear_frequencies(1)[0]
    assert rec["frequency"] == pytest.approx(discrete_linear_frequency(f_lin, N), rel=1e-10)
    assert rec["contact_force_max"] == 0.0
    mu = p.floquet_multipliers(u)
    np.testing.assert_allclose(np.abs(mu), 1.0, atol=1e-9)
    # mode shape: the orbit is the linear mode
    _, modes = beam8.linear_modes(1)
    x, _ = p.unpack(u)
    phi = modes[beam8.l, 0]
    cos = abs(x @ phi) / (np.linalg.norm(x) * np.linalg.norm(phi))
    assert cos == pytest.approx(1.0, abs=1e-12)


@pytest.mark.skipif(os.environ.get("NUMBA_DISABLE_JIT") == "1", reason="minutes without the JIT")
def test_default_beam_passes_grazing():
    model = mmshbm.default_beam().model(21)
    g = model.gap
    branch = mmshbm.backbone(model, method="shooting", steps_per_period=128, max_amplitude=1.003 * g)
    assert branch.status == "bound:amplitude"
    assert "grazing" in [name for name, _ in branch.special_points]
    p = branch.solver
    above = np.flatnonzero(branch.amplitude > g * 1.0005)
    assert len(above) >= 2
    f_lin = discrete_linear_frequency(model.linear_frequencies(1)[0], 128)
    for i in above:
        u = branch.states[i]
        assert np.abs(p.evaluate(u, jacobian=False)).max() < 1e-8
        rec = p.monitor(u)
        assert rec["contact_force_max"] > 0 and rec["frequency"] > f_lin
        # the averaged-vector-field step conserves the energy of the orbit
        _, Q, V, _ = p.trajectory(u)
        E = [p.energy(p.pack(q, 2 * np.pi * rec["frequency"])) + 0.5 * v @ (model.blocks["M_ll"] @ v)
             for q, v in zip(Q[::8], V[::8], strict=True)]
        np.testing.assert_allclose(E, rec["energy"], rtol=1e-9)


# ---------------------------------------------------------------------- input
def test_bad_input():
    model = OSC.model()
    with pytest.raises(ValueError, match="steps_per_period"):
        ShootingProblem(model, steps_per_period=65)
    with pytest.raises(ValueError, match="steps_per_period"):
        ShootingProblem(model, steps_per_period=4)
    with pytest.raises(TypeError, match="steps_per_period"):
        ShootingProblem(model, steps_per_period=64.0)
    with pytest.raises(ValueError, match="scheme"):
        ShootingProblem(model, scheme="euler")
    with pytest.raises(ValueError, match="floquet"):
        ShootingProblem(model, floquet="yes")
    with pytest.raises(TypeError, match="model"):
        ShootingProblem("beam")
    p = ShootingProblem(model, steps_per_period=16)
    with pytest.raises(ValueError, match="shape"):
        p.evaluate(np.zeros(3))
    with pytest.raises(ValueError, match="Ω"):
        p.evaluate(np.array([-1.0, -1.0]))
    with pytest.raises(ValueError, match="harmonics"):
        p.harmonic_content(p.linear_point(0.5), harmonics=8)
    with pytest.raises(ValueError, match="dofs"):
        p.time_signals(p.linear_point(0.5), dofs=[5])


def test_harmonic_content_linear_mode():
    p = ShootingProblem(OSC.model(), steps_per_period=64)
    u = p.solve_at_amplitude(0.5)
    amp = p.harmonic_content(u, dof=0, harmonics=5)
    assert amp.shape == (6,)
    assert amp[1] == pytest.approx(0.5, rel=1e-3)
    assert amp[0] < 1e-9 and amp[2:].max() < 1e-3
    assert p.H == 0 and p.N == 64
