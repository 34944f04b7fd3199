"""The complex condensation of damped structures: both back ends against each other,
derivatives against finite differences, the undamped limit against harmonic.condense."""

from __future__ import annotations

import numpy as np
import pytest
from finite_differences import assert_derivative

import mmshbm
from mmshbm.harmonic.condense import Condensation
from mmshbm.methods.mms.condensation.damped_condense import DampedCondensation

FIELDS = ("D", "dD_domega", "dD_dxi", "P", "dP_domega", "dP_dxi", "Z", "Y")


def _models():
    beam = mmshbm.default_beam().model(8)
    return [beam.with_damping(modal_ratio=0.01), beam.with_damping(rayleigh=(2.0, 1e-6)),
            mmshbm.OneDofOscillator(1, 1, 4, 1).model().with_damping(modal_ratio=0.05)]


@pytest.fixture(scope="module", params=range(3), ids=["beam-modal", "beam-rayleigh", "oscillator"])
def model(request):
    return _models()[request.param]


def _loads(model):
    B = np.zeros((len(model.l), 2), dtype=complex)
    B[-1, 0] = 1.0
    B[0, 1] = 2.0j
    return B


def test_modal_and_direct_back_ends_agree(model):
    B = _loads(model)
    modal, direct = DampedCondensation(model, B, "modal"), DampedCondensation(model, B, "direct")
    assert modal.backend == "modal" and direct.backend == "direct"
    w1 = 2 * np.pi * model.linear_frequencies(1)[0]
    for ratio, xi in ((0.9, 0.0), (1.0, 0.3), (1.0, 2 * 0.01 * w1), (1.7, -0.1)):
        a = modal.evaluate(ratio * w1, 5, xi, True, True, True)
        b = direct.evaluate(ratio * w1, 5, xi, True, True, True)
        for name in FIELDS:
            x, y = getattr(a, name), getattr(b, name)
            assert np.abs(x - y).max() <= 1e-9 * np.abs(y).max(), name


@pytest.mark.parametrize("backend", ["modal", "direct"])
def test_derivatives_match_finite_differences(model, backend):
    cond = DampedCondensation(model, _loads(model), backend)
    omega = 1.13 * 2 * np.pi * model.linear_frequencies(1)[0]
    xi = 0.05 * omega
    c = cond.evaluate(omega, 3, xi, True, True)
    at = {"omega": lambda s: cond.evaluate(omega + s, 3, xi, False),
          "xi": lambda s: cond.evaluate(omega, 3, xi + s, False)}
    for name, d_D, d_P in (("omega", c.dD_domega, c.dP_domega), ("xi", c.dD_dxi, c.dP_dxi)):
        assert_derivative(lambda s, f=at[name]: f(s).D, d_D, 1e-4 * omega, name=f"dD/d{name}")
        assert_derivative(lambda s, f=at[name]: f(s).P, d_P, 1e-4 * omega, name=f"dP/d{name}")


def test_undamped_limit_is_the_real_condensation():
    model = mmshbm.default_beam().model(8)
    omega = 2 * np.pi * 55.0
    D_ref, dD_ref = Condensation(model).dynamic_stiffness(omega, 5)
    c = DampedCondensation(model.with_damping(modal_ratio=0.0), None, "modal").evaluate(omega, 5)
    assert np.abs(c.D - D_ref).max() <= 1e-10 * np.abs(D_ref).max()
    assert np.abs(c.dD_domega - dD_ref).max() <= 1e-9 * np.abs(dD_ref).max()
    assert np.abs(c.D.imag).max() == 0 or np.abs(c.D.imag).max() < 1e-12 * np.abs(D_ref).max()


def test_modal_back_end_is_regular_on_an_undamped_open_mode():
    """The linear EPMC sits exactly on ω_1 with zero effective damping: d_1 = ∞, D_1 finite."""
    osc = mmshbm.OneDofOscillator(1, 1, 4, 1).model().with_damping(modal_ratio=0.0)
    c = DampedCondensation(osc, None, "modal").evaluate(1.0, 3)
    # one DOF: D(ω) = k2 (k1 − ω²) / (k1 + k2 − ω²), zero at ω = ω_1 = 1
    assert abs(c.D[1, 0, 0]) < 1e-15
    w = np.array([2.0, 3.0])
    np.testing.assert_allclose(c.D[2:, 0, 0].real, 4 * (1 - w**2) / (5 - w**2), rtol=1e-13)


def test_modal_back_end_refuses_non_proportional_damping():
    model = mmshbm.default_beam().model(8)
    C = np.zeros((model.n_dof, model.n_dof))
    C[0, 0] = 1.0
    damped = mmshbm.Model.from_matrices(model.M, model.K, model.contact_dof, model.gap, damping=C)
    assert DampedCondensation(damped).backend == "direct"
    with pytest.raises(ValueError, match="backend 'modal' needs"):
        DampedCondensation(damped, backend="modal")


def test_compiled_modal_condensation_equals_the_numpy_one():
    """The compiled modal back end (no recovery) against its NumPy formulas (with recovery),
    including ξ on the linear EPMC point (γ_1 = ξ: the removed mode's d_j infinite)."""
    model = _models()[0]
    cond = DampedCondensation(model, _loads(model), "modal")
    w1 = 2 * np.pi * model.linear_frequencies(1)[0]
    gamma1 = 2 * 0.01 * w1
    for ratio, xi, H in ((0.9, 0.0, 3), (1.0, gamma1, 5), (1.7, -0.1, 12), (3.1, 0.4, 30)):
        a = cond.evaluate(ratio * w1, H, xi, True, True, recover=True)
        b = cond.evaluate(ratio * w1, H, xi, True, True, recover=False)
        for name in FIELDS[:6]:
            x, y = getattr(a, name), getattr(b, name)
            assert np.abs(x - y).max() <= 1e-12 * np.abs(x).max(), name
        c = cond.evaluate(ratio * w1, H, xi, False, False, recover=False)
        assert c.dD_domega is None and c.dD_dxi is None and np.array_equal(c.D, b.D)
