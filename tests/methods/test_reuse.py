"""What a run keeps instead of computing again gives the numbers it would compute: the
compiled overloads typed once per argument types, the corrector's tangent solve, the
condensed stiffness of the converged points, the per-(H, N) tables and the modal
selection."""

import numpy as np
import pytest

import mmshbm
from mmshbm.core._entry import _type_key, compiled_entry
from mmshbm.core.bordered import bordered_solve_sign
from mmshbm.core.steps import _tangent_sign
from mmshbm.harmonic.kernels import _dense_solve
from mmshbm.methods.mms.conservative import MMSHBMProblem


def _system(n=7, seed=3):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n)) + n * np.eye(n)
    return A, rng.standard_normal(n)


def test_type_key_tells_apart_what_numba_types_apart():
    c = np.zeros((3, 4))
    readonly = c.copy()
    readonly.flags.writeable = False
    keys = {_type_key(c), _type_key(np.asfortranarray(c)), _type_key(c[:, ::2]), _type_key(readonly),
            _type_key(c.astype(np.float32)), _type_key(c[0])}
    assert len(keys) == 6
    assert _type_key(np.ones((5, 2))) == _type_key(c)  # shape and values do not matter
    assert _type_key(c[1:]) == _type_key(c)  # a C-contiguous view is typed as the array
    assert _type_key(3) != _type_key(2**63) and _type_key(3) != _type_key(3.0) != _type_key(True)
    assert _type_key((c, 1.0)) != _type_key((c, 1))
    assert _type_key((c, None)) is None  # not described: typed in full every time


def test_compiled_entry_is_kept_per_types_and_solves():
    A, b = _system()
    if not hasattr(_dense_solve, "compile"):
        pytest.skip("NUMBA_DISABLE_JIT")
    n = len(b)

    def args(A):
        return (A, b, np.empty((n, n)), np.empty(n), np.zeros(1))

    first = args(A)
    entry = compiled_entry(_dense_solve, first)
    assert compiled_entry(_dense_solve, args(A.copy())) is entry  # same types: not typed again
    fortran = args(np.asfortranarray(A))
    other = compiled_entry(_dense_solve, fortran)
    assert other is not entry
    for call, a in ((entry, first), (other, fortran)):
        assert call(*a) == 0
        np.testing.assert_allclose(a[3], np.linalg.solve(A, b), rtol=1e-12, atol=1e-12)
        assert a[4][0] == np.sign(np.linalg.det(A))


@pytest.fixture(scope="module")
def beam():
    return mmshbm.default_beam().model(21)


def test_corrector_tangent_is_the_bordered_solve(beam):
    """The tangent the compiled corrector solves at its return is, bit for bit, the bordered
    solve of the continuation (and it is handed out once, for that J and t only)."""
    p = MMSHBMProblem(beam, harmonics=5)
    u = p.linear_mode_point(0.5 * beam.gap)
    t = p.initial_tangent()
    u_new, nit, hist, J = p.fast_newton(u, u, t, 1e-10, 10, 1e-12)
    assert p.solved_tangent(J, t.copy()) is None  # another tangent vector: not this solve
    rhs = np.zeros(len(t))
    rhs[-1] = 1.0
    x_ref, sign_ref = bordered_solve_sign(J, t, rhs)
    x, sign = p.solved_tangent(J, t)
    np.testing.assert_array_equal(x, x_ref)  # one LU kernel (kernels._dense_solve) on one matrix
    assert sign == sign_ref
    assert p.solved_tangent(J, t) is None  # given once
    p.fast_newton(u, u, t, 1e-10, 10, 1e-12)
    t_kernel, s_kernel = _tangent_sign(J, t, p)  # the J of the first run: solved again
    p2 = MMSHBMProblem(beam, harmonics=5)
    _, _, _, J2 = p2.fast_newton(u, u, t, 1e-10, 10, 1e-12)
    t_fresh, s_fresh = _tangent_sign(J2, t, p2)
    np.testing.assert_array_equal(t_kernel, t_fresh)
    assert s_kernel == s_fresh


def test_condensed_stiffness_kept_by_frequency_is_the_computed_one(beam):
    b = mmshbm.backbone(beam, harmonics=5, max_amplitude=3 * beam.gap)
    omegas = 2 * np.pi * b.frequency
    kept = b.solver
    assert len(kept._by_omega) >= len(b) // 2  # the converged points' stiffness was kept
    fresh = MMSHBMProblem(beam, harmonics=5)
    for derivative in (False, True):
        D, dD = kept.condensed_many(omegas, derivative=derivative)
        D_ref, dD_ref = fresh.condensed_many(omegas, derivative=derivative)
        np.testing.assert_array_equal(D, D_ref)  # kept copies of _modal_dynamic_stiffness's output
        if derivative:
            np.testing.assert_array_equal(dD, dD_ref)
    # and the records computed from them: a branch's modal shares, again from scratch
    np.testing.assert_array_equal(b.records["modal_shares"], fresh.branch_records(b.states)["modal_shares"])


def test_problems_share_tables_and_selection_by_value_not_by_object(beam):
    p, q = MMSHBMProblem(beam, harmonics=5), MMSHBMProblem(beam, harmonics=5)
    for name in ("_tau", "_cos_table", "_sin_table", "_tau_fine", "_cos_fine"):
        a, b = getattr(p, name), getattr(q, name)
        assert a is not b and not np.shares_memory(a, b) and a.flags.writeable
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(p._cos_table, np.cos(np.outer(np.arange(11), p._tau)))
    assert p.cond.n_modes == q.cond.n_modes and p.cond.error_estimate == q.cond.error_estimate
    assert p.cond.Rs is not q.cond.Rs
    np.testing.assert_array_equal(p.cond.Rs, q.cond.Rs)
    assert p.cond.error_estimate <= p.cond.tol  # the selection's own bound holds


def test_projections_shared_between_condensations_project_the_recovery(beam):
    """Two condensations of one reduction share a projector's projections; what they give is
    the projector applied to the recovered motion (cosine coefficients of the DOFs with mass)."""
    from mmshbm.harmonic.condense import make_condensation

    c1 = make_condensation(beam, "modal", harmonics=5)
    c2 = make_condensation(beam, "modal", harmonics=5)
    rng = np.random.default_rng(0)
    P = rng.standard_normal((3, len(beam.l)))
    a = rng.standard_normal((6, len(beam.c))) * beam.gap
    omega = 2 * np.pi * 40.0
    first = c1.projected_cosine_recovery(omega, a, P)
    again = c2.projected_cosine_recovery(omega, a, P)
    assert c2._projections[id(P)] is c1._projections[id(P)]
    np.testing.assert_array_equal(first, again)
    Qc = np.zeros((len(beam.c), 11))
    Qc[:, 0], Qc[:, 1::2] = a[0], a[1:].T
    Ql = c2.recover(omega, Qc)
    ref = P @ np.column_stack([Ql[:, 0], Ql[:, 1::2]])
    np.testing.assert_allclose(again, ref, rtol=1e-9, atol=1e-12 * np.abs(ref).max())


def test_monitor_share_records_in_one_call_are_the_separate_calls(beam):
    """The monitor's share records in one compiled call (starting mode's share and family
    records) are, bit for bit, those of the separate calls."""
    b = mmshbm.backbone(beam, harmonics=5, max_amplitude=10 * beam.gap)
    fused, apart = MMSHBMProblem(beam, harmonics=5), MMSHBMProblem(beam, harmonics=5)
    apart._point_records = ()  # the separate calls
    fused._fast_setup()
    apart._fast_setup()
    if not fused._point_records_setup():
        pytest.skip("NUMBA_DISABLE_JIT")
    for u in b.states[::7]:
        one, three = fused.monitor(u), apart.monitor(u)
        assert one.keys() == three.keys()
        np.testing.assert_array_equal(np.array(list(one.values())), np.array(list(three.values())))
    assert np.any(b.contact_force_max > 0) and np.any(np.isfinite(b.records["resonance_detuning"]))


def test_start_mode_projections_kept_per_model_are_the_projections(beam):
    """The starting mode's row of Φᵀ M is one object per (model, H, mode), so its projections
    are built once; they are, bit for bit, the row applied to Z_0, φ_j and Ṽ_i."""
    p, q = MMSHBMProblem(beam, harmonics=5), MMSHBMProblem(beam, harmonics=5)
    if p.cond.backend != "modal":
        pytest.skip("modal back end only")
    row = p._start_row()
    assert q._start_row() is row
    assert np.array_equal(row, p._modal_basis()[2][p.mode - 1:p.mode])
    first = p._share_setup()
    kept = p.cond._projections[id(row)]
    second = q._share_setup()
    assert q.cond._projections[id(row)] is kept  # not built again
    cond = q.cond
    cond._static_recovery()
    np.testing.assert_array_equal(second[1], (row @ cond._Z0)[0])
    np.testing.assert_array_equal(second[2], (row @ cond.phi_j)[0])
    if not cond.complete:
        np.testing.assert_array_equal(second[3], np.array([(row @ V)[0] for V in cond._V[1:]]))
    for x, y in zip(first, second, strict=True):
        np.testing.assert_array_equal(x, y)
    b = mmshbm.backbone(beam, harmonics=5, max_amplitude=3 * beam.gap)
    shares = q._modal_shares_all(b.states)  # projections of Φᵀ M kept: the same as a fresh store's
    MPhiT = q._modal_basis()[2]
    cond._projections.pop(id(MPhiT), None)
    np.testing.assert_array_equal(shares, q._modal_shares_all(b.states))
    assert np.all(shares[:, q.mode - 1, 1] > 0)


@pytest.mark.parametrize("mode", [1, 2])
def test_fixed_numbers_kept_per_model_are_the_computed_ones(beam, mode):
    """A problem whose contact, mode and scaling numbers come from the per-model store has,
    bit for bit, those a problem computes afresh, in arrays of its own."""
    from mmshbm.methods.mms.fixed import _FIXED, _FIXED_CONTACTS, _FIXED_SCALING

    _FIXED.pop(beam, None)
    fresh = MMSHBMProblem(beam, harmonics=5, mode=mode)
    assert (MMSHBMProblem, 5, fresh.N, mode, "auto", "exact", True) in _FIXED[beam]
    kept = MMSHBMProblem(beam, harmonics=5, mode=mode)
    given_r = MMSHBMProblem(beam, harmonics=5, mode=mode, r=fresh.r_each)  # not from the store
    for name in _FIXED_CONTACTS + _FIXED_SCALING + ("n_unknowns", "n_poles", "_pole_w2"):
        a, b = getattr(fresh, name), getattr(kept, name)
        if isinstance(a, np.ndarray):
            assert a.dtype == b.dtype and not np.shares_memory(a, b)
            np.testing.assert_array_equal(a, b)
            np.testing.assert_array_equal(a, getattr(given_r, name))
        else:
            assert type(a) is type(b) and a == b
    u = kept.linear_mode_point(0.5 * beam.gap)
    np.testing.assert_array_equal(u, fresh.linear_mode_point(0.5 * beam.gap))
    np.testing.assert_array_equal(kept.evaluate(u, True)[1], fresh.evaluate(u, True)[1])


@pytest.mark.parametrize("name", ["oscillator", "beam"])
def test_kept_entry_points_are_those_the_arguments_resolve_to(beam, name):
    """The problems built from one set of kept numbers share their kernels' compiled entry
    points; each is the one that describing that problem's own arguments resolves to, and
    the branches they compute are, bit for bit, those of a problem that typed its own."""
    from mmshbm.core._entry import _ENTRIES
    from mmshbm.methods.mms import corrector_kernels as ck
    from mmshbm.methods.mms.fixed import _FIXED

    if not hasattr(ck._newton_modal, "compile"):
        pytest.skip("NUMBA_DISABLE_JIT")
    model = mmshbm.OneDofOscillator(1.0, 1.0, 4.0, 1.0).model() if name == "oscillator" else beam
    H, top = (13, 2.0) if name == "oscillator" else (5, 3.0)
    _FIXED.pop(model, None)
    first = mmshbm.backbone(model, harmonics=H, max_amplitude=top * model.gap)
    assert first.solver._entries is None  # computed its numbers: typed its own arguments
    second = mmshbm.backbone(model, harmonics=H, max_amplitude=top * model.gap)
    p = second.solver
    kept = p._entries
    assert kept is not None and len(kept) == 5
    u = np.ascontiguousarray(second.states[len(second) // 2])
    t = p.initial_tangent()
    hist = np.empty(11)
    fast = p._fast
    newton_args = (u.copy(), u, t, 1e-10, 1e-8, 10, *fast["fixed"], hist, *fast["data"])
    a, omega, eta = p._unpack_all(u)
    a = np.ascontiguousarray(a)
    D, dD = p._condensed(omega, True)
    monitor_args = (D, dD, a, eta, p._pole_k, p._pole_b, p.cdof, p.lo, p.hi, p.r_each, omega,
                    p._amplitude_row(a, omega, eta), p._amp_sign, p._cos_table, p._sin_table,
                    *p._monitor_work)
    D0, B, w2, Rs, keep, static, rtol = fast["cond"]
    stiffness_args = (D0, B, w2, Rs, omega, p.H, keep, rtol, np.empty_like(D), np.empty_like(D), True)
    _, share_args, _, family_args, _ = p._point_records
    from mmshbm.harmonic._modal_kernels import _modal_dynamic_stiffness
    from mmshbm.methods.mms import _family_kernels
    from mmshbm.methods.mms.contact_kernels import _mmshbm_monitor_multi

    calls = {ck._newton_modal: newton_args, _mmshbm_monitor_multi: monitor_args,
             _modal_dynamic_stiffness: stiffness_args,
             ck._start_mode_share: (a, eta, omega, dD, p._pole_k, *share_args),
             _family_kernels._family_records: (a, dD, eta, p._pole_k, omega, *family_args)}
    for dispatcher, args in calls.items():
        assert kept[dispatcher] is _ENTRIES[dispatcher, _type_key(args)]
        assert kept[dispatcher] is compiled_entry(dispatcher, args)
    for attr in ("states", "frequency", "amplitude", "energy", "contact_force_max", "newton_iterations",
                 "step_size"):
        np.testing.assert_array_equal(getattr(second, attr), getattr(first, attr))
    for key, value in first.records.items():
        np.testing.assert_array_equal(second.records[key], value)
    assert second.metadata["checks"] == first.metadata["checks"]


def test_fine_grid_copied_on_first_use_is_the_computed_one(beam):
    """A backbone leaves the fine grid alone; its first use copies the kept table, which is,
    bit for bit, the grid computed afresh (and for tables too large to keep, the problem's
    own computed ones)."""
    from mmshbm.methods.mms.tables import _compute_tables, _tables_kept

    b = mmshbm.backbone(beam, harmonics=5, max_amplitude=3 * beam.gap)
    p = b.solver
    assert p._fine is None
    tau, cos = p._tau_fine, p._cos_fine
    n_fine = max(512, 8 * p.N)
    np.testing.assert_array_equal(tau, 2 * np.pi * np.arange(n_fine) / n_fine)
    np.testing.assert_array_equal(cos, np.cos(np.outer(np.arange(p.H + 1), tau)))
    assert tau.flags.writeable and cos.flags.writeable and p._cos_fine is cos
    q = MMSHBMProblem(beam, harmonics=5)
    assert not np.shares_memory(q._cos_fine, cos)
    u = b.states[len(b) // 2]
    assert p.amplitude_value(u) == q.amplitude_value(u)  # the peak kernel on the copied grid
    np.testing.assert_allclose(p.amplitude_value(u), b.amplitude[len(b) // 2], rtol=1e-12)
    H, N = 200, 4096
    assert not _tables_kept(H, N)
    big = MMSHBMProblem(mmshbm.OneDofOscillator(1.0, 1.0, 4.0, 1.0).model(), harmonics=H, n_samples=N)
    assert big._fine is not None
    for x, y in zip(big._fine, _compute_tables(H, N)[3:], strict=True):
        np.testing.assert_array_equal(x, y)
