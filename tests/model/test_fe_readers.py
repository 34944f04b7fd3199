"""mmshbm.read_fe: the cantilever of tests/data/fe/ in every format, the import checks, the
DOF table, FEMatrices.model (contacts and friction by node, the massless layer), large
exports without densifying, and the optional readers (skipped where not installed)."""

import importlib.util
import subprocess
import sys

import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp
from locations import DATA as TEST_DATA

import mmshbm
from mmshbm.model.readers import FEMatrices, ReadError, read_fe

DATA = TEST_DATA / "fe"
sys.path.insert(0, str(DATA))
import make_fixtures  # noqa: E402

L, B, H, E, RHO = 0.5, 0.020, 0.0135, 210e9, 7850.0
I_AREA, AREA = B * H**3 / 12, B * H
TIP = make_fixtures.TIP_NODE

#: files of the cantilever -> digits they keep (17: exact doubles; the DMIG large field 10)
EXPORTS = {
    "abaqus": (["beam_MASS1.mtx", "beam_STIF1.mtx"], 17),
    "abaqus-user": (["beam_substructure.inp"], 17),
    "op4-text-dense": (["beam.op4"], 17),
    "op4-text-sparse": (["beam_sparse.op4"], 17),
    "op4-binary-dense": (["beam_binary.op4"], 17),
    "op4-binary-bigmat": (["beam_bigmat.op4"], 17),
    "dmig": (["beam.pch"], 10),
    "matrix-market": (["beam_M.mtx", "beam_K.mtx"], 17),
    "harwell-boeing": (["beam_M.rua", "beam_K.rua"], 17),
    "matlab-v5": (["beam.mat"], 17),
    "matlab-v73": (["beam_v73.mat"], 17),
    "code-aster": (["beam_aster.npz"], 17),
    "npz": (["beam.npz"], 17),
}
NEEDS = {"matlab-v73": "h5py"}


def _read(name):
    files, _ = EXPORTS[name]
    if name in NEEDS and importlib.util.find_spec(NEEDS[name]) is None:
        pytest.skip(f"{NEEDS[name]} is not installed (pip install 'mmshbm[fe]')")
    return read_fe(*(DATA / f for f in files))


@pytest.fixture(scope="module")
def reference():
    return make_fixtures.cantilever()


@pytest.mark.parametrize("name", sorted(EXPORTS))
def test_every_format_holds_the_generators_cantilever(name, reference):
    fe = _read(name)
    M, K = reference
    assert fe.n_dof == 20
    digits = EXPORTS[name][1]
    # written with `digits` significant digits: each entry within half a unit of the last one
    rtol = 0.5 * 10.0 ** (1 - digits) if digits < 17 else 2e-16
    for got, want in ((fe.M, M), (fe.K, K)):
        assert abs(got.toarray() - want).max() <= rtol * abs(want).max() * 1.01
    if fe.dofs[:, 1].any():  # formats with a DOF table: nodes 2..11, u_y and r_z
        assert fe.dofs.tolist() == make_fixtures.DOFS.tolist()
        assert fe.index(TIP, 2) == 18 and fe.index(TIP, 6) == 19
    else:
        assert fe.dofs.tolist() == [[i, 0] for i in range(20)]


@pytest.mark.parametrize("name", sorted(set(EXPORTS) - {"abaqus"}))
def test_every_format_gives_the_same_frequencies(name):
    f_ref = _read("abaqus").frequencies(5)
    f = _read(name).frequencies(5)
    # exact doubles: the same matrices (round-off of one eigen-solve); DMIG's 10 digits perturb
    # each entry by <= 5e-10 relative, and the eigenvalues by as much
    tol = 1e-12 if EXPORTS[name][1] == 17 else 1e-9
    np.testing.assert_allclose(f, f_ref, rtol=tol)


def test_the_cantilever_is_the_euler_bernoulli_beam():
    """Independent of every reader: the closed-form cantilever frequency (β₁L = 1.8751...,
    Hermite-cubic FE frequencies are upper bounds within 1e-6 on 10 elements) and the static
    tip stiffness 3EI/L³ (exact for cubic elements)."""
    fe = _read("abaqus")
    f1 = 1.875104068711961**2 / (2 * np.pi) * np.sqrt(E * I_AREA / (RHO * AREA * L**4))
    assert 0 < fe.frequencies(1)[0] / f1 - 1 < 2e-6
    k_s = fe.static_stiffness([fe.index(TIP, 2)])[0]
    assert k_s == pytest.approx(3 * E * I_AREA / L**3, rel=1e-11)


def test_triangles_lower_upper_and_full_read_alike(tmp_path, reference):
    M, K = reference
    dofs = make_fixtures.DOFS
    want = read_fe(DATA / "beam_MASS1.mtx", DATA / "beam_STIF1.mtx").frequencies(3)
    for name, keep in (("upper", lambda i, j: i <= j), ("full", lambda i, j: True)):
        for role, A in (("MASS", M), ("STIF", K)):
            lines = [f"{dofs[i, 0]}, {dofs[i, 1]}, {dofs[j, 0]}, {dofs[j, 1]}, {float(A[i, j])!r}\n"
                     for i in range(20) for j in range(20) if A[i, j] != 0 and keep(i, j)]
            (tmp_path / f"{name}_{role}1.mtx").write_text("".join(lines))
        # the stiffness file first: roles come from the names
        fe = read_fe(tmp_path / f"{name}_STIF1.mtx", tmp_path / f"{name}_MASS1.mtx")
        np.testing.assert_allclose(fe.frequencies(3), want, rtol=1e-12)


def test_a_non_symmetric_entry_is_named(tmp_path, reference):
    M, K = reference
    dofs = make_fixtures.DOFS
    bad = K.copy()
    bad[5, 2] *= 1.01  # node 4's r_z against node 3's u_y, in one triangle only
    lines = [f"{dofs[i, 0]}, {dofs[i, 1]}, {dofs[j, 0]}, {dofs[j, 1]}, {float(bad[i, j])!r}\n"
             for i in range(20) for j in range(20) if bad[i, j] != 0]
    (tmp_path / "job_STIF1.mtx").write_text("".join(lines))
    with pytest.raises(ReadError, match=r"job_STIF1.mtx: K is not symmetric: the entry at \(node 3 component "
                                        r"2; node 4 component 6\)"):
        read_fe(DATA / "beam_MASS1.mtx", tmp_path / "job_STIF1.mtx")


def test_mismatched_dof_counts_name_both_files(tmp_path, reference):
    M, K = reference
    scipy.io.mmwrite(str(tmp_path / "M.mtx"), sp.coo_matrix(M[:18, :18]))
    scipy.io.mmwrite(str(tmp_path / "K.mtx"), sp.coo_matrix(K))
    with pytest.raises(ReadError, match=r"different numbers of DOFs .*M.mtx': 18, .*K.mtx': 20"):
        read_fe(tmp_path / "M.mtx", tmp_path / "K.mtx")


def test_constrained_dofs_as_zero_rows_are_removed(tmp_path):
    Mf, Kf = make_fixtures.full_cantilever()  # root node's DOFs 0, 1 not yet fixed
    Kz, Mz = Kf.copy(), Mf.copy()
    Kz[:2, :], Kz[:, :2], Mz[:2, :], Mz[:, :2] = 0, 0, 0, 0  # as ANSYS writes fixed DOFs
    scipy.io.mmwrite(str(tmp_path / "mass.mtx"), sp.coo_matrix(Mz), symmetry="symmetric")
    scipy.io.mmwrite(str(tmp_path / "stiffness.mtx"), sp.coo_matrix(Kz), symmetry="symmetric")
    fe = read_fe(tmp_path / "stiffness.mtx", tmp_path / "mass.mtx")
    assert fe.n_dof == 20 and fe.removed.tolist() == [[0, 0], [1, 0]]
    np.testing.assert_allclose(fe.frequencies(3), _read("abaqus").frequencies(3), rtol=1e-12)
    with pytest.raises(ValueError, match="removed as constrained"):
        fe.index(0, 0)


def test_a_free_structure_or_swapped_files_are_refused(tmp_path, reference):
    Mf, Kf = make_fixtures.full_cantilever()  # nothing fixed: K is singular
    scipy.io.mmwrite(str(tmp_path / "M.mtx"), sp.coo_matrix(Mf))
    scipy.io.mmwrite(str(tmp_path / "K.mtx"), sp.coo_matrix(Kf))
    with pytest.raises(ReadError, match=r"K.mtx: K is singular.*after removing the constrained DOFs"):
        read_fe(tmp_path / "M.mtx", tmp_path / "K.mtx")
    M, K = reference
    Kz = K.copy()
    Kz[0, :], Kz[:, 0] = 0, 0  # a DOF with mass and no stiffness
    scipy.io.mmwrite(str(tmp_path / "K.mtx"), sp.coo_matrix(Kz))
    scipy.io.mmwrite(str(tmp_path / "M.mtx"), sp.coo_matrix(M))
    with pytest.raises(ReadError, match="row 0 has mass but no stiffness"):
        read_fe(tmp_path / "M.mtx", tmp_path / "K.mtx")


def test_bad_files_get_one_line_errors(tmp_path):
    bad = tmp_path / "job_STIF1.mtx"
    bad.write_text("1, 2, 1, 2, 3.0\n1, 2, x, 2, 1.0\n")
    with pytest.raises(ReadError, match=r"job_STIF1.mtx, line 2: not four integers and a number"):
        read_fe(DATA / "beam_MASS1.mtx", bad)
    with pytest.raises(ReadError, match="no stiffness matrix K"):
        read_fe(DATA / "beam_MASS1.mtx")
    with pytest.raises(FileNotFoundError, match="no such file"):
        read_fe(tmp_path / "missing.op4")
    (tmp_path / "notes.txt").write_text("hello\n")
    with pytest.raises(ReadError, match="cannot tell the format .* give format="):
        read_fe(tmp_path / "notes.txt")
    with pytest.raises(ValueError, match="format must be one of"):
        read_fe(DATA / "beam.op4", format="nastran")
    with pytest.raises(ReadError, match="different formats"):
        read_fe(DATA / "beam_M.mtx", DATA / "beam_STIF1.mtx")
    truncated = tmp_path / "cut.op4"
    truncated.write_text("".join((DATA / "beam.op4").read_text().splitlines(keepends=True)[:30]))
    with pytest.raises(ReadError, match="matrix KAA ends before its closing column 21"):
        read_fe(truncated)


def test_code_aster_lagrange_rows_and_relations(tmp_path):
    fe = _read("code-aster")
    assert fe.removed.tolist() == [[1, 2], [1, 6]]  # the root node, fixed by DDL_IMPO
    data = dict(np.load(DATA / "beam_aster.npz"))
    rows, cols = data["K_rows"], data["K_cols"]
    # make the first multiplier tie the root's u_y to a second DOF: a LIAISON relation
    lag = int(np.flatnonzero(np.char.startswith(data["components"], "LAGR"))[0])
    data["K_rows"], data["K_cols"] = np.append(rows, 5), np.append(cols, lag)
    data["K_data"] = np.append(data["K_data"], 1.0)
    np.savez(tmp_path / "relation.npz", **data)
    with pytest.raises(ReadError, match="ties several DOFs"):
        read_fe(tmp_path / "relation.npz")


def test_op4_files_agree_with_pynastran():
    """pyNastran's own OP4 reader (an independent implementation) reads the fixtures alike."""
    pytest.importorskip("pyNastran.op4.op4", reason="pyNastran is not installed (pip install 'mmshbm[op2]')")
    from pyNastran.op4.op4 import read_op4

    from mmshbm.model.readers.op4 import read_matrices

    for name in ("beam.op4", "beam_sparse.op4"):
        theirs = read_op4(str(DATA / name), debug=False)
        ours = read_matrices(DATA / name)
        for key in ("KAA", "MAA"):
            A = theirs[key].data if hasattr(theirs[key], "data") else theirs[key][1]
            A = A.toarray() if sp.issparse(A) else np.asarray(A)
            np.testing.assert_array_equal(ours[key].toarray(), A)


def test_ansys_example_full_file():
    """ansys-mapdl-reader's shipped example: 1283.2, 1283.2, 5782.0 Hz once the zero rows
    (constrained DOFs) are removed and the upper triangles completed."""
    pytest.importorskip("ansys.mapdl.reader", reason="ansys-mapdl-reader is not installed "
                                                     "(pip install 'mmshbm[fe]')")
    from ansys.mapdl.reader import examples

    fe = read_fe(examples.fullfile)
    assert fe.format == "ansys" and set(fe.dofs[:, 1]) <= {1, 2, 3}
    np.testing.assert_allclose(fe.frequencies(3), [1283.2, 1283.2, 5782.0], rtol=1e-4)
    assert len(fe.removed) > 0 and fe.n_dof + len(fe.removed) == 963


def test_heavy_readers_are_refused_by_name(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "ansys", None)
    monkeypatch.setitem(sys.modules, "ansys.mapdl", None)
    (tmp_path / "file.full").write_bytes(b"\0" * 64)
    with pytest.raises(ImportError, match=r"ANSYS \.full files needs ansys-mapdl-reader: pip install "
                                          r"'mmshbm\[fe\]'"):
        read_fe(tmp_path / "file.full")
    monkeypatch.setitem(sys.modules, "pyNastran", None)
    monkeypatch.setitem(sys.modules, "pyNastran.op2", None)
    monkeypatch.setitem(sys.modules, "pyNastran.op2.op2", None)
    (tmp_path / "beam.op2").write_bytes(b"\0" * 64)
    with pytest.raises(ImportError, match=r"\.op2 files needs pyNastran: pip install 'mmshbm\[op2\]'"):
        read_fe(tmp_path / "beam.op2")
    monkeypatch.setitem(sys.modules, "h5py", None)
    with pytest.raises(ImportError, match=r"v7.3 .* needs h5py: pip install 'mmshbm\[fe\]'"):
        read_fe(DATA / "beam_v73.mat")


def test_import_mmshbm_imports_no_reader():
    code = ("import sys, mmshbm; mmshbm.read_fe; "
            "print(sorted(m for m in ('h5py', 'ansys', 'pyNastran', 'pyvista') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
    assert "read_fe" in mmshbm.__all__ and "FEMatrices" in mmshbm.__all__
    assert mmshbm.FEMatrices is FEMatrices


def test_model_inserts_a_stated_layer_where_the_dof_carries_mass():
    fe = _read("abaqus")
    model = fe.model(contact=[(TIP, 2, 1e-3, 1)])
    layer = model.description["contact_layer"]
    k_s = 3 * E * I_AREA / L**3
    assert layer["attached_to"] == [[TIP, 2]] and layer["nodes"] == [20]
    assert layer["stiffness"][0] == pytest.approx(1e5 * k_s, rel=1e-11)
    assert model.contact_dof == 20 and model.c.tolist() == [20] and model.amplitude_dof == fe.index(TIP, 2)
    # the layer is unloaded while the contact is open: the frequencies are the structure's, up to
    # the round-off of condensing the stiff spring, a few eps x k / k_s
    np.testing.assert_allclose(model.linear_frequencies(3), fe.frequencies(3), rtol=10 * 2.2e-16 * 1e5)
    stiff = fe.model(contact=[(TIP, 2, 1e-3)], layer_stiffness={(TIP, 2): 3e6})
    assert stiff.description["contact_layer"]["stiffness"] == [3e6]
    assert stiff.K[20, 20] == 3e6 and stiff.K[18, 20] == -3e6


def test_model_friction_and_errors():
    fe = _read("abaqus")
    model = fe.model(contact=[(TIP, 2, 1e-3, 1)], friction=[(TIP - 1, 2, 0.3, 10.0)])
    assert [f.dof for f in model.friction] == [20]  # the slider node joined to node 10's u_y
    assert model.contact_dof == 21 and sorted(model.c.tolist()) == [20, 21]
    with pytest.raises(ValueError, match=r"no DOF \(node 12, component 2\) .* nodes 2-11"):
        fe.model(contact=[(12, 2, 1e-3, 1)])
    with pytest.raises(ValueError, match=r"node 11 has no component 3 \(it has \[2, 6\]\)"):
        fe.model(contact=[(11, 3, 1e-3, 1)])
    with pytest.raises(ValueError, match=r"contact\[0\] side must be \+1 or -1"):
        fe.model(contact=[(11, 2, 1e-3, 2)])
    with pytest.raises(ValueError, match="at least one contact"):
        fe.model()
    with pytest.raises(ValueError, match="layer_stiffness for"):
        fe.model(contact=[(11, 2, 1e-3)], layer_stiffness=-1.0)


def test_a_large_export_is_read_and_reduced_without_densifying(tmp_path, monkeypatch):
    """A 3-D solid (quadratic elements, > 1000 DOFs: past the dense eigen-solvers' limits) as a
    Matrix Market pair: read, contact on a tip node with its mass (layer), modal condensation:
    no dense n x n array."""
    from mmshbm.harmonic.condense import make_condensation
    solid = mmshbm.solid_beam_model(mmshbm.default_beam(), 24, 1, 1, massless_tip=False)
    M, K = solid.M, solid.K
    scipy.io.mmwrite(str(tmp_path / "solid_M.mtx"), M.tocoo(), symmetry="symmetric")
    scipy.io.mmwrite(str(tmp_path / "solid_K.mtx"), K.tocoo(), symmetry="symmetric")
    n = M.shape[0]
    real = {cls: cls.toarray for cls in (sp.csr_matrix, sp.csc_matrix, sp.coo_matrix)}

    def guard(cls):
        def toarray(self, *args, **kwargs):
            if self.shape[0] * self.shape[1] > 200 * n:
                raise AssertionError(f"densified a {self.shape} sparse matrix")
            return real[cls](self, *args, **kwargs)
        return toarray

    for cls in real:
        monkeypatch.setattr(cls, "toarray", guard(cls))
    fe = read_fe(tmp_path / "solid_M.mtx", tmp_path / "solid_K.mtx")
    assert fe.n_dof == n > 1000
    model = fe.model(contact=[(solid.contact_dofs[0], 0, 1e-3, 1)])  # a tip node's u_z, with its mass
    cond = make_condensation(model, "modal", harmonics=3)
    assert cond.reduction.solver == "arpack" and cond.n_modes < 60
    assert np.all(np.isfinite(cond.dynamic_stiffness(2 * np.pi * 40.0, 3, False)))


def test_harwell_boeing_symmetric_storage(tmp_path, reference):
    """An RSA file (symmetric: the lower triangle by columns) reads as the full matrix."""
    M, K = reference
    for name, A in (("M", M), ("K", K)):
        path = tmp_path / f"beam_{name}.rsa"
        scipy.io.hb_write(str(path), sp.csc_matrix(np.tril(A)))
        lines = path.read_text().splitlines(keepends=True)
        assert lines[2].startswith("RUA")
        lines[2] = "RSA" + lines[2][3:]
        path.write_text("".join(lines))
    fe = read_fe(tmp_path / "beam_M.rsa", tmp_path / "beam_K.rsa")
    np.testing.assert_allclose(fe.K.toarray(), K, rtol=0, atol=2e-16 * abs(K).max())
    np.testing.assert_allclose(fe.frequencies(3), _read("abaqus").frequencies(3), rtol=1e-12)
