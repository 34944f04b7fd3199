"""The forced shooting's start, ``linear_response_point``: the linear steady state of its
discrete map with the stop ignored, against the closed form.

The trapezoidal rule's periodic solution under the sampled force Re(F̂ e^{iΩt_k}) is
q_k = Re(Q̂ e^{iΩt_k}) with (K + iΩ̃C − Ω̃²M) Q̂ = F̂ at the warped frequency
Ω̃ = (2/h) tan(Ωh/2), h = 2π/(NΩ), and the scheme's velocity v_k = Re(iΩ̃ Q̂ e^{iΩt_k}):
substitute q_k = Q̂ z^k, z = e^{iΩh}, into (q₁ − q₀)/h = (v₀ + v₁)/2 and
M(v₁ − v₀)/h = ((f₀ + f₁) − K(q₀ + q₁) − C(v₀ + v₁))/2, and (z − 1)/(z + 1) = i tan(Ωh/2).
"""

from __future__ import annotations

import numpy as np
import pytest

import mmshbm
from mmshbm.methods.shooting.forced import ShootingForcedProblem

N = 64


def _closed_form(model, F, frequency):
    """(q_l(0), v_l(0)) of the discrete map's linear steady state (module docstring)."""
    omega = 2 * np.pi * frequency
    h = 2 * np.pi / omega / N
    w = 2 / h * np.tan(omega * h / 2)
    A = model.K.toarray() + 1j * w * model.damping.toarray() - w**2 * model.M.toarray()
    Q = np.linalg.solve(A, F)[model.l]
    return np.concatenate([Q.real, -w * Q.imag])


def _chain():
    """Two masses and a massless contact node (k = 3 to mass 2), modal damping 2 %."""
    K = np.array([[3.0, -1.0, 0.0], [-1.0, 4.0, -3.0], [0.0, -3.0, 3.0]])
    M = np.diag([1.0, 1.5, 0.0])
    return mmshbm.Model.from_matrices(M, K, contact_dof=2, gap=0.1).with_damping(modal_ratio=0.02)


@pytest.mark.parametrize("which", ["oscillator", "chain"])
@pytest.mark.parametrize("ratio", [0.5, 0.9, 1.0, 1.3])
def test_the_linear_response_point_is_the_discrete_maps_linear_response(which, ratio):
    if which == "oscillator":
        model = mmshbm.OneDofOscillator(m=1.0, k1=1.0, k2=4.0, gap=1.0).model().with_damping(modal_ratio=0.02)
        F = np.array([2.0, 0.0])
    else:
        model = _chain()
        F = np.array([0.0, 1.0, 0.0])
    p = ShootingForcedProblem(model, F, steps_per_period=N, stability=False)
    f = ratio * model.linear_frequencies(1)[0]
    ref = _closed_form(model, F, f)
    # a force large enough that the linear response, and the motion from rest over the first
    # period, pass the stop (several gaps): the stop must be ignored
    assert np.abs(ref[: len(model.l)]).max() > 2 * model.gap
    z, omega = p.unpack(p.linear_response_point(f))
    assert omega == pytest.approx(2 * np.pi * f, rel=1e-15)
    # round-off of one period of N steps and one solve of I − Φ (Φ the monodromy, |μ| ≥
    # e^{−2π·0.02} ≈ 0.88: condition ~10): N·10·ε ≈ 1.4e-13; 1e-11 leaves room for the modes' spread
    assert np.abs(z - ref).max() <= 1e-11 * np.abs(ref).max()
