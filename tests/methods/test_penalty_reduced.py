"""Penalty HBM on the condensed contact DOFs ("penalty-reduced") against the full-DOF
penalty HBM (same k_p, H, N: the same solutions), a clearance's closed form, and an
uncoupled pair of oscillators."""

import numpy as np
import pytest
import scipy.sparse as sp

import mmshbm
from mmshbm.core.continuation import newton
from mmshbm.methods.registry import make_problem


def _solve_at(problem, u0, index, value):
    """Newton on R(u) = 0 with unknown ``index`` held at ``value`` (unscaled); returns u."""
    t = np.zeros(problem.n_unknowns)
    t[index] = 1.0
    u_pred = u0.copy()
    u_pred[index] = value / problem.colscale[index]
    u, *_ = newton(problem, u_pred, t, u_pred, 1e-11, 30, 1e-13)
    return u


def _full_state(full, red, u):
    """The full-DOF penalty unknowns of a reduced point (DOFs with mass recovered)."""
    Q = red.coefficients(u)
    cos = np.concatenate([Q[:, :1], Q[:, 1::2]], axis=1)
    return full.pack(cos.T, red.unpack(u)[1])


@pytest.mark.parametrize("name", ["oscillator", "beam8"])
@pytest.mark.parametrize("backend", ["banded", "modal"])
def test_same_solutions_as_full_dof_penalty(name, backend):
    """Eliminating the DOFs with mass is exact: reduced solutions are full solutions (scaled
    full residual at round-off), and at a fixed contact-DOF coefficient both give the same Ω,
    amplitude and energy."""
    model = mmshbm.one_dof_oscillator() if name == "oscillator" else mmshbm.default_beam().model(8)
    branch = mmshbm.backbone(model, harmonics=5, method="penalty-reduced", max_amplitude=2.5 * model.gap,
                             backend=backend)
    assert branch.status == "bound:amplitude"
    red = branch.solver
    assert red.penalty_stiffness == pytest.approx(make_problem(model, "penalty").penalty_stiffness, rel=1e-10)
    full = make_problem(model, "penalty", harmonics=5, penalty_stiffness=red.penalty_stiffness)
    assert full.N == red.N
    for i in np.linspace(0, len(branch) - 1, 6).astype(int):
        R = full.evaluate(_full_state(full, red, branch.states[i]), jacobian=False)
        assert np.abs(R).max() < 1e-9
    cd, ci = model.contact_dof, int(np.searchsorted(model.c, model.contact_dof))
    for gaps in (1.5, 2.2):
        i = int(np.argmin(np.abs(branch.amplitude - gaps * model.gap)))
        value = red.unpack(branch.states[i])[0][1, ci]
        u_red = _solve_at(red, branch.states[i], red.n_c + ci, value)
        u_full = _solve_at(full, _full_state(full, red, branch.states[i]), full.n + cd, value)
        m_red, m_full = red.monitor(u_red), full.monitor(u_full)
        assert m_red["frequency"] == pytest.approx(m_full["frequency"], rel=1e-11)
        assert m_red["amplitude"] == pytest.approx(m_full["amplitude"], rel=1e-10)
        assert m_red["energy"] == pytest.approx(m_full["energy"], rel=1e-9)
        assert m_red["contact_force_max"] == pytest.approx(m_full["contact_force_max"], rel=1e-6)


def _clearance_period(A, m, k1, k2, g):
    """Closed-form period of the massless-node oscillator in a symmetric clearance ±g, mass
    amplitude A: open arcs x = C sin ω₁t through the clearance, contact arcs about the shifted
    centre x_c = k₂g/(k₁+k₂) with ω₂ = √((k₁+k₂)/m); the speed at x = g matches:
    ω₂²(B² − (g − x_c)²) = ω₁²(C² − g²), B = A − x_c."""
    w1, w2 = np.sqrt(k1 / m), np.sqrt((k1 + k2) / m)
    if A <= g:
        return 2 * np.pi / w1
    xc = k2 * g / (k1 + k2)
    B = A - xc
    C = np.sqrt(g**2 + w2**2 * (B**2 - (g - xc) ** 2) / w1**2)
    return 4 / w1 * np.arcsin(g / C) + 4 / w2 * np.arccos((g - xc) / B)


def test_clearance_against_its_closed_form():
    """Two stops on the node (±g): the penalty backbone approaches the closed form as H and
    k_p grow (errors include the penalty's k_c/k_p and the linear interpolation)."""
    m, k1, k2, g = 1.0, 1.0, 4.0, 1.0
    base = mmshbm.OneDofOscillator(m, k1, k2, g).model()
    model = mmshbm.Model.from_matrices(base.M, base.K, [1, 1], g, [1, -1], amplitude_dof=0)
    k_c = k1 * k2 / (k1 + k2)
    errors = {}
    for H, factor in ((5, 1e3), (20, 1e5)):
        b = mmshbm.backbone(model, harmonics=H, method="penalty-reduced", max_amplitude=3.5,
                            penalty_stiffness=factor * k_c)
        assert b.status == "bound:amplitude"
        errors[H] = max(abs(b.frequency_at(A) * _clearance_period(A, m, k1, k2, g) - 1)
                        for A in (1.5, 2.0, 3.0))
    assert errors[20] < 1.5e-3 and errors[5] < 1e-2
    assert errors[20] < errors[5] / 3
    # the clearance is stiffer than one stop: 2 gaps, frequency above the one-sided closed form
    one_sided = mmshbm.OneDofOscillator(m, k1, k2, g)
    assert 1 / _clearance_period(2.0, m, k1, k2, g) > one_sided.frequency(2.0) * 1.05


def test_second_uncoupled_oscillator_stays_at_rest():
    """Two uncoupled oscillators, one contact each: the first mode moves only the softer one,
    whose backbone is then that of the oscillator alone; the other contact stays open."""
    a = mmshbm.OneDofOscillator(1.0, 1.0, 4.0, 1.0).model()
    b = mmshbm.OneDofOscillator(1.0, 3.0, 4.0, 1.0).model()
    M = sp.block_diag([a.M, b.M]).tocsr()
    K = sp.block_diag([a.K, b.K]).tocsr()
    pair = mmshbm.Model.from_matrices(M, K, [1, 3], 1.0, [1, 1], amplitude_dof=1)
    alone = mmshbm.backbone(a, harmonics=5, method="penalty-reduced", max_amplitude=3.0)
    both = mmshbm.backbone(pair, harmonics=5, method="penalty-reduced", max_amplitude=3.0)
    assert both.status == alone.status == "bound:amplitude"
    for A in (1.2, 2.0, 2.8):
        assert both.frequency_at(A) == pytest.approx(alone.frequency_at(A), rel=1e-3)
    q = both.time_signals(len(both) - 1, dofs=[2, 3])[1]
    assert np.abs(q).max() < 1e-9


def test_mirrored_stop_gives_the_same_backbone():
    osc = mmshbm.one_dof_oscillator()
    mirrored = mmshbm.Model.from_matrices(osc.M, osc.K, 1, osc.gap, -1)
    up = mmshbm.backbone(osc, harmonics=3, method="penalty-reduced", max_amplitude=2.0)
    down = mmshbm.backbone(mirrored, harmonics=3, method="penalty-reduced", max_amplitude=2.0)
    np.testing.assert_allclose(down.frequency, up.frequency, rtol=1e-12)
    np.testing.assert_allclose(down.amplitude, up.amplitude, rtol=1e-12)


def test_needs_massless_contacts_and_an_amplitude_dof():
    beam = mmshbm.default_beam()
    heavy = beam.model(8, massless_tip=False)
    with pytest.raises(ValueError, match="with_contact_layer"):
        make_problem(heavy, "penalty-reduced")
    osc = mmshbm.one_dof_oscillator()
    with pytest.raises(ValueError, match="penalty_stiffness must be positive"):
        make_problem(osc, "penalty-reduced", penalty_stiffness=0.0)
