"""Result files written by earlier versions still load: a backbone of the one-DOF oscillator,
one of a 3-DOF chain given by its matrices (stored in the file) and a forced response of
the damped oscillator, each written by 0.2.0 and by the last version before the results
shared one base class (tests/data/results, written by tests/data/README.md's recipe).
The loaded arrays are checked against the physics they describe, and the solver rebuilt
from each file reproduces the stored points."""

from __future__ import annotations

import numpy as np
import pytest
from locations import DATA as TEST_DATA

import mmshbm
from mmshbm.io import load
from mmshbm.results.branch import Branch
from mmshbm.results.response import FrequencyResponse

FILES = TEST_DATA / "results"
VERSIONS = ["v0.2", "main"]


@pytest.mark.parametrize("version", VERSIONS)
def test_oscillator_backbone_file(version):
    b = Branch.load(FILES / f"branch_osc_{version}.npz")
    assert isinstance(load(FILES / f"branch_osc_{version}.npz"), Branch)
    assert b.attached_solver is None and b.method == "mmshbm" and b.harmonics == 3 and b.completed
    # m = k1 = 1, k2 = 4, gap 1: linear below grazing (ω = 1 rad/s), stiffer above
    below = b.amplitude < 1.0
    np.testing.assert_allclose(b.frequency[below], 1 / (2 * np.pi), rtol=1e-9)
    assert b.frequency[-1] > b.frequency[0] and b.amplitude[-1] == pytest.approx(2.0, rel=1e-9)
    assert b.gap == 1.0
    # the solver rebuilt from the file alone: the stored points solve its equations
    residual = max(np.abs(b.solver.evaluate(u, jacobian=False)).max() for u in b.states)
    assert residual < 1e-8
    assert b.solver is b.attached_solver  # rebuilt once, then held
    t, lam = b.contact_force(len(b) - 1, 64)
    assert t.shape == (64,) and lam.max() == pytest.approx(b.contact_force_max[-1], rel=0.05)


@pytest.mark.parametrize("version", VERSIONS)
def test_user_matrix_backbone_file(version):
    b = Branch.load(FILES / f"branch_chain_{version}.npz")
    model = b.get_model()  # from the stored matrices: the description cannot rebuild it
    assert model.n_dof == 3 and model.gap == 0.01 and model.contact_dof == 2
    np.testing.assert_array_equal(model.K.toarray(), [[2000.0, -1000.0, 0.0], [-1000.0, 6000.0, -5000.0],
                                                      [0.0, -5000.0, 5000.0]])
    # below grazing: the chain's first mode with the massless node condensed out
    K = model.K.toarray()
    Kc = K[:2, :2] - np.outer(K[:2, 2], K[2, :2]) / K[2, 2]
    w1 = np.sqrt(np.linalg.eigvalsh(Kc)[0])
    np.testing.assert_allclose(b.frequency[b.amplitude < 0.01], w1 / (2 * np.pi), rtol=1e-9)
    assert b.solver.n_unknowns == b.states.shape[1]
    if version != "v0.2":  # 0.2 scaled the unknowns of several-DOF models otherwise
        residual = max(np.abs(b.solver.evaluate(u, jacobian=False)).max() for u in b.states)
        assert residual < 1e-8


@pytest.mark.parametrize("version", VERSIONS)
def test_forced_response_file(version):
    r = FrequencyResponse.load(FILES / f"response_osc_{version}.npz")
    assert isinstance(load(FILES / f"response_osc_{version}.npz"), FrequencyResponse)
    assert r.completed and r.frequency.min() == pytest.approx(0.1, rel=1e-6) and r.gap == 1.0
    assert r.special_points[0].kind == "start" and r.special_points[-1].kind == "endpoint"
    # at the low end the response is linear: |x| = F / |k1 − m ω² + i c ω|, c = 2 ζ ω1 m
    w = 2 * np.pi * r.frequency[0]
    x = 0.3 / abs(1.0 - w**2 + 1j * 2 * 0.02 * 1.0 * w)
    assert r.amplitude[0] == pytest.approx(x, rel=1e-6)
    p = r.solver  # rebuilt from the model description and the stored excitation
    for i in (0, len(r) // 2, len(r) - 1):
        assert np.abs(p.evaluate(r.states[i], jacobian=False)).max() < 1e-8
        assert p.monitor(r.states[i])["amplitude"] == pytest.approx(r.amplitude[i], rel=1e-9)


def test_rebuilt_files_write_the_same_arrays(tmp_path):
    """A file of 0.2 read and written again by this version keeps every array bit for bit."""
    old = Branch.load(FILES / "branch_osc_v0.2.npz")
    again = Branch.load(old.save(tmp_path / "b.npz"))
    for name in Branch.ARRAY_FIELDS:
        assert getattr(old, name).tobytes() == getattr(again, name).tobytes()
    r = FrequencyResponse.load(FILES / "response_osc_v0.2.npz")
    r2 = FrequencyResponse.load(r.save(tmp_path / "r.npz"))
    for name in FrequencyResponse.ARRAY_FIELDS:
        assert getattr(r, name).tobytes() == getattr(r2, name).tobytes()
    assert sorted(r.records) == sorted(r2.records)


def test_a_file_of_another_kind_is_refused():
    with pytest.raises(ValueError, match="not a saved mmshbm FrequencyResponse"):
        FrequencyResponse.load(FILES / "branch_osc_main.npz")
    with pytest.raises(ValueError, match="not a saved mmshbm Branch"):
        Branch.load(FILES / "response_osc_main.npz")


def test_solver_is_rebuilt_lazily_and_can_be_dropped():
    b = mmshbm.Branch.load(FILES / "branch_osc_main.npz")
    assert b.attached_solver is None
    s = b.solver
    assert s is not None and b.attached_solver is s
    b.solver = None
    assert b.attached_solver is None and b.solver is not s  # rebuilt again
