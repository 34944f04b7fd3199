"""The amplitude DOF's row of the recovery (``_amplitude_row``, computed alone) against
the full recovery of every DOF with mass (``_recover``), on every condensation back end,
with and without pole unknowns.

Both sum the same products in the same grouping up to the order of a few dot products:
they differ by round-off, a few ε per term over ~n_l + n_modes terms (here ~60: ~1e-14 of the
row's largest entry); 1e-12 bounds that with room and fails on any wrong term (each is
O(1) of the row for random motion).
"""

from __future__ import annotations

import numpy as np
import pytest

from mmshbm.methods.mms.conservative import MMSHBMProblem


@pytest.fixture(scope="module")
def clearance_beam():
    from validation import corpus

    return corpus.generate(291, 29)[290].model()  # a beam clearance, amplitude DOF with mass


@pytest.mark.parametrize("poles", [True, False])
@pytest.mark.parametrize("backend", ["modal", "banded", "splu"])
def test_the_amplitude_row_is_that_of_the_full_recovery(clearance_beam, backend, poles):
    model = clearance_beam
    p = MMSHBMProblem(model, harmonics=15, backend=backend, poles=poles)
    assert not p._amp_in_c and (p.n_poles > 15 if poles else p.n_poles == 0)
    i = int(np.searchsorted(model.l, model.amplitude_dof))
    rng = np.random.default_rng(7)
    w1 = 2 * np.pi * model.linear_frequencies(1)[0]
    for omega in (1.05 * w1, 1.05 * w1, 1.2 * w1):  # the second: the modal factors of the last Ω, reused
        a = rng.standard_normal((p.H + 1, p.n_c))
        eta = rng.standard_normal(p.n_poles)
        row = p._amplitude_row(a, omega, eta)
        full = p._recover(a, omega, eta)[i]
        ref = np.concatenate([[full[0]], full[1::2]])
        assert row.shape == (p.H + 1,)
        assert np.abs(row - ref).max() <= 1e-12 * np.abs(ref).max()


@pytest.fixture(scope="module")
def chain():
    from validation import corpus

    return corpus.generate(201, 97)[200].model()  # a chain, amplitude DOF with mass, 35 pole unknowns


def _state(p, omega, seed):
    """Scaled unknowns of a random cosine motion at Ω (harmonics decaying as 1/(k+1))."""
    rng = np.random.default_rng(seed)
    a = rng.standard_normal((p.H + 1, p.n_c)) * p.gap / (1.0 + np.arange(p.H + 1))[:, None]
    return p.pack(a, omega, 0.01 * rng.standard_normal(p.n_poles))


@pytest.mark.parametrize("poles", [True, False])
@pytest.mark.parametrize("backend", ["modal", "banded"])
@pytest.mark.parametrize("which", ["beam", "chain"])
def test_the_amplitude_gradient_is_that_of_central_differences(clearance_beam, chain, which, backend, poles):
    """∇A against central differences of A with steps h and 2h: D(h) − A′ ≈ c h² (+ round-off
    ≤ 4ε|A|/h), D(2h) − D(h) ≈ 3c h², so |∇A − D(h)| ≤ |D(2h) − D(h)| + 8ε|A|/h bounds the
    difference with room (factor 3 on the truncation, 2 on the round-off); a wrong entry
    (a term or a scale missing) is off by O(|∇A|). A direct back end differences its row in Ω
    itself (step 1e-6: ≲ 4e-8 of the coefficients' derivative against Richardson
    extrapolation; 1e-7 of Σ_k |cos kτ*| |∂G/∂u_Ω| |u| allowed). The amplitude from the gradient's call is
    the value's, and that of the row of the full recovery to round-off."""
    model = clearance_beam if which == "beam" else chain
    p = MMSHBMProblem(model, harmonics=15, backend=backend, poles=poles)
    assert not p._amp_in_c
    i = int(np.searchsorted(model.l, model.amplitude_dof))
    eps = np.finfo(float).eps
    for seed, factor in ((1, 1.04), (2, 1.25)):
        u = _state(p, factor * p.omega_ref, seed)
        A, g = p.amplitude_and_gradient(u)
        assert A == p.amplitude_value(u)
        a, omega = p.unpack(u)
        full = p._recover(a, omega, p.unpack_eta(u))[i]
        ref = np.concatenate([[full[0]], full[1::2]])
        from mmshbm.core.measures import _cosine_peak

        A_ref, _ = _cosine_peak(ref, p._amp_sign, np.empty(p.H + 1))
        assert abs(A - A_ref) <= 1e-12 * np.abs(ref).sum()
        h = 1e-5
        for j in range(len(u)):
            e = np.zeros(len(u))
            e[j] = h
            d1 = (p.amplitude_value(u + e) - p.amplitude_value(u - e)) / (2 * h)
            d2 = (p.amplitude_value(u + 2 * e) - p.amplitude_value(u - 2 * e)) / (4 * h)
            own = 0.0
            if backend != "modal" and j == len(u) - 1:
                _, cosk, _, _ = p._amplitude_peak(u)
                dG = p._amplitude_row_derivatives(omega)[1]
                own = 1e-7 * float(np.abs(cosk) @ (np.abs(dG) @ np.abs(u[:-1])))
            assert abs(g[j] - d1) <= abs(d2 - d1) + 8 * eps * A / h + own, (j, g[j], d1, d2)


@pytest.mark.parametrize("backend", ["modal", "banded"])
def test_the_amplitude_gradient_is_that_of_unit_motions(chain, backend):
    """The cosine and pole entries of ∇A against s cos kτ* applied to the row of each unit
    motion (``_amplitude_row`` of e_c at every harmonic, of each η_p): the same products
    summed in another order, round-off of the row's entries (~1e-15 of the largest)."""
    p = MMSHBMProblem(chain, harmonics=15, backend=backend)
    u = _state(p, 1.1 * p.omega_ref, 3)
    _, g = p.amplitude_and_gradient(u)
    _, cosk, _, s = p._amplitude_peak(u)
    _, omega = p.unpack(u)
    n_a = (p.H + 1) * p.n_c
    own = np.empty(len(u) - 1)
    for c in range(p.n_c):
        e = np.zeros((p.H + 1, p.n_c))
        e[:, c] = 1.0
        own[c:n_a:p.n_c] = s * p._amplitude_row(e, omega, np.zeros(p.n_poles)) * cosk
    for q in range(p.n_poles):
        e = np.zeros(p.n_poles)
        e[q] = 1.0
        own[n_a + q] = s * (p._amplitude_row(np.zeros((p.H + 1, p.n_c)), omega, e) @ cosk)
    own *= p.colscale[:-1]
    assert np.abs(g[:-1] - own).max() <= 1e-12 * np.abs(own).max()
