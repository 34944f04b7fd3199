"""Modal condensation (backend="modal") against the banded LU, closed forms, finite
differences and its own truncation bound; the reduction's cache; bad input."""

import warnings

import numpy as np
import pytest
from finite_differences import assert_derivative

import mmshbm
import mmshbm.harmonic.modal_reduction as mr
from mmshbm.harmonic.condense import (
    MODAL_CROSSOVER,
    Condensation,
    SingularDynamicStiffness,
    make_condensation,
)
from mmshbm.harmonic.modal import ModalCondensation
from mmshbm.harmonic.modal_reduction import ModalReduction, structure_key

OMEGAS = 2 * np.pi * np.array([0.0, 45.0, 120.0, 300.0])


@pytest.fixture(scope="module")
def complete21(beam21):
    return ModalCondensation(beam21, n_modes="all")


@pytest.fixture(scope="module")
def banded21(beam21):
    return Condensation(beam21, "banded")


def _fresh(model, **options):
    """A modal condensation that computes its reduction anew (memory cache emptied)."""
    mr._MEMORY.pop(model, None)
    return ModalCondensation(model, **options)


def test_all_modes_equal_the_banded_backend(complete21, banded21):
    """With every mode the modal sum is exact: the banded LU's D_k and ∂D_k/∂Ω to 1e-10."""
    assert complete21.complete and complete21.n_modes == complete21.n_l == 40
    for omega in OMEGAS:
        D, dD = complete21.dynamic_stiffness(omega, 5)
        D_ref, dD_ref = banded21.dynamic_stiffness(omega, 5)
        for k in range(6):
            assert np.abs(D[k] - D_ref[k]).max() <= 1e-10 * np.abs(D_ref[k]).max()
            assert np.abs(dD[k] - dD_ref[k]).max() <= 1e-10 * max(np.abs(dD_ref[k]).max(), 1e-300)
            np.testing.assert_array_equal(D[k], D[k].T)  # the kernel mirrors its upper triangle


def test_one_dof_closed_form():
    """D_k = k2 − k2²/(k1 + k2 − (kΩ)² m): one mode, exact."""
    m, k1, k2 = 2.0, 3.0, 5.0
    cond = make_condensation(mmshbm.OneDofOscillator(m, k1, k2, 0.1).model(), "modal", harmonics=4)
    omega = 0.9
    D, dD = cond.dynamic_stiffness(omega, 4)
    for k in range(5):
        s = k1 + k2 - (k * omega) ** 2 * m
        assert D[k, 0, 0] == pytest.approx(k2 - k2**2 / s, rel=1e-13)
        assert dD[k, 0, 0] == pytest.approx(-(k2**2) * 2 * k**2 * omega * m / s**2, rel=1e-12, abs=1e-14)


@pytest.mark.parametrize("options", [{"n_modes": "all"}, {}, {"cutoff": 3000.0, "residual_terms": 3}])
def test_derivative_is_the_finite_difference(beam21, options):
    """∂D_k/∂Ω = −Σ_j b_j b_jᵀ 2k²Ω/(ω_j² − (kΩ)²)² (+ the residual terms' derivative)."""
    cond = ModalCondensation(beam21, **options)
    for omega in 2 * np.pi * np.array([50.0, 130.0]):
        _, dD = cond.dynamic_stiffness(omega, 5)
        for k in range(1, 6):
            assert_derivative(lambda s, k=k, w=omega: cond.dynamic_stiffness(w + s, 5, False)[k], dD[k],
                              1e-4 * omega, name=f"harmonic {k}")


@pytest.mark.parametrize("n_modes", [3, 6, 10])
@pytest.mark.parametrize("terms", [1, 3, 5])
def test_truncation_error_is_within_its_bound(beam21, complete21, n_modes, terms):
    """‖D_k^m − D_k‖₂ <= ω^{2P+2}/(ω_{m+1}² − ω²) ‖R(P+1)‖₂ (reported relative to ‖D_0‖₂),
    and the bound is not vacuous: within a factor 100 of the error at 300 Hz."""
    cond = ModalCondensation(beam21, n_modes=n_modes, residual_terms=terms)
    norm0 = np.linalg.norm(cond.D0, 2)
    for omega in OMEGAS[1:]:
        D = cond.dynamic_stiffness(omega, 5, False)
        D_ref = complete21.dynamic_stiffness(omega, 5, False)
        bound = cond.truncation_error(omega, 5)
        for k in range(1, 6):
            if not np.isfinite(bound[k]):
                assert k * omega >= cond.omega_j[-1]
                continue
            err = np.linalg.norm(D[k] - D_ref[k], 2) / norm0
            assert err <= bound[k] * (1 + 1e-6) + 1e-12
    omega = 2 * np.pi * 300.0
    diff = cond.dynamic_stiffness(omega, 1, False)[1] - complete21.dynamic_stiffness(omega, 1, False)[1]
    err = np.linalg.norm(diff, 2) / norm0
    assert err > 1e-2 * cond.truncation_error(omega, 1)[1] or err < 1e-13


def test_higher_residual_terms_need_fewer_modes(beam21):
    """The default (P = 5) meets 1e-10 at H = 5 over the first fixed-interface frequency
    with far fewer modes than the residual inertia alone (P = 1)."""
    p5 = ModalCondensation(beam21, harmonics=5)
    p1 = ModalCondensation(beam21, harmonics=5, residual_terms=1)
    assert p5.error_estimate <= 1e-10 and p1.error_estimate <= 1e-10
    assert p5.n_modes <= 12 < p1.n_modes
    assert p5.design_frequency == pytest.approx(5 * p5.omega_j[0] / (2 * np.pi))


def test_sparse_eigensolver_path_matches_the_dense_one(beam21, complete21):
    """ARPACK shift-invert with deflated Krylov moments (dense_limit=0) on the same beam."""
    cond = _fresh(beam21, dense_limit=0)
    assert cond.reduction.solver == "arpack" and not cond.complete
    np.testing.assert_allclose(cond.omega_j, complete21.omega_j[: cond.n_modes], rtol=1e-11)
    norm0 = np.linalg.norm(cond.D0, 2)
    for omega in OMEGAS:
        D = cond.dynamic_stiffness(omega, 5, False)
        D_ref = complete21.dynamic_stiffness(omega, 5, False)
        bound = cond.truncation_error(omega, 5)
        size = np.linalg.norm(D_ref, 2, axis=(1, 2))  # round-off grows with D_k near a pole
        assert np.all(np.linalg.norm(D - D_ref, 2, axis=(1, 2)) <= bound * norm0 + 1e-10 * size)
    mr._MEMORY.pop(beam21, None)


def test_large_beam_is_independent_of_its_size():
    """1000 elements: ARPACK, the same ~11 modes as 21 elements, D against the banded LU to
    2e-9 (the modes left out) plus the banded LU's own round-off. D = K_cc − K_cl S⁻¹ K_lc
    cancels terms far larger than itself (S of 2000 DOFs), so that round-off is well above
    ε|D| and depends on the LAPACK kernel: measured as the asymmetry of the banded D (exact D
    is symmetric, the modal one is by construction), four times its largest."""
    model = mmshbm.default_beam().model(1000)
    cond = make_condensation(model, "modal")
    assert cond.reduction.solver == "arpack" and cond.n_modes <= 12
    band = Condensation(model, "banded")
    for omega in OMEGAS:
        D, D_ref = cond.dynamic_stiffness(omega, 5, False), band.dynamic_stiffness(omega, 5, False)
        noise = np.abs(D_ref - D_ref.transpose(0, 2, 1)).max()
        assert noise <= 1e-6 * np.abs(D_ref).max()  # round-off, not a wrong reference
        assert np.abs(D - D_ref).max() <= 2e-9 * np.abs(D_ref).max() + 4 * noise


def test_pole_raises_and_excluding_its_term_regularises():
    """kΩ on ω_j: SingularDynamicStiffness; with (k, j) excluded D_k is the regular part,
    and away from the pole D_k a = D_k^reg a − b_j η (kΩ)²/ω_j², η = b_jᵀa/(ω_j² − (kΩ)²)."""
    model = mmshbm.OneDofOscillator(1.0, 1.0, 3.0, 0.1).model()
    cond = make_condensation(model, "modal")
    pole = cond.omega_j[0]
    with pytest.raises(SingularDynamicStiffness, match="singular"):
        cond.dynamic_stiffness(pole / 2, 2)
    D, dD = cond.dynamic_stiffness(pole / 2, 2, exclude=[(2, 0)])
    assert D[2, 0, 0] == pytest.approx(cond.D0[0, 0]) and dD[2, 0, 0] == 0.0
    assert cond.poles_near(pole / 2 * 1.01, 3) == [(2, 0)]


def test_regular_part_identity(complete21):
    rng = np.random.default_rng(3)
    a = rng.normal(size=complete21.n_c)
    omega, k, j = 2 * np.pi * 57.0, 5, 0  # 5Ω near the first fixed-interface mode (285.7 Hz)
    assert (k, j) in complete21.poles_near(omega, 5, window=0.01)
    D, dD = complete21.dynamic_stiffness(omega, 5)
    Dr, dDr = complete21.dynamic_stiffness(omega, 5, exclude=[(k, j)])
    b, w2, x = complete21.b_j[j], complete21.omega_j[j] ** 2, (k * omega) ** 2
    eta = b @ a / (w2 - x)
    np.testing.assert_allclose(D[k] @ a, Dr[k] @ a - b * eta * x / w2, rtol=1e-9,
                               atol=1e-9 * np.abs(D[k] @ a).max())
    deta = b @ a * 2 * k * k * omega / (w2 - x) ** 2  # ∂η/∂Ω
    np.testing.assert_allclose(dD[k] @ a, dDr[k] @ a - b * (deta * x + eta * 2 * k * k * omega) / w2,
                               rtol=1e-8)
    np.testing.assert_array_equal(D[:k], Dr[:k])  # each harmonic its own loop: those below k untouched
    # the exposed modes: M-orthonormal, b_j = K_cl φ_j
    model = mmshbm.default_beam().model(21)
    M = model.blocks["M_ll"]
    phi = complete21.phi_j
    np.testing.assert_allclose(phi.T @ (M @ phi), np.eye(phi.shape[1]), atol=1e-9)
    np.testing.assert_allclose(complete21.b_j, phi.T @ model.blocks["K_lc"], rtol=1e-12)


@pytest.mark.parametrize("options", [{"n_modes": "all"}, {}])
def test_recover_satisfies_the_linear_equations(beam21, options):
    cond = ModalCondensation(beam21, **options)
    omega, H = 2 * np.pi * 50.0, 3
    Qc = np.random.default_rng(1).normal(size=(cond.n_c, 2 * H + 1))
    Ql = cond.recover(omega, Qc)
    b = beam21.blocks
    for col in range(2 * H + 1):
        k = (col + 1) // 2
        res = (b["K_ll"] - (k * omega) ** 2 * b["M_ll"]) @ Ql[:, col] + b["K_lc"] @ Qc[:, col]
        assert np.abs(res).max() < 1e-8 * np.abs(b["K_lc"] @ Qc[:, col]).max()


def test_recover_reuses_its_factors_only_for_the_same_call_inputs(beam21):
    """recover keeps the factors of its last (Ω, H, exclusions): any sequence of calls
    gives what a fresh condensation gives for each call alone, bit for bit."""
    rng = np.random.default_rng(4)
    calls = [(2 * np.pi * 50.0, 3, ()), (2 * np.pi * 50.0, 3, ()), (2 * np.pi * 50.0, 3, [(2, 0)]),
             (2 * np.pi * 50.0, 5, [(2, 0)]), (2 * np.pi * 61.0, 5, [(2, 0)]), (2 * np.pi * 50.0, 3, ())]
    cond = ModalCondensation(beam21)
    for omega, H, exclude in calls:
        Qc = rng.normal(size=(cond.n_c, 2 * H + 1))
        alone = ModalCondensation(beam21).recover(omega, Qc, exclude=exclude)
        assert np.array_equal(cond.recover(omega, Qc, exclude=exclude), alone)
    with pytest.raises(SingularDynamicStiffness):  # a pole met after a cached call still raises
        cond.recover(cond.omega_j[0], rng.normal(size=(cond.n_c, 3)))


def test_reduction_cache_on_disk(tmp_path, beam21, monkeypatch):
    """Saved once, loaded by the next run (nothing recomputed), shared across gaps, refused
    for another structure."""
    mr._MEMORY.pop(beam21, None)
    first = ModalCondensation(beam21, cache=tmp_path)
    files = list(tmp_path.glob("modal-*.npz"))
    assert len(files) == 1

    def no_compute(*args, **kwargs):
        raise AssertionError("recomputed a cached reduction")

    monkeypatch.setattr(mr, "_dense_reduction", no_compute)
    other_gap = beam21.with_gap(2e-3)  # another model object, same structure
    second = ModalCondensation(other_gap, cache=tmp_path)
    assert structure_key(other_gap) == structure_key(beam21) != beam21.fingerprint()
    for omega in OMEGAS:
        np.testing.assert_array_equal(first.dynamic_stiffness(omega, 5, False),
                                      second.dynamic_stiffness(omega, 5, False))
    red = ModalReduction.load(files[0], beam21)
    with pytest.raises(ValueError, match="another structure"):
        ModalReduction.load(files[0], mmshbm.default_beam().model(8))
    with pytest.raises(ValueError, match="too few"):
        ModalCondensation(mmshbm.default_beam().model(21), reduction=_truncated(red, 3))
    bad = tmp_path / "bad.npz"
    np.savez(bad, x=np.zeros(2))
    with pytest.raises(ValueError, match="not a modal reduction"):
        ModalReduction.load(bad)
    mr._MEMORY.pop(beam21, None)


def _truncated(red, k):
    import dataclasses

    return dataclasses.replace(red, omega=red.omega[:k], phi=red.phi[:, :k], B=red.B[:k], complete=False)


def test_factory_dispatch(beam21):
    assert make_condensation(beam21, "banded").backend == "banded"
    assert make_condensation(beam21, "modal").backend == "modal"
    assert MODAL_CROSSOVER == 1  # "auto" is modal for every model with a DOF with mass
    assert make_condensation(mmshbm.default_beam().model(3)).backend == "modal"
    assert make_condensation(mmshbm.OneDofOscillator(1.0, 1.0, 4.0, 1.0).model()).backend == "modal"
    with pytest.raises(ValueError, match="backend must be one of"):
        make_condensation(beam21, "dense")
    with pytest.raises(TypeError, match="apply to backend='modal' only"):
        make_condensation(beam21, "banded", tol=1e-6)


@pytest.mark.parametrize("options, match", [
    ({"cutoff": 0.0}, "cutoff must be a frequency > 0"),
    ({"cutoff": -5.0}, "cutoff must be a frequency > 0"),
    ({"cutoff": 1e3, "n_modes": 3}, "n_modes or cutoff, not both"),
    ({"n_modes": "some"}, "n_modes must be a positive integer or 'all'"),
    ({"n_modes": 0}, "n_modes must be >= 1"),
    ({"tol": 0.0}, "tol must be positive"),
    ({"residual_terms": 6}, r"residual_terms must be in \[1, 5\]"),
    ({"max_frequency": -1.0}, "max_frequency must be positive"),
    ({"harmonics": 0}, "harmonics must be >= 1"),
])
def test_bad_options_are_named(beam21, options, match):
    with pytest.raises(ValueError, match=match):
        ModalCondensation(beam21, **options)


def test_eigensolver_that_does_not_converge_is_a_value_error(beam21, monkeypatch):
    """ARPACK's ArpackNoConvergence (shift-invert converges on the beams within one restart,
    so it is provoked) becomes a ValueError naming the eigen-solver and its limit."""

    def no_convergence(A, k, **kwargs):
        raise mr.spla.ArpackNoConvergence("no", np.ones(2), np.ones((A.shape[0], 2)))

    monkeypatch.setattr(mr.spla, "eigsh", no_convergence)
    with pytest.raises(ValueError, match=r"eigen-solver \(ARPACK.*did not converge: 2 of 16 .*maxiter=7"):
        _fresh(beam21, dense_limit=0, maxiter=7)
    mr._MEMORY.pop(beam21, None)


def test_too_many_modes_needed_is_a_value_error(beam21):
    with pytest.raises(ValueError, match="max_modes=4 stops here"):
        _fresh(beam21, dense_limit=0, max_modes=4)
    mr._MEMORY.pop(beam21, None)


def test_bad_calls(complete21):
    with pytest.raises(ValueError, match="out of range"):
        complete21.dynamic_stiffness(1.0, 3, exclude=[(4, 0)])
    with pytest.raises(TypeError, match="pairs of integers"):
        complete21.dynamic_stiffness(1.0, 3, exclude=[(1.5, 0)])
    with pytest.raises(ValueError, match="omega must be finite"):
        complete21.dynamic_stiffness(np.nan, 3)
    with pytest.raises(ValueError, match="Qc must have shape"):
        complete21.recover(1.0, np.zeros((3, 5)))
    no_massless = mmshbm.Model.from_matrices(np.eye(2), 2 * np.eye(2), 0, 0.1)
    with pytest.raises(ValueError, match="no massless DOF"):
        ModalCondensation(no_massless)


def test_leaving_the_design_range_warns(beam21):
    cond = ModalCondensation(beam21, n_modes=2)
    assert cond.check_range(0.5 * cond.cutoff * 2 * np.pi, 1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cond.dynamic_stiffness(cond.cutoff * 2 * np.pi, 1)  # Newton iterates may wander: no check
    with pytest.warns(mmshbm.ModelWarning, match="leaves out"):
        assert not cond.check_range(cond.cutoff * 2 * np.pi, 1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cond.check_range(cond.cutoff * 2 * np.pi, 1)  # once per condensation


def test_mms_hbm_backbone_with_the_modal_backend():
    """8 elements, H = 5, to 2 gaps: the same branch as the banded LU, point for point."""
    model = mmshbm.default_beam().model(8)
    a = mmshbm.backbone(model, harmonics=5, max_amplitude=2e-3, backend="banded")
    b = mmshbm.backbone(model, harmonics=5, max_amplitude=2e-3, backend="modal")
    assert b.solver.cond.backend == "modal" and len(a) == len(b)
    np.testing.assert_allclose(b.frequency, a.frequency, rtol=1e-9)
    np.testing.assert_allclose(b.energy, a.energy, rtol=1e-8)
