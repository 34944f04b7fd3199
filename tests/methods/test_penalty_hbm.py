"""Penalty harmonic balance (baseline 1): kernels and Jacobian against plain-NumPy
references and finite differences, the one-DOF closed form as k_p grows, agreement with
MMS-HBM on the beam, and the sparse structure.

The error tables these tests assert are reported in docs/penalty.md.
"""

import numpy as np
import pytest
import scipy.sparse as sp
from finite_differences import assert_jacobian

import mmshbm
from mmshbm.harmonic.harmonics import default_n_samples
from mmshbm.methods.penalty._kernels import _penalty_contacts
from mmshbm.methods.penalty.defaults import _condensed_contact_stiffness
from mmshbm.methods.penalty.hbm import (
    DEFAULT_PENALTY_FACTOR,
    PenaltyHBMProblem,
    penalty_n_samples,
)

OSC = mmshbm.OneDofOscillator(m=1.0, k1=1.0, k2=4.0, gap=1.0)
FACTORS = (1e2, 1e3, 1e4)  # k_p / k_c


# ----------------------------------------------------------------------------- references
def penalty_contact_loop(q, gap, side, kp):
    """Plain loop: λ_j = kp max(0, side q_j − gap), active_j = [side q_j > gap]."""
    lam = np.zeros(len(q))
    active = np.zeros(len(q))
    for j, qj in enumerate(q):
        pen = side * qj - gap
        if pen > 0:
            lam[j], active[j] = kp * pen, 1.0
    return lam, active


def _dft(H, N):
    """Cosine synthesis C (H+1, N) and projection weights c_m/N (H+1,)."""
    tau = 2 * np.pi * np.arange(N) / N
    C = np.cos(np.outer(np.arange(H + 1), tau))
    w = np.full(H + 1, 2.0 / N)
    w[0] = 1.0 / N
    return C, w


def naive_residual(p: PenaltyHBMProblem, u):
    """Dense residual from explicit cosine sums (scaled like ``p.evaluate``)."""
    Q, om = p.unpack(u)
    K, M = p.K.toarray(), p.M.toarray()
    C, w = _dft(p.H, p.N)
    q = Q[:, p.cd] @ C
    lam, _ = penalty_contact_loop(q, p.gap, p.side, p.penalty_stiffness)
    lam_k = w * (C @ lam)
    R = np.array([(K - (k * om) ** 2 * M) @ Q[k] for k in range(p.H + 1)])
    R[:, p.cd] += p.side * lam_k
    return R.ravel() / p.rowscale


def naive_jacobian(p: PenaltyHBMProblem, u):
    """Dense Jacobian by the textbook formulas (scaled like ``p.evaluate``)."""
    Q, om = p.unpack(u)
    K, M = p.K.toarray(), p.M.toarray()
    n, H = p.n, p.H
    C, w = _dft(H, p.N)
    _, s = penalty_contact_loop(Q[:, p.cd] @ C, p.gap, p.side, p.penalty_stiffness)
    J = np.zeros((n * (H + 1), n * (H + 1) + 1))
    for m in range(H + 1):
        J[m * n:(m + 1) * n, m * n:(m + 1) * n] = K - (m * om) ** 2 * M
        J[m * n:(m + 1) * n, -1] = -2 * m**2 * om * (M @ Q[m])
        for k in range(H + 1):
            J[m * n + p.cd, k * n + p.cd] += p.penalty_stiffness * w[m] * np.sum(s * C[m] * C[k])
    return J * p.colscale[None, :] / p.rowscale[:, None]


def _contact_point(problem, amplitude_gaps=1.6, seed=0):
    """Scaled unknowns of the linear mode at ``amplitude_gaps`` gaps (contact active on
    part of the period) plus a random perturbation of every harmonic."""
    rng = np.random.default_rng(seed)
    u = problem.linear_point(amplitude_gaps * problem.gap)
    u[:-1] += 0.05 * rng.standard_normal(len(u) - 1)
    u[-1] *= 1.1
    return u


# ----------------------------------------------------------------------------- kernels
@pytest.mark.parametrize("side", [1.0, -1.0])
def test_penalty_contact_kernel_equals_loop(side):
    rng = np.random.default_rng(1)
    q = rng.uniform(-3e-3, 3e-3, (1, 200))
    force, act = np.empty((1, 200)), np.empty((1, 200))
    _penalty_contacts(q, np.array([0]), np.array([1e-3]), np.array([side]), np.array([2e7]),
                      np.array([2e7]), force, act)
    lam_ref, act_ref = penalty_contact_loop(q[0], 1e-3, side, 2e7)
    np.testing.assert_allclose(force[0], side * lam_ref, rtol=1e-14, atol=0)
    np.testing.assert_array_equal(act[0], act_ref)
    assert 0 < act.sum() < 200


def test_penalty_kernel_sums_the_contacts_of_a_dof():
    """A clearance (two stops on one DOF, different k_p) and a third contact on another DOF:
    the net force per DOF is Σ side_i λ_i and the active weights are k_p,i / k_p,ref."""
    rng = np.random.default_rng(2)
    q = rng.uniform(-3e-3, 3e-3, (2, 300))
    slot, gap = np.array([0, 0, 1]), np.array([1e-3, 2e-3, 0.5e-3])
    side, kp = np.array([1.0, -1.0, -1.0]), np.array([2e7, 1e7, 3e5])
    kp_ref = np.array([2e7, 3e5])
    force, act = np.empty((2, 300)), np.empty((2, 300))
    _penalty_contacts(q, slot, gap, side, kp, kp_ref, force, act)
    f_ref, a_ref = np.zeros((2, 300)), np.zeros((2, 300))
    for i in range(3):
        lam, s = penalty_contact_loop(q[slot[i]], gap[i], side[i], kp[i])
        f_ref[slot[i]] += side[i] * lam
        a_ref[slot[i]] += kp[i] / kp_ref[slot[i]] * s
    np.testing.assert_allclose(force, f_ref, rtol=1e-14, atol=0)
    np.testing.assert_allclose(act, a_ref, rtol=1e-15, atol=0)
    assert np.all(act[0] <= 1.0) and set(np.unique(act[0])) == {0.0, 0.5, 1.0}


@pytest.fixture(scope="module")
def small_beam():
    return PenaltyHBMProblem(mmshbm.default_beam().model(4), harmonics=3)


def test_residual_equals_naive(small_beam):
    u = _contact_point(small_beam)
    R, J = small_beam.evaluate(u)
    np.testing.assert_allclose(R, naive_residual(small_beam, u), rtol=1e-10, atol=1e-12 * np.abs(R).max())


def test_jacobian_kernel_equals_naive(small_beam):
    u = _contact_point(small_beam)
    _, J = small_beam.evaluate(u)
    assert sp.issparse(J)
    J_ref = naive_jacobian(small_beam, u)
    np.testing.assert_allclose(J.toarray(), J_ref, rtol=1e-10, atol=1e-12 * np.abs(J_ref).max())


@pytest.mark.parametrize("model", ["oscillator", "beam"])
def test_jacobian_equals_finite_difference(model, small_beam):
    problem = small_beam if model == "beam" else PenaltyHBMProblem(OSC.model(), harmonics=6)
    u = _contact_point(problem, seed=3)
    _, J = problem.evaluate(u)
    J = J.toarray()
    # semismooth: a sample switching inside the step fails the check's own smoothness test
    assert_jacobian(lambda v: problem.evaluate(v, False), u, J, 1e-5)


def test_jacobian_is_sparse_and_no_dense_matrix_of_full_size():
    """On the default beam the Jacobian stores O(H n) entries, not (n(H+1))²; the
    continuation's bordered solve keeps it sparse."""
    model = mmshbm.default_beam().model(21)
    p = PenaltyHBMProblem(model, harmonics=20)
    _, J = p.evaluate(_contact_point(p))
    rows = p.n * (p.H + 1)
    assert isinstance(J, sp.csr_matrix) and J.shape == (rows, rows + 1)
    nnz_block = (abs(model.K) + abs(model.M)).nnz
    assert J.nnz <= (p.H + 1) * nnz_block + (p.H + 1) ** 2 + p.H * len(model.l)
    assert J.nnz < 0.02 * rows * (rows + 1)
    # no array of the problem has two dimensions of the system's size
    for value in vars(p).values():
        if isinstance(value, np.ndarray):
            assert not (value.ndim == 2 and min(value.shape) >= rows), value.shape


def test_bad_input():
    with pytest.raises(ValueError, match="penalty_stiffness"):
        PenaltyHBMProblem(OSC.model(), penalty_stiffness=-1.0)
    with pytest.raises(TypeError, match="Model"):
        PenaltyHBMProblem("beam")


def test_default_penalty_is_a_multiple_of_the_condensed_static_stiffness():
    p = PenaltyHBMProblem(OSC.model())
    assert p.contact_stiffness == pytest.approx(OSC.contact_stiffness, rel=1e-12)
    assert p.penalty_stiffness == pytest.approx(DEFAULT_PENALTY_FACTOR * OSC.contact_stiffness, rel=1e-12)


def test_default_samples_grow_with_penalty_stiffness():
    for H in (5, 20):
        N0 = default_n_samples(H)
        assert penalty_n_samples(H, 1e2) == penalty_n_samples(H, 1e3) == N0
        assert penalty_n_samples(H, 1e4) == 2 * N0 and penalty_n_samples(H, 1e6) == 8 * N0
    assert PenaltyHBMProblem(OSC.model(), harmonics=5, penalty_stiffness=1e5 * OSC.contact_stiffness).N \
        == 4 * default_n_samples(5)
    with pytest.raises(ValueError, match="penalty_factor"):
        penalty_n_samples(5, 0.0)


# ----------------------------------------------------------------------------- one DOF
def _freq(method, H, A, **kw):
    br = mmshbm.backbone(OSC.model(), harmonics=H, method=method, max_amplitude=A * OSC.gap, **kw)
    assert br.status == "bound:amplitude", br.status
    assert br.amplitude[-1] == pytest.approx(A * OSC.gap, rel=1e-9)
    return br.frequency[-1]


@pytest.fixture(scope="module")
def one_dof_table():
    """Relative frequency errors at 2 gaps: {(H, k_p/k_c): (vs closed form, vs MMS-HBM)}."""
    f_exact = float(OSC.frequency(2.0))
    table = {}
    for H in (5, 10, 20):
        f_mms = _freq("mmshbm", H, 2.0)
        table[H, "mms"] = ((f_mms - f_exact) / f_exact, 0.0)
        for fac in FACTORS + (1e6,):
            f = _freq("penalty", H, 2.0, penalty_stiffness=fac * OSC.contact_stiffness)
            table[H, fac] = ((f - f_exact) / f_exact, (f - f_mms) / f_mms)
    return table


def test_one_dof_penalty_converges_to_closed_form_and_mmshbm(one_dof_table):
    """At H = 20 (truncation below the penalty error) the error against the closed form
    and against MMS-HBM at the same H falls about tenfold per decade of k_p, as
    predicted by |e| ≈ C k_c/k_p with C ≈ 0.4 (docs/penalty.md)."""
    t = one_dof_table
    exact = [abs(t[20, f][0]) for f in FACTORS]
    mms = [abs(t[20, f][1]) for f in FACTORS]
    assert exact[0] > exact[1] > exact[2] and mms[0] > mms[1] > mms[2], t
    for fac, e in zip(FACTORS, exact, strict=True):
        assert e < 0.5 / fac + 1e-4  # prediction C k_c/k_p (C <= 0.5) + truncation at H = 20
    assert exact[0] > 0.2 / FACTORS[0]  # the k_p error is real, not hidden in round-off
    assert exact[2] < 1.5e-4 and mms[2] < 1.5e-4


def test_one_dof_penalty_limit_is_a_different_truncation(one_dof_table):
    """As k_p -> oo at fixed H the penalty backbone tends to its own H-truncated limit,
    not to MMS-HBM's: the penalty's contact force is the positive part of a degree-H
    polynomial times k_p, whose limit is impulsive, while MMS-HBM keeps the node on the
    stop over the closed phase. The gap closes as H grows."""
    t = one_dof_table
    gap_to_mms = {H: abs(t[H, 1e6][1]) for H in (5, 10, 20)}
    assert gap_to_mms[5] > 1e-3 and gap_to_mms[20] < 1e-4
    assert gap_to_mms[5] > gap_to_mms[10] > gap_to_mms[20]
    # and at fixed H the penalty's own k_p convergence: 1e4 is within 1e-3 of the limit
    for H in (5, 10, 20):
        assert abs(t[H, 1e4][0] - t[H, 1e6][0]) < 1e-3


# ----------------------------------------------------------------------------- beam
def test_beam_penalty_agrees_with_mmshbm_within_predicted_error():
    """Default beam (21 elements) at 1.05 gaps: the penalty error C k_c/k_p (C ≈ 0.1
    at H = 20, bounded here by C = 2) plus the difference of the two truncations (measured 2.2e-4 at H = 20)
    bounds the discrepancy; at H = 5 the two formulations differ by 3 % already here
    (docs/penalty.md), so the comparison is made at H = 20."""
    model = mmshbm.default_beam().model(21)
    A, H = 1.05 * model.gap, 20
    f_mms = mmshbm.backbone(model, harmonics=H, max_amplitude=A).frequency[-1]
    kc = _condensed_contact_stiffness(model)
    freqs = {}
    for fac in (1e2, 1e3):
        br = mmshbm.backbone(model, harmonics=H, method="penalty", max_amplitude=A,
                             penalty_stiffness=fac * kc)
        assert br.status == "bound:amplitude"
        freqs[fac] = br.frequency[-1]
    err = {fac: abs(f - f_mms) / f_mms for fac, f in freqs.items()}
    predicted = {fac: 2.0 / fac + 3e-4 for fac in freqs}
    assert all(err[f] < predicted[f] for f in freqs), (err, predicted)
    assert err[1e3] < err[1e2]
    assert err[1e3] < 5e-4


def test_beam_at_two_gaps_equal_H_agreement():
    """At 2 gaps (the issue's comparison amplitude) and H = 20 the penalty backbone
    (default k_p = 10³ k_c) meets MMS-HBM within the predicted penalty error (Richardson
    estimate from k_p = 10² k_c) plus the truncation difference of the two formulations
    (measured 2e-4..7e-4 at H = 20, docs/penalty.md). At H = 5 the two differ by 3 %,
    a truncation effect of the penalty formulation, not a penalty error (see docs)."""
    model = mmshbm.default_beam().model(21)
    A, H = 2.0 * model.gap, 20
    # plain path following, as the penalty branch does: both follow the same branch (which
    # at H = 20 climbs the 17:1 tongue with mode 3 at 46.9 Hz; the family-following
    # default jumps it and ends on the first-mode backbone at 59.5 Hz instead)
    f_mms = mmshbm.backbone(model, harmonics=H, max_amplitude=A, follow="path").frequency[-1]
    kc = _condensed_contact_stiffness(model)
    f = {}
    for fac in (1e2, 1e3):
        br = mmshbm.backbone(model, harmonics=H, method="penalty", max_amplitude=A,
                             penalty_stiffness=fac * kc)
        assert br.status == "bound:amplitude"
        f[fac] = br.frequency[-1]
    penalty_error = abs(f[1e3] - f[1e2]) / 9 / f[1e3]  # e(k_p) ~ 1/k_p
    assert penalty_error < 2.0 / 1e3
    assert abs(f[1e3] - f_mms) / f_mms < penalty_error + 1e-3
