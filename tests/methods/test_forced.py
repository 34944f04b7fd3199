"""Forced responses: MMS-HBM with the full cosine/sine ansatz against the linear closed form,
finite differences and the exact event-driven reference."""

from __future__ import annotations

import numpy as np
import pytest
from finite_differences import assert_jacobian
from scipy.integrate import solve_ivp

import mmshbm
from mmshbm.core.continuation import newton
from mmshbm.methods.exact.forced import forced_orbit
from mmshbm.methods.mms.forced import ForcedResponseProblem, base_excitation
from mmshbm.results.response import FrequencyResponse

OSC = dict(m=1.0, k1=1.0, k2=4.0, gap=1.0)
ZETA = 0.02
F_OSC = np.array([0.1, 0.0])


@pytest.fixture(scope="module")
def osc():
    return mmshbm.OneDofOscillator(**OSC).model().with_damping(modal_ratio=ZETA)


@pytest.fixture(scope="module")
def beam():
    return mmshbm.default_beam().model(8).with_damping(modal_ratio=0.01)


def _closed_form(model, F, omega):
    """All DOFs' complex first-harmonic amplitudes of the linear response, (K + iΩC − Ω²M) Q̂ = F̂
    (dense solve of the whole model, refined twice with residuals in extended precision: the
    graded beam's K has a condition number ~1e10)."""
    A = model.K.toarray() + 1j * omega * model.damping.toarray() - omega**2 * model.M.toarray()
    Q = np.linalg.solve(A, F)
    for _ in range(2):
        R = np.asarray(F, dtype=np.clongdouble) - A.astype(np.clongdouble) @ Q.astype(np.clongdouble)
        Q = Q + np.linalg.solve(A, R.astype(complex))
    return Q


def _fd_check(problem, u, h=1e-5):
    R, J = problem.evaluate(u)
    assert_jacobian(lambda v: problem.evaluate(v, False), u, J, h)


def test_linear_response_below_the_gap_is_the_closed_form(beam):
    F = np.zeros(beam.n_dof)
    F[10] = 1e-3
    # a Newton tolerance that the closed-form comparison to 1e-10 can rely on (the linear
    # response near resonance amplifies a scaled residual of 1e-14 to ~2e-10; 1e-15 is reached)
    resp = mmshbm.frequency_response(beam, F, (30.0, 60.0), harmonics=3, newton_tol=1e-15)
    assert resp.completed and len(resp) > 5 and resp.contact_force_max.max() == 0
    tip = beam.contact_dof
    worst = 0.0
    for i, f in enumerate(resp.frequency):
        Q = _closed_form(beam, F, 2 * np.pi * f)
        coeffs = resp.solver.coefficients(resp.states[i])
        ref = np.zeros_like(coeffs)
        ref[:, 1], ref[:, 2] = Q.real, -Q.imag
        worst = max(worst, np.abs(coeffs - ref).max() / np.abs(Q).max())
        assert resp.amplitude[i] == pytest.approx(abs(Q[tip]), rel=1e-10)
        lag = (np.angle(F[10]) - np.angle(Q[tip]) + 0.5 * np.pi) % (2 * np.pi) - 0.5 * np.pi
        assert resp.phase[i] == pytest.approx(lag, abs=1e-10)
    assert worst < 1e-10
    # stability below the gap: the multipliers are those of the damped linear structure
    w = 2 * np.pi * beam.linear_frequencies(1)[0]
    T = 1 / resp.frequency[0]
    assert resp.floquet_max[0] == pytest.approx(np.exp(-0.01 * w * T), rel=1e-8)


@pytest.mark.parametrize("projection", ["exact", "sampled"])
def test_jacobian_matches_finite_differences(osc, beam, projection):
    rng = np.random.default_rng(3)
    for model, F, H in ((osc, F_OSC, 4), (beam, np.eye(beam.n_dof)[12] * 5.0, 3)):
        p = ForcedResponseProblem(model, F, harmonics=H, projection=projection, stability=False)
        u = p.linear_point(1.1 * model.linear_frequencies(1)[0])
        u[:-1] += 0.5 * rng.standard_normal(len(u) - 1)
        u[p.n_c + p.contact_rows[0]] += 2.0  # well into contact
        _fd_check(p, u)


def test_base_excitation_and_bad_input(osc, beam):
    exc = base_excitation(beam, "transverse", acceleration=2.0)
    np.testing.assert_allclose(exc.vector[beam.l], -2.0 * (beam.M @ np.where(np.arange(beam.n_dof) % 2 == 0,
                                                                              1.0, 0.0))[beam.l])
    disp = base_excitation(beam, "transverse", displacement=1e-4)
    assert disp.scale(3.0) == (9.0, 6.0)
    for F, rng_, match in (([1.0], (0.1, 0.3), "force must have length n_dof = 2"),
                           ([0.0, 1.0], (0.1, 0.3), r"force acts on the massless DOFs \[1\]"),
                           ([0.0, 0.0], (0.1, 0.3), "force is zero"),
                           (F_OSC, (0.3, 0.1), "empty or inverted"),
                           (F_OSC, (0.2, 0.2), "empty or inverted"),
                           (F_OSC, (-0.1, 0.2), "frequency_range start must be positive"),
                           (F_OSC, 0.2, "frequency_range must be a pair")):
        with pytest.raises(ValueError, match=match):
            mmshbm.frequency_response(osc, F, rng_)
    with pytest.raises(ValueError, match="unknown method 'hbm'"):
        mmshbm.frequency_response(osc, F_OSC, (0.1, 0.2), method="hbm")
    with pytest.raises(TypeError, match="unknown option 'n_sample'"):
        mmshbm.frequency_response(osc, F_OSC, (0.1, 0.2), n_sample=64)


@pytest.fixture(scope="module")
def osc_response(osc):
    return mmshbm.frequency_response(osc, F_OSC, (0.1, 0.3), harmonics=20)


def test_exact_forced_reference_is_exact(osc):
    # below the gap: the linear steady state
    omega = 2 * np.pi * 0.1
    o = forced_orbit(osc, F_OSC, 0.1)
    X = 0.1 / (1 - omega**2 + 2j * ZETA * omega)
    assert o.converged and o.n_contacts == 0
    np.testing.assert_allclose(o.z0, [X.real, (1j * omega * X).real], rtol=1e-13)


def test_exact_orbit_above_the_gap_against_dop853_and_energy_balance(osc_response, osc):
    resp = osc_response
    i = int(np.flatnonzero((resp.frequency > 0.18) & (resp.amplitude > 1.5))[0])
    u, p = resp.states[i], resp.solver
    Q = p.coefficients(u)
    omega = 2 * np.pi * resp.frequency[i]
    k = np.arange(1, p.H + 1)
    guess = np.array([Q[0, 0] + Q[0, 1::2].sum(), omega * (k * Q[0, 2::2]).sum()])
    o = forced_orbit(osc, F_OSC, resp.frequency[i], guess=guess)
    assert o.converged and o.residual < 1e-12 and o.n_contacts == 1
    # independent integration (DOP853) of the piecewise-linear ODE over one period
    kc, c = 4.0, 2 * ZETA

    def rhs(t, z):
        return [z[1], 0.1 * np.cos(omega * t) - c * z[1] - z[0] - kc * max(0.0, z[0] - 1.0)]

    T = 2 * np.pi / omega
    end = solve_ivp(rhs, (0, T), o.z0, method="DOP853", rtol=1e-12, atol=1e-14).y[:, -1]
    assert np.abs(end - o.z0).max() < 1e-9 * np.abs(o.z0).max()
    # energy balance over a period: work of the force = energy dissipated by the damper
    # (Gauss–Legendre on every smooth phase: exact to round-off)
    x, w = np.polynomial.legendre.leggauss(40)
    work = loss = 0.0
    for phase, a, b, alpha in o.segments:
        t = 0.5 * (b - a) * x + 0.5 * (a + b)
        v = phase.state(alpha, a, t)[1]
        work += 0.5 * (b - a) * w @ (0.1 * np.cos(omega * t) * v)
        loss += 0.5 * (b - a) * w @ (c * v**2)
    assert work == pytest.approx(loss, rel=1e-11)
    # MMS-HBM converges to it in H; the Floquet multipliers follow
    errors = []
    for H in (5, 10, 20, 40):
        ph = ForcedResponseProblem(osc, F_OSC, harmonics=H, stability=False)
        x = np.zeros(ph.n_x)
        cf = [o.fourier(d, H) for d in osc.c]
        x[:] = np.array(cf).T.ravel()
        v0 = ph.pack(x, omega)
        tang = np.zeros(ph.n_unknowns)
        tang[-1] = 1.0
        v1, *_ = newton(ph, v0, tang, v0, 1e-12, 30)
        errors.append(np.abs(ph.unpack(v1)[0] - x).max() / np.abs(x).max())
    assert all(b < a for a, b in zip(errors, errors[1:], strict=False))
    assert errors[-1] < 2e-4
    mu_hbm = resp.records["floquet"][i]
    assert np.abs(np.sort_complex(mu_hbm) - np.sort_complex(o.multipliers)).max() < 5e-3


def test_response_files_round_trip(osc_response, tmp_path):
    resp = osc_response
    assert resp.completed and (~resp.stable).any() and any(p.kind == "fold" for p in resp.special_points)
    path = resp.save(tmp_path / "frf.npz")
    back = FrequencyResponse.load(path)
    for name in ("frequency", "amplitude", "phase", "energy", "stable", "floquet_max", "states"):
        np.testing.assert_array_equal(getattr(back, name), getattr(resp, name))
    np.testing.assert_array_equal(back.records["floquet"], resp.records["floquet"])
    assert back.special_points == resp.special_points and back.status == resp.status
    t, q = back.time_signals(5, dofs=[1])  # the solver is rebuilt from the metadata
    np.testing.assert_allclose(q, resp.time_signals(5, dofs=[1])[1], rtol=1e-12, atol=1e-15)
    csv = resp.to_csv(tmp_path / "frf.csv")
    head = csv.read_text().splitlines()
    assert head[0].startswith("frequency_hz,amplitude_m,phase_rad") and len(head) == len(resp) + 1
    with pytest.raises(ValueError, match="not a saved mmshbm FrequencyResponse"):
        np.savez(tmp_path / "x.npz", metadata=np.array('{"format": "other"}'))
        FrequencyResponse.load(tmp_path / "x.npz")


def test_mmshbm_load_reads_responses(osc_response, tmp_path):
    path = osc_response.save(tmp_path / "r.npz")
    back = mmshbm.load(path, attach_solver=True)
    assert isinstance(back, FrequencyResponse) and back.solver is not None
    np.testing.assert_array_equal(back.amplitude, osc_response.amplitude)
