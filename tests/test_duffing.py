"""The Duffing oscillator x'' + x + x³ = 0 (m = k = k₃ = 1) by MMS-HBM with a cubic spring
element, against its closed forms.

Single-harmonic balance: ω = √(1 + ¾A²). Exact: x(t) = A cn(ω t, m) with
ω = π√(1 + A²)/(2K(m)), m = A²/(2(1 + A²)), A = max|x| (here x(0): the cosine ansatz puts
the turning point at τ = 0).
"""

import numpy as np
import pytest
from scipy.special import ellipk

import mmshbm
from mmshbm.elements import CubicSpring


def duffing(k3=1.0):
    return mmshbm.Model.from_matrices([[1.0]], [[1.0]], [], [], []).with_element(
        CubicSpring(dof=0, stiffness=k3))


def exact_frequency(A):
    m = A**2 / (2 * (1 + A**2))
    return np.pi * np.sqrt(1 + A**2) / (2 * ellipk(m))


@pytest.fixture(scope="module")
def branches():
    return {H: mmshbm.backbone(duffing(), harmonics=H, max_amplitude=2.0) for H in (1, 15)}


def test_single_harmonic_backbone_is_the_closed_form(branches):
    """At H = 1 the balance is a_1 = A, Ω² = 1 + ¾A² exactly: the branch meets it to
    round-off of the Newton solution (tolerance 1e-9 of Ω, well above 1e-12 noise)."""
    b = branches[1]
    assert str(b.status).startswith("bound") and b.amplitude.max() >= 2.0 - 1e-9
    omega = 2 * np.pi * b.frequency
    np.testing.assert_allclose(omega, np.sqrt(1 + 0.75 * b.amplitude**2), rtol=1e-9, atol=0)


def test_fifteen_harmonics_meet_the_exact_backbone(branches):
    """At H = 15 the truncation error of the cn series (nome q <= 0.04 at A = 2: the
    omitted harmonics are below q^8 ~ 1e-11) is far below 1e-8 of Ω."""
    b = branches[15]
    assert b.amplitude.max() >= 2.0 - 1e-9 and b.amplitude.min() < 0.05
    omega = 2 * np.pi * b.frequency
    np.testing.assert_allclose(omega, exact_frequency(b.amplitude), rtol=1e-8, atol=0)


def test_amplitude_is_the_displacement_maximum_not_the_fundamental(branches):
    """The branch's amplitude is max|x(τ)| = x(0) = Σ_k a_k, which at A = 2 differs from the
    fundamental a_1 by the higher harmonics (a few per cent): the exact formula takes the
    former."""
    b = branches[15]
    problem = b.solver
    a, _ = problem.unpack(b.states[-1])
    assert b.amplitude[-1] == pytest.approx(a[:, 0].sum(), rel=1e-12)
    assert a[1, 0] < 0.99 * a[:, 0].sum()


def test_energy_is_the_duffing_energy(branches):
    """The energy record at the turning point: ½A² + ¼A⁴ (m = k = k₃ = 1)."""
    b = branches[15]
    A = b.amplitude
    np.testing.assert_allclose(b.energy, 0.5 * A**2 + 0.25 * A**4, rtol=1e-12)


def test_softening_spring_bends_the_backbone_down():
    """k₃ = −0.1: Ω = √(1 − 0.075 A²) at H = 1 (no turning point before A = 1.5)."""
    b = mmshbm.backbone(duffing(-0.1), harmonics=1, max_amplitude=1.5)
    omega = 2 * np.pi * b.frequency
    np.testing.assert_allclose(omega, np.sqrt(1 - 0.075 * b.amplitude**2), rtol=1e-9, atol=0)
    assert omega[-1] < omega[0]
