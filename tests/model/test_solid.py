"""The 3-D solid beam (scikit-fem hexahedra) against scikit-fem's own assembly and the
Timoshenko beam; large models stay sparse."""

import dataclasses

import numpy as np
import pytest
import scipy.sparse as sp

import mmshbm
from mmshbm.fe.solid import rebuild_solid, solid_beam_matrices
from mmshbm.harmonic.condense import make_condensation
from mmshbm.methods.registry import make_problem
from mmshbm.model.contact import Contact
from mmshbm.model.model import Model


@pytest.fixture(scope="module")
def beam():
    return mmshbm.default_beam()


@pytest.mark.parametrize("order", [1, 2])
def test_box_scaled_assembly_equals_skfem(beam, order):
    M1, K1, loc1, comp1 = solid_beam_matrices(beam, 4, 1, 2, 4.0, order, fast=True)
    M2, K2, loc2, comp2 = solid_beam_matrices(beam, 4, 1, 2, 4.0, order, fast=False)
    assert abs(K1 - K2).max() <= 1e-13 * abs(K2).max()
    assert abs(M1 - M2).max() <= 1e-13 * abs(M2).max()
    np.testing.assert_array_equal(loc1, loc2)
    np.testing.assert_array_equal(comp1, comp2)
    # rigid-body motions: the free-free stiffness has six zero-energy modes
    rigid = np.zeros((K1.shape[0], 6))
    x, y, z = loc1
    for c in range(3):
        rigid[comp1 == c, c] = 1.0
    rigid[comp1 == 0, 3], rigid[comp1 == 1, 3] = -y[comp1 == 0], x[comp1 == 1]
    rigid[comp1 == 1, 4], rigid[comp1 == 2, 4] = -z[comp1 == 1], y[comp1 == 2]
    rigid[comp1 == 2, 5], rigid[comp1 == 0, 5] = -x[comp1 == 2], z[comp1 == 0]
    assert np.abs(K1 @ rigid).max() <= 1e-9 * abs(K1).max()
    mass = beam.rho * beam.length * beam.width * beam.height
    assert rigid[:, 0] @ (M1 @ rigid[:, 0]) == pytest.approx(mass, rel=1e-12)


def test_model_layout(beam):
    """Root face removed, tip face massless, one contact per tip-face node's u_z (same gap,
    side +1), the amplitude DOF on the centre line."""
    n_l, n_w, n_h = 6, 1, 2
    model = beam.solid_model(n_l, n_w, n_h)
    _, _, loc, comp = solid_beam_matrices(beam, n_l, n_w, n_h, 10.0, 2)
    keep = loc[0] > 1e-9
    loc, comp = loc[:, keep], comp[keep]
    tip = np.isclose(loc[0], beam.length)
    assert model.n_dof == keep.sum() and not np.isclose(loc[0], 0.0).any()
    np.testing.assert_array_equal(model.c, np.flatnonzero(tip))
    assert model.n_contacts == (2 * n_w + 1) * (2 * n_h + 1)
    assert {c.gap for c in model.contacts} == {beam.gap} and {c.side for c in model.contacts} == {1}
    dofs = np.array(model.contact_dofs)
    assert np.all(comp[dofs] == 2) and np.all(tip[dofs])
    assert np.allclose(loc[1:, model.amplitude_dof], 0.0)
    assert model.description["kind"] == "SolidBeam"
    assert rebuild_solid(model.description).fingerprint() == model.fingerprint()


def test_first_bending_frequency_against_timoshenko(beam):
    """ν = 0: the converged solid equals Timoshenko theory (κ = 5/6) to 3e-5. ν = 0.3: the
    solid is 0.2-0.3 % stiffer: the clamped root face blocks the Poisson contraction and the
    section bends anticlastically, which 1-D theory with E alone ignores."""
    for nu, lo, hi in ((0.0, -3e-5, 3e-5), (0.3, 1.5e-3, 3.5e-3)):
        b = dataclasses.replace(beam, nu=nu)
        f_timo = b.model(400, grading=1.0, massless_tip=False).linear_frequencies(1)[0]
        f_solid = b.solid_model(40, 2, 2, grading=1.0, massless_tip=False).linear_frequencies(1)[0]
        assert lo <= f_solid / f_timo - 1 <= hi, (nu, f_solid / f_timo - 1)


def test_massless_tip_layer_shifts_little(beam):
    """Dropping the tip face's mass raises f1 by 0.25 % at 40 elements graded 10:1 (the
    1-D beam's massless tip node: 0.85 %; a Q2 face node carries a sixth of its element's
    mass, a beam node half)."""
    massive = beam.solid_model(40, 1, 1, massless_tip=False).linear_frequencies(1)[0]
    massless = beam.solid_model(40, 1, 1).linear_frequencies(1)[0]
    assert 0 < massless / massive - 1 < 4e-3


def test_bad_mesh_options(beam):
    with pytest.raises(ValueError, match="order must be 1 or 2"):
        beam.solid_model(4, order=3)
    with pytest.raises(ValueError, match="n_length must be >= 1"):
        beam.solid_model(0)
    with pytest.raises(ValueError, match="grading must be positive"):
        beam.solid_model(4, grading=-1.0)
    with pytest.raises(TypeError, match="massless_tip must be a bool"):
        beam.solid_model(4, massless_tip="yes")
    with pytest.raises(ValueError, match="not of a SolidBeam"):
        rebuild_solid({"kind": "TimoshenkoBeam"})


def _normalised(branch, model, gaps):
    f0 = model.linear_frequencies(1)[0]
    return np.array([branch.frequency_at(g * model.gap) for g in gaps]) / f0


def test_solid_penalty_backbone_against_timoshenko(beam):
    """Several contacts (the tip face on the plane), penalty HBM on the condensed DOFs: the
    backbone, relative to each model's linear frequency, lies 0.5-0.8 % above the Timoshenko
    beam's: the face held on the plane is a stiffer support than the beam's point contact
    (closed-phase vertical bending 201 against 197 Hz)."""
    gaps = (1.2, 1.5)
    solid, timo = beam.solid_model(8, 1, 1), beam.model(21)
    bs = mmshbm.backbone(solid, harmonics=3, method="penalty-reduced", max_amplitude=1.6e-3)
    bt = mmshbm.backbone(timo, harmonics=3, method="penalty-reduced", max_amplitude=1.6e-3)
    assert bs.status == bt.status == "bound:amplitude"
    ratio = _normalised(bs, solid, gaps) / _normalised(bt, timo, gaps) - 1
    assert np.all((ratio > 0) & (ratio < 1.5e-2)), ratio


def test_solid_mms_hbm_backbone_against_timoshenko(beam):
    """MMS-HBM on the solid (9 contacts under the tip face, modal condensation) against the
    Timoshenko beam at H = 5: relative to each model's linear frequency the solid's backbone
    lies about 1-1.7 % above the beam's (measured +1.65, +0.98, +0.95 % at 1.2, 1.5, 1.8
    gaps; at 2 gaps the beam's H = 5 backbone is inside its 5:1 internal resonance, which
    frequency_at does not report): the tip face held flat on the plane is a stiffer support
    than the beam's point contact (closed-phase vertical bending relative to the open
    frequency 4.38 against 4.31)."""
    gaps = (1.2, 1.5, 1.8)
    solid, timo = beam.solid_model(16, 1, 1), beam.model(21)
    bs = mmshbm.backbone(solid, harmonics=5, max_amplitude=2.1e-3, backend="modal")
    bt = mmshbm.backbone(timo, harmonics=5, max_amplitude=2.1e-3)
    assert bs.status == bt.status == "bound:amplitude"
    assert bs.solver.cond.backend == "modal" and bs.solver.cond.n_modes < 30
    ratio = _normalised(bs, solid, gaps) / _normalised(bt, timo, gaps) - 1
    assert np.all((ratio > 0.5e-2) & (ratio < 2.5e-2)), ratio


def test_large_model_is_never_densified(beam, monkeypatch):
    """Building, validating, the linear modes and the modal condensation of a 3-D model with
    1300 DOFs touch no dense array larger than n_dof x n_contact-DOFs."""
    M, K, loc, comp = solid_beam_matrices(beam, 24, 1, 1, 10.0, 2)
    n = M.shape[0]
    limit = 200 * n
    real_toarray = sp.csr_matrix.toarray

    def guarded(self, *args, **kwargs):
        if self.shape[0] * self.shape[1] > limit:
            raise AssertionError(f"densified a {self.shape} sparse matrix")
        return real_toarray(self, *args, **kwargs)

    for cls in (sp.csr_matrix, sp.csc_matrix, sp.coo_matrix):
        monkeypatch.setattr(cls, "toarray", guarded)
    monkeypatch.setattr(sp.csr_matrix, "todense", lambda self, *a, **k: pytest.fail("todense"))
    model = beam.solid_model(24, 1, 1)
    assert len(model.l) > 600  # past every dense-solver limit
    assert 45.0 < model.linear_frequencies(1)[0] < 46.0
    cond = make_condensation(model, "modal", harmonics=3)
    assert cond.reduction.solver == "arpack"
    assert np.all(np.isfinite(cond.dynamic_stiffness(2 * np.pi * 50, 3, False)))
    closed = Model(model.M, model.K, (Contact(model.contact_dofs[0], 0.0, 1),))
    assert closed.zero_gap_frequency() > 45.0
    problem = make_problem(model, "mmshbm", harmonics=3, backend="modal")  # its pole range: held frequency
    low, high = problem._omega_range()
    assert high >= low > 0


def test_held_frequency_sparse_equals_dense(beam, monkeypatch):
    """MMS-HBM's upper frequency (every contact DOF held) by the sparse path equals the dense one."""
    import mmshbm.model.linear_modes as mm
    from mmshbm.methods.mms.held import _held_frequency_solve

    model = beam.solid_model(24, 1, 1)
    sparse = _held_frequency_solve(model, model.contact_dofs, 1)
    monkeypatch.setattr(mm, "_DENSE_EIG_LIMIT", 10**6)
    dense = _held_frequency_solve(model, model.contact_dofs, 1)
    assert sparse == pytest.approx(dense, rel=1e-7)
