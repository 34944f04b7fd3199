"""Admissible signals: the massless DOFs from the exact static contact problem."""

import warnings

import numpy as np
import pytest
import scipy.sparse as sp

import mmshbm
from mmshbm import BranchWarning
from mmshbm.contact.static import StaticContact, admissible_signals


@pytest.fixture(scope="module")
def beam_branch():
    model = mmshbm.default_beam().model(21)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BranchWarning)
        return mmshbm.backbone(model, harmonics=5, max_amplitude=3.2e-3), model


def test_no_penetration_and_signorini(beam_branch):
    branch, model = beam_branch
    gap, side, d = model.gap, model.stop_side, model.contact_dof
    i = int(np.argmax(branch.amplitude > 3e-3))  # point 2 of Figure 2: the series passes the stop
    _, q_series = branch.time_signals(i, dofs=[d], n_samples=1024)
    assert (side * q_series[0] - gap).max() > 0.3 * gap
    t, q = branch.time_signals(i, n_samples=1024, admissible=True)
    _, lam = branch.contact_force(i, n_samples=1024, admissible=True)
    g = gap - side * q[d]
    assert g.min() >= -1e-12 * gap  # never through the stop
    assert lam.min() >= 0.0
    assert np.abs(g * lam).max() <= 1e-9 * gap * lam.max()  # complementarity
    assert np.all(lam[g > 1e-9 * gap] == 0.0)  # exactly zero where open
    # the DOFs with mass keep their truncated series
    _, q_all = branch.time_signals(i, n_samples=1024)
    np.testing.assert_array_equal(q[model.l], q_all[model.l])
    # static equilibrium of the massless DOFs: K_cc q_c + K_cl q_l = w λ
    b = model.blocks
    w = np.zeros(len(model.c))
    w[model.contact_index] = -side
    residual = b["K_cc"] @ q[model.c] + b["K_lc"].T @ q[model.l] - np.outer(w, lam)
    assert np.abs(residual).max() <= 1e-8 * np.abs(b["K_lc"].T @ q[model.l]).max()


def test_single_contact_closed_form(beam_branch):
    """λ = k_c max(0, −h(q_l)) (docs/exact.md) with k_c the static contact stiffness."""
    branch, model = beam_branch
    i = len(branch) - 1
    _, q, lam = admissible_signals(model, branch.solver.coefficients(branch.states[i]),
                                   2 * np.pi * branch.frequency[i], 256)
    b = model.blocks
    q_free = -np.linalg.solve(b["K_cc"], b["K_lc"].T @ q[model.l])
    h = model.gap - model.stop_side * q_free[model.contact_index]
    e = np.zeros(len(model.c))
    e[model.contact_index] = 1.0
    k_c = 1.0 / (e @ np.linalg.solve(b["K_cc"], e))
    np.testing.assert_allclose(lam[0], k_c * np.maximum(0.0, -h), rtol=1e-9, atol=1e-12 * k_c * model.gap)


def test_open_contact_gives_exact_zero(beam_branch):
    branch, model = beam_branch
    assert branch.amplitude[0] < model.gap
    t, lam = branch.contact_force(0, admissible=True)
    assert np.all(lam == 0.0)
    _, q = branch.time_signals(0, dofs=list(model.c), admissible=True)
    _, q_series = branch.time_signals(0, dofs=list(model.c))
    np.testing.assert_allclose(q, q_series, atol=1e-12 * model.gap)


def test_several_contacts_lcp():
    """Two stops (tip deflection and tip rotation): the per-sample LCP satisfies
    λ >= 0, g >= 0, g·λ = 0 with g = gap + Wᵀ q_c, and matches a brute-force solve."""
    base = mmshbm.default_beam().model(6)
    c = [int(x) for x in base.c]
    model = mmshbm.Model.from_matrices(base.M, base.K, c, [1e-3, 2e-3], [1, -1])
    static = StaticContact(model)
    rng = np.random.default_rng(3)
    q_l = 3e-3 * rng.standard_normal((len(model.l), 200))
    q_c, lam = static.solve(q_l)
    g = static.gaps[:, None] + static.W.T @ q_c
    assert lam.min() >= 0 and g.min() >= -1e-12
    assert np.abs(g * lam).max() <= 1e-9 * 1e-3 * max(lam.max(), 1.0)
    assert np.any(lam[0] > 0) and np.any(lam[1] > 0) and np.any((lam[0] > 0) & (lam[1] > 0))
    # brute force on a fine grid of both forces at one sample with both contacts closed
    j = int(np.flatnonzero((lam[0] > 0) & (lam[1] > 0))[0])
    h = static.gaps + static.W.T @ (static.B @ q_l[:, j])
    np.testing.assert_allclose(static.G @ lam[:, j], -h, rtol=1e-10)


def test_clearance_on_one_dof():
    """A DOF between two stops (gaps 1 and 2 mm): G is singular, the LCP still exact."""
    base = mmshbm.default_beam().model(6)
    d = int(base.contact_dof)
    model = mmshbm.Model.from_matrices(sp.csr_matrix(base.M), sp.csr_matrix(base.K), [d, d], [1e-3, 2e-3],
                                       [1, -1])
    static = StaticContact(model)
    q_l = 5e-3 * np.random.default_rng(1).standard_normal((len(model.l), 100))
    q_c, lam = static.solve(q_l)
    x = q_c[list(model.c).index(d)]
    assert x.max() <= 1e-3 * (1 + 1e-12) and x.min() >= -2e-3 * (1 + 1e-12)
    assert lam.min() >= 0 and not np.any((lam[0] > 0) & (lam[1] > 0))


def test_shooting_signals_are_already_admissible():
    model = mmshbm.default_beam().model(4)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BranchWarning)
        branch = mmshbm.backbone(model, method="shooting", max_amplitude=1.5e-3, steps_per_period=64)
    i = len(branch) - 1
    np.testing.assert_array_equal(branch.time_signals(i, admissible=True)[1], branch.time_signals(i)[1])


def test_bad_input():
    model = mmshbm.default_beam().model(4)
    with pytest.raises(ValueError, match="Q must have shape"):
        admissible_signals(model, np.zeros((3, 3)), 1.0)
    with pytest.raises(ValueError, match="n_samples"):
        admissible_signals(model, np.zeros((model.n_dof, 3)), 1.0, n_samples=0)


def test_peak_force_before_grazing_is_exactly_zero(tmp_path):
    """Open contact, exact zeros: in the branch (the monitor) and in its CSV."""
    model = mmshbm.default_beam().model(21)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BranchWarning)
        branch = mmshbm.backbone(model, harmonics=5, max_amplitude=0.95e-3)
    assert np.all(branch.contact_force_max == 0.0)
    rows = branch.to_csv(tmp_path / "b.csv").read_text().splitlines()[1:]
    assert all(row.split(",")[3] == "0.0" for row in rows)
