"""Contact DOFs that carry mass (models as FE packages export them) in penalty-HBM and
shooting: the penalty spring is then the contact law itself.

Ground truths: a mass on a spring k1 with a penalty spring k_p at the gap is the one-DOF
oscillator of :class:`~mmshbm.fe.oscillator.OneDofOscillator` with k2 = k_p (its closed
phase is k1 x + k_p (x − g), whichever node the spring sits on), so its backbone is known
in closed form; an Euler–Bernoulli cantilever (NLvib's benchmark model, rebuilt here from
the textbook element) has the static tip stiffness 3EI/L³ exactly.
"""

from __future__ import annotations

import numpy as np
import pytest

import mmshbm
from mmshbm import Model, OneDofOscillator
from mmshbm.contact.table import static_contact_stiffness
from mmshbm.methods.penalty.hbm import PenaltyHBMProblem
from mmshbm.methods.shooting.conservative import ShootingProblem

KP = 40.0
REF = OneDofOscillator(m=1.0, k1=1.0, k2=KP, gap=1.0)


def heavy_oscillator() -> Model:
    """A 1-kg mass on a 1 N/m spring, a stop 1 m away on the mass itself."""
    return Model.from_matrices([[1.0]], [[1.0]], contact_dof=0, gap=1.0)


def eb_cantilever(n_el=21, L=0.5, b=0.02, h=0.0135, E=210e9, rho=7850.0):
    """Clamped Euler–Bernoulli beam with consistent mass (cubic Hermite elements, DOFs
    (w, θ) per node, root removed): M, K (42 × 42 for 21 elements) and 3EI/L³ (N/m)."""
    le, I, A = L / n_el, b * h**3 / 12, b * h
    k = E * I / le**3 * np.array([[12, 6 * le, -12, 6 * le], [6 * le, 4 * le**2, -6 * le, 2 * le**2],
                                  [-12, -6 * le, 12, -6 * le], [6 * le, 2 * le**2, -6 * le, 4 * le**2]])
    m = rho * A * le / 420 * np.array([[156, 22 * le, 54, -13 * le],
                                       [22 * le, 4 * le**2, 13 * le, -3 * le**2],
                                       [54, 13 * le, 156, -22 * le],
                                       [-13 * le, -3 * le**2, -22 * le, 4 * le**2]])
    n = 2 * (n_el + 1)
    K, M = np.zeros((n, n)), np.zeros((n, n))
    for e in range(n_el):
        i = slice(2 * e, 2 * e + 4)
        K[i, i] += k
        M[i, i] += m
    return M[2:, 2:], K[2:, 2:], 3 * E * I / L**3


def test_penalty_hbm_on_a_heavy_contact_converges_in_H():
    """Relative frequency error against the closed form at 2 gaps, H = 5, 10, 20 (measured
    −5.1e-3, +2.4e-5, −8.1e-6; 40: −7e-7): k_p is the model here, so only the truncation is
    left."""
    model = heavy_oscillator()
    err = {}
    for H in (5, 10, 20):
        br = mmshbm.backbone(model, method="penalty", harmonics=H, penalty_stiffness=KP, max_amplitude=2.0)
        assert br.status == "bound:amplitude"
        err[H] = abs(br.frequency[-1] / REF.frequency(2.0) - 1)
    assert err[5] > 10 * err[10] and err[20] < 2e-5 and err[10] < 5e-5
    # and below the gap the linear frequency
    assert br.frequency[0] == pytest.approx(REF.omega_open / (2 * np.pi), rel=1e-12)


def test_shooting_on_a_heavy_contact_converges_at_order_two():
    """The penalty spring on the mass is integrated as a stiff, piecewise-linear ODE by the
    same energy-conserving step (its force depends on the state through one free gap)."""
    Ns = np.array([64, 128, 256, 512])
    err = []
    for N in Ns:
        p = ShootingProblem(heavy_oscillator(), steps_per_period=N, penalty_stiffness=KP)
        u, e = None, []
        for A in (0.9, 1.2, 1.6, 2.0, 3.0):
            u = p.solve_at_amplitude(A, guess=u)
            e.append(p.monitor(u)["frequency"] / REF.frequency(A) - 1)
        err.append(np.abs(e[1:]).max())
    slope = np.polyfit(np.log(Ns), np.log(err), 1)[0]
    assert slope == pytest.approx(-2.0, abs=0.1)
    assert err[-1] < 5e-5  # measured 3.9e-5
    rec = p.monitor(u)
    assert rec["amplitude"] == pytest.approx(3.0, rel=1e-12)
    # the energy includes the penalty spring's: ½ k1 A² at the turning point away from the stop
    assert rec["energy"] == pytest.approx(0.5 * 9.0, rel=1e-12)


def test_eb_cantilever_as_exported_runs_with_penalty_hbm():
    """NLvib's 21-element Euler–Bernoulli cantilever with the full tip mass (contact DOF 40
    carries mass): the default k_p is 10³ times the static tip stiffness, which is 3EI/L³;
    penalty-HBM (H = 5, N = 1024) runs it from the linear mode across grazing."""
    M, K, k3 = eb_cantilever()
    model = Model.from_matrices(M, K, contact_dof=40, gap=1e-3)
    assert not model.massless_contacts and len(model.c) == 0
    assert model.linear_frequencies(1)[0] == pytest.approx(45.118, abs=5e-4)
    assert static_contact_stiffness(model)[0] == pytest.approx(k3, rel=1e-10)
    p = PenaltyHBMProblem(model, harmonics=5, n_samples=1024)
    assert p.penalty_stiffness == pytest.approx(1e3 * k3, rel=1e-10)
    br = mmshbm.backbone(model, method="penalty", harmonics=5, n_samples=1024, penalty_stiffness=1e3 * k3,
                         max_amplitude=1.2e-3)
    assert br.status == "bound:amplitude"
    f1 = model.linear_frequencies(1)[0]
    assert br.frequency[0] == pytest.approx(f1, rel=1e-12)
    assert br.frequency[-1] > 1.05 * f1  # the contact stiffens the mode
    assert br.contact_force_max[-1] > 0
    # the tip's mass is inertia in the Ω column: the harmonic balance of the tip row
    R = br.solver.evaluate(br.states[-1], jacobian=False)
    assert np.abs(R).max() < 1e-9


def test_eb_cantilever_shooting_passes_grazing():
    """Shooting with the penalty spring on the heavy tip: below the gap the orbit is the
    linear mode at the trapezoidal rule's discrete frequency; the continuation passes
    grazing (above it the stiff penalty spring makes the tip rattle, as the massless tip
    does: docs/shooting.md)."""
    M, K, _ = eb_cantilever(8)
    model = Model.from_matrices(M, K, contact_dof=14, gap=1e-3)
    N = 128
    p = ShootingProblem(model, steps_per_period=N, floquet=False)
    u = p.solve_at_amplitude(0.6e-3)
    f1 = model.linear_frequencies(1)[0]
    assert p.monitor(u)["frequency"] == pytest.approx(f1 * np.pi / (N * np.tan(np.pi / N)), rel=1e-10)
    assert p.penalty_stiffnesses[0] == pytest.approx(1e3 * static_contact_stiffness(model)[0], rel=1e-12)
    br = mmshbm.backbone(model, method="shooting", steps_per_period=N, max_amplitude=1.003e-3, floquet=False)
    assert br.status == "bound:amplitude"
    above = np.flatnonzero(br.amplitude > 1.0005e-3)
    assert len(above) >= 2 and np.all(br.contact_force_max[above] > 0)
    for i in above:
        assert np.abs(br.solver.evaluate(br.states[i], jacobian=False)).max() < 1e-8
        assert br.frequency[i] > p.monitor(u)["frequency"]
