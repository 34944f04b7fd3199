"""The bolted lap joint (mmshbm.lap_joint): its reduction against the unreduced scikit-fem
structure — the bonded joint's first bending frequency, the stuck interface's linear
response, the frictionless interface's — and its bad input."""

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import mmshbm
from mmshbm.fe.lap_joint import grid_shape, lap_joint
from mmshbm.methods.mms.friction_forced import FrictionForcedProblem
from mmshbm.model.contact_pairs import pair_dofs


@pytest.fixture(scope="module")
def stuck():
    return lap_joint(8, mu=1e4, modal_damping=0.0)


@pytest.fixture(scope="module")
def frictionless():
    return lap_joint(8, mu=0.0, modal_damping=0.0)


def _tip_harmonic(joint, frequency):
    P = FrictionForcedProblem(joint.model, joint.force, harmonics=3)
    u, ok = P.solve_at(frequency, P.linear_response_point(frequency))
    assert ok
    q = P.coefficients(u)[0]
    return q[1] - 1j * q[2], q


def test_the_joint_is_a_reduced_model_of_pairs(stuck):
    model = stuck.model
    assert model.amplitude_dof == 0 and stuck.force[0] == 1.0 and np.count_nonzero(stuck.force) == 1
    slip = pair_dofs(model)
    assert slip.shape == (8, 2) and set(model.c.tolist()) == set(slip.ravel().tolist())
    assert [fc.dof for fc in model.friction] == slip.ravel().tolist()
    # the bolt's preload shared by the pairs, most under the bolt
    assert np.isclose(stuck.preloads.sum(), 2000.0, rtol=1e-12)
    f0, f1 = stuck.frequency_range
    assert f0 < stuck.bending_frequency < f1
    assert mmshbm.lap_joint is lap_joint and mmshbm.fe.lap_joint is lap_joint


def test_bending_frequency_is_the_scikit_fem_structures(stuck):
    full = stuck.full
    w2 = spla.eigsh(full["K"], k=1, M=full["M"], sigma=0.0)[0][0]
    f_full = np.sqrt(w2) / (2 * np.pi)
    # the reduction's basis holds the bonded joint's modes as ARPACK computes them: the
    # frequencies agree to ARPACK's accuracy (measured 2e-9)
    assert abs(stuck.bending_frequency / f_full - 1) < 1e-7
    assert 20.0 < f_full < 50.0


def test_stuck_interface_is_the_bonded_joints_linear_response(stuck):
    f = 0.9 * stuck.bending_frequency
    omega = 2 * np.pi * f
    tip, q = _tip_harmonic(stuck, f)
    full = stuck.full
    e = np.zeros(full["M"].shape[0])
    e[full["tip"]] = 1.0
    ref = spla.spsolve((full["K"] - omega**2 * full["M"]).tocsc(), e)[full["tip"]]
    # the reduction is exact for the static load and holds the bonded modes; what is left
    # is the inertia of the modes above the eighth (measured 4e-8) and the solves' round-off
    assert abs(tip - ref) <= 1e-6 * abs(ref)
    assert np.abs(q[3:]).max() <= 1e-12 * abs(ref)  # linear: no higher harmonics


def test_frictionless_interface_is_the_split_plates(frictionless):
    f = 0.9 * frictionless.bending_frequency
    omega = 2 * np.pi * f
    tip, _ = _tip_harmonic(frictionless, f)
    full = frictionless.full
    n_l, n_c = full["M"].shape[0], full["K_cc"].shape[0]
    A = sp.bmat([[full["K"] - omega**2 * full["M"], full["K_lc"]], [full["K_lc"].T, full["K_cc"]]]).tocsc()
    rhs = np.zeros(n_l + n_c)
    rhs[full["tip"]] = 1.0
    ref = spla.spsolve(A, rhs)[full["tip"]]
    # the plates joined by the bolt and the normal stiffness only: the interface slides
    # freely, its motion's inertia carried by the interface modes (measured 4e-7; 3.5e-5
    # with twice the modes, the size of the reduction's error)
    assert abs(tip - ref) <= 1e-4 * abs(ref)
    # and far from the stuck joint's (the interface carries no shear)
    assert abs(ref) > 2 * abs(_stuck_reference(frictionless, omega))


def _stuck_reference(joint, omega):
    full = joint.full
    e = np.zeros(full["M"].shape[0])
    e[full["tip"]] = 1.0
    return spla.spsolve((full["K"] - omega**2 * full["M"]).tocsc(), e)[full["tip"]]


def test_grid_shape():
    assert grid_shape(100) == (10, 10) and grid_shape(1000) == (40, 25) and grid_shape(8) == (4, 2)


@pytest.mark.parametrize("kwargs, match", [
    ({"contact_nodes": 7}, "composite"),
    ({"contact_nodes": 8, "overlap": 0.3}, "overlap"),
    ({"contact_nodes": 8, "mu": -0.1}, "mu"),
    ({"contact_nodes": 8, "normal": "glued"}, "normal"),
    ({"contact_nodes": 8, "n_interface": -1}, "n_interface"),
    ({"contact_nodes": 8, "n_modes": 0}, "n_modes"),
])
def test_bad_input_is_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        lap_joint(**kwargs)


def test_interface_reduction_keeps_the_static_interface_and_the_tip_exact():
    """On a chain of 60 masses with 6 massless interface DOFs: the reduced model's static
    condensation onto the interface and its static tip response to a tip load are the full
    model's (round-off of the solves: a few ε times the condition, ~1e-10 here)."""
    from mmshbm.model.interface_reduction import reduce_to_interface

    rng = np.random.default_rng(3)
    n_l, n_c = 60, 6
    k = 1e4 * (1 + rng.random(n_l + 1))
    K_ll = sp.diags([k[:-1] + k[1:], -k[1:-1], -k[1:-1]], [0, 1, -1], format="csr").tolil()
    M_ll = sp.diags(1 + rng.random(n_l), format="csr")
    attach = rng.choice(n_l, n_c, replace=False)
    k_i = 5e3 * (1 + rng.random(n_c))
    K_lc = sp.csr_matrix((-k_i, (attach, np.arange(n_c))), shape=(n_l, n_c))
    for a, kk in zip(attach, k_i, strict=True):
        K_ll[a, a] += kk
    K_ll = K_ll.tocsr()
    K_cc = sp.diags(k_i, format="csr")
    tip = 37
    red = reduce_to_interface(M_ll, K_ll, K_lc, K_cc, tip, n_modes=4, n_interface=3)
    n_r = red.n_reduced
    D0_full = K_cc.toarray() - K_lc.T.toarray() @ np.linalg.solve(K_ll.toarray(), K_lc.toarray())
    Kr = red.K
    D0_red = Kr[n_r:, n_r:] - Kr[n_r:, :n_r] @ np.linalg.solve(Kr[:n_r, :n_r], Kr[:n_r, n_r:])
    assert np.abs(D0_red - D0_full).max() <= 1e-9 * np.abs(D0_full).max()
    # a unit tip load, the interface free: the tip's static displacement
    K_full = sp.bmat([[K_ll, K_lc], [K_lc.T, K_cc]]).toarray()
    f = np.zeros(n_l + n_c)
    f[tip] = 1.0
    q_full = np.linalg.solve(K_full, f)
    q_red = np.linalg.solve(Kr, red.load(f[:n_l]))
    assert abs(q_red[0] - q_full[tip]) <= 1e-9 * abs(q_full[tip])
    assert np.abs(q_red[n_r:] - q_full[n_l:]).max() <= 1e-9 * np.abs(q_full[n_l:]).max()
    assert np.allclose(red.basis[tip], np.eye(n_r)[0], atol=1e-12)


def test_unilateral_pairs_open_and_close():
    """normal="unilateral": a stop per pair at gap 0, the tangents pressed by its contact force;
    at the bending frequency the forced orbit converges with the pairs closing (contact
    force) and slipping part of the period."""
    joint = lap_joint(8, normal="unilateral")
    model = joint.model
    assert len(model.contacts) == 8 and all(c.side == -1 and c.gap == 0.0 for c in model.contacts)
    assert [fc.normal_contact for fc in model.friction] == [p for p in range(8) for _ in range(2)]
    P = FrictionForcedProblem(model, joint.force, harmonics=3)
    u = P.start_point(joint.bending_frequency)
    x, omega = P.unpack(u)
    assert np.abs(P.residual_parts(x, omega, 1.0, False)[0] / P.rowscale).max() < 1e-10
    rec = P._record(x, omega, 1.0)
    assert rec["contact_force_max"] > 0 and 0 < rec["slip_fraction"] < 1


# ---------------------------------------------------------------------- condensation back end
@pytest.fixture(scope="module")
def joint16():
    return lap_joint(16)


def test_auto_backend_follows_the_operation_counts(joint16):
    """``backend="auto"`` of the damped condensation: modal while n_c stays below ~1.37 n_l
    (damped; ``modal_is_cheaper``), direct above: the beam (40 DOFs with mass, 2 massless)
    keeps the modal back end, the 8-pair joint (21 + 16) too, the 16-pair joint (21 + 32)
    takes the direct one."""
    from mmshbm.methods.mms.condensation.damped_condense import DampedCondensation, modal_is_cheaper

    beam = mmshbm.default_beam().model(21).with_damping(modal_ratio=0.01)
    assert (len(beam.l), len(beam.c)) == (40, 2)
    assert DampedCondensation(beam).backend == "modal"
    small = lap_joint(8).model
    assert (len(small.l), len(small.c)) == (21, 16) and DampedCondensation(small).backend == "modal"
    big = joint16.model
    assert (len(big.l), len(big.c)) == (21, 32) and DampedCondensation(big).backend == "direct"
    # the crossover of 3 r³ − r² − 4 r − 1/3 (damped) lies between r = 1.35 and 1.40
    assert modal_is_cheaper(100, 135, True) and not modal_is_cheaper(100, 140, True)
    assert modal_is_cheaper(100, 105, False) and not modal_is_cheaper(100, 107, False)
    assert DampedCondensation(big, backend="modal").backend == "modal"  # an explicit choice is kept


def test_modal_and_direct_condensations_agree_on_the_joint(joint16):
    """D_k of both back ends over the frequency range within their round-off: the direct
    one's Z_k = S_k⁻¹ K_lc to n_l ε κ(S_k) and the cancellation in K_cc − K_lcᵀ Z_k, the modal
    one's inverse of A_k ≈ D_k⁻¹ to n_c ε κ(D_k) ‖D_k‖ (tests/roundoff.py, 4 ulps)."""
    from roundoff import EPS

    from mmshbm.methods.mms.condensation.damped_condense import DampedCondensation

    model = joint16.model
    b = model.blocks
    B = joint16.force[model.l][:, None]
    modal, direct = DampedCondensation(model, B, "modal"), DampedCondensation(model, B, "direct")
    K, M, C = (b[n].toarray() for n in ("K_ll", "M_ll", "C_ll"))
    K_lc, K_cc = np.asarray(b["K_lc"]), np.asarray(b["K_cc"])
    n_l, n_c = K.shape[0], K_cc.shape[0]
    for f in np.linspace(*joint16.frequency_range, 3):
        omega = 2 * np.pi * f
        a = modal.evaluate(omega, 3, recover=False)
        d = direct.evaluate(omega, 3, recover=True)
        for k in range(1, 4):
            S = K + 1j * k * omega * C - (k * omega) ** 2 * M
            scale = np.abs(K_cc) + np.abs(K_lc).T @ np.abs(d.Z[k])
            tol = 4 * EPS * (n_l * np.linalg.cond(S) * scale
                             + n_c * np.linalg.cond(d.D[k]) * np.abs(d.D[k]).max())
            assert np.all(np.abs(a.D[k] - d.D[k]) <= tol), (f, k)
        assert np.abs(a.P - d.P).max() <= 4 * EPS * (n_l + n_c) * np.linalg.cond(d.D[1]) * np.abs(d.P).max()


def test_modal_and_direct_forced_points_agree_on_the_joint(joint16):
    """The forced response with friction at fixed frequency (slip over part of the period):
    the modal back end's point is the direct one's within the bound the direct residuals of
    both points allow (‖J⁻¹‖∞ (r_d + r_m), scaled unknowns, times 2): the modal
    condensation's round-off enters through r_m."""
    model = joint16.model
    direct = FrictionForcedProblem(model, joint16.force, harmonics=3, backend="direct")
    modal = FrictionForcedProblem(model, joint16.force, harmonics=3, backend="modal")
    assert direct.cond.backend == "direct" and modal.cond.backend == "modal"

    def scaled(u):
        x, omega = direct.unpack(u)
        R, Jx, _, _ = direct.residual_parts(x, omega, 1.0, True)
        return R / direct.rowscale, Jx * direct.xscale[None, :] / direct.rowscale[:, None]

    f = joint16.bending_frequency
    guess = direct.linear_response_point(f)
    u_d, ok_d = direct.solve_at(f, guess)
    u_m, ok_m = modal.solve_at(f, guess)
    assert ok_d and ok_m
    x, omega = direct.unpack(u_d)
    assert 0.05 < direct._record(x, omega, 1.0)["slip_fraction"] < 0.999
    R_d, J = scaled(u_d)
    R_m, _ = scaled(u_m)
    bound = 2 * np.abs(np.linalg.inv(J)).sum(axis=1).max() * (np.abs(R_d).max() + np.abs(R_m).max())
    assert np.abs(u_m - u_d)[:direct.n_x].max() <= max(bound, 1e-13)


def test_builds_repeat_bit_for_bit():
    """The same build twice in one process gives the same model, number for number (the
    reduction's eigensolver starts from a fixed vector, not from ARPACK's generator, which
    advances with every call: a continuation on two builds then takes the same steps)."""
    a, b = lap_joint(4), lap_joint(4)
    for name in ("K", "M"):
        A, B = getattr(a.model, name), getattr(b.model, name)
        A = A.toarray() if hasattr(A, "toarray") else np.asarray(A)
        B = B.toarray() if hasattr(B, "toarray") else np.asarray(B)
        assert np.array_equal(A, B), name
    assert a.bending_frequency == b.bending_frequency
