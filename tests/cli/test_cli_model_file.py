"""The command line with FE exports: ``--model-file PATH [PATH ...]``, ``--contact``,
``--friction``, what ``mmshbm modes`` prints of an import, and ``modes -n`` beyond the
model's modes."""

import csv

import numpy as np
import pytest
from locations import DATA as TEST_DATA

from mmshbm.cli import main
from mmshbm.results.branch import Branch

DATA = TEST_DATA / "fe"
ABAQUS = [str(DATA / "beam_MASS1.mtx"), str(DATA / "beam_STIF1.mtx")]
SAME_CANTILEVER = {
    "abaqus": ABAQUS,
    "op4": [str(DATA / "beam.op4")],
    "matrix-market": [str(DATA / "beam_M.mtx"), str(DATA / "beam_K.mtx")],
    "matlab": [str(DATA / "beam.mat")],
}


def _modes(files, tmp_path, *extra):
    out = tmp_path / "out"
    assert main(["modes", "--model-file", *files, "-n", "5", *extra, "--out", str(out)]) == 0
    with open(out / "modes.csv") as f:
        return np.array([float(r["frequency_hz"]) for r in csv.DictReader(f)])


def test_the_same_cantilever_in_four_formats_has_the_same_modes(tmp_path):
    freqs = {name: _modes(files, tmp_path) for name, files in SAME_CANTILEVER.items()}
    # modes.csv keeps 10 significant digits: equal matrices give values within one unit of
    # the 10th digit, 1e-9 relative for frequencies whose leading digit is >= 1
    for name, f in freqs.items():
        np.testing.assert_allclose(f, freqs["abaqus"], rtol=1e-9, err_msg=name)
    assert freqs["abaqus"][0] == pytest.approx(45.117935, rel=1e-7)


def test_modes_prints_the_import(tmp_path, capsys):
    _modes(ABAQUS, tmp_path)
    out = capsys.readouterr().out
    assert "(abaqus): 20 DOFs" in out and "nodes 2-11 (10), components [2, 6]" in out
    assert "mode 1: 45.1179 Hz" in out and "Hz if the export's units are consistent" in out
    _modes([str(DATA / "beam_aster.npz")], tmp_path)
    out = capsys.readouterr().out
    assert "removed 2 constrained DOFs (nodes 1)" in out
    _modes([str(DATA / "beam.op4")], tmp_path)
    assert "plain indices 0..19" in capsys.readouterr().out


def test_modes_says_why_it_computes_fewer_than_asked(tmp_path, capsys):
    assert main(["modes", "-n", "1000", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert ("the model has 40 DOFs with mass: 40 modes (-n 1000 asked for more; its 2 massless DOFs "
            "have none; "
            "all 40 computed)") in out
    assert "mode 40:" in out and "mode 41:" not in out
    assert main(["modes", "--model-file", *ABAQUS, "-n", "1000", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "20 modes (-n 1000 asked for more; all 20 computed)" in out and "mode 20:" in out


def test_backbone_of_the_abaqus_pair_by_node_under_the_defaults(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["backbone", "--model-file", *ABAQUS, "--contact", "11:2:1e-3", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert ("massless layer at node 11 component 2: k = 2.06671e+09 N/m (1e+05 x the static "
            "stiffness") in printed
    branch = Branch.load(out / "backbone.npz")
    assert branch.status == "bound:amplitude"
    assert branch.amplitude.max() == pytest.approx(10e-3, rel=1e-6)  # the default bound: 10 gaps
    assert branch.frequency[0] == pytest.approx(45.117935, rel=1e-6)


def test_contact_layer_and_gap_options(tmp_path, capsys):
    argv = ["modes", "--model-file", *ABAQUS, "--contact", "11:2", "--gap", "2e-3", "--contact-layer", "5e6",
            "-n", "2", "--out", str(tmp_path)]
    assert main(argv) == 0
    assert "k = 5e+06 N/m (242 x the static stiffness" in capsys.readouterr().out
    assert main([*argv[:6], "-n", "2", "--out", str(tmp_path)]) == 2
    assert "--contact 11:2: give the gap (NODE:COMPONENT:GAP) or --gap" in capsys.readouterr().err


@pytest.mark.parametrize(("argv", "message"), [
    (["--contact", "11"], "expected NODE:COMPONENT[:GAP[:SIDE]], got '11'"),
    (["--contact", "11:2:1e-3:0"], "the side must be +1 or -1"),
    (["--contact", "11:2:-1"], "the gap must be a finite number > 0"),
    (["--contact", "12:2:1e-3"], "no DOF (node 12, component 2)"),
    (["--friction", "10:2:0.3"], "expected NODE:COMPONENT:MU:LOAD"),
    (["--contact-dof", "18", "--contact", "11:2:1e-3"], "not both"),
])
def test_bad_contact_options(argv, message, tmp_path, capsys):
    assert main(["backbone", "--model-file", *ABAQUS, *argv, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


def test_an_export_without_contact_is_refused_with_the_option(tmp_path, capsys):
    assert main(["backbone", "--model-file", *ABAQUS, "--out", str(tmp_path)]) == 2
    assert "names no contact: give --contact NODE:COMPONENT:GAP (nodes 2-11" in capsys.readouterr().err


def test_friction_by_node(tmp_path, capsys):
    argv = ["modes", "--model-file", *ABAQUS, "--friction", "11:2:0.3:5", "-n", "2", "--out", str(tmp_path)]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "massless layer at node 11 component 2" in out and "mode 2:" in out


def test_contact_dof_rows_on_an_export(tmp_path, capsys):
    """--contact-dof names rows (0-based) for formats without a DOF table."""
    argv = ["modes", "--model-file", str(DATA / "beam.op4"), "--contact-dof", "18", "--gap", "1e-3",
            "-n", "1", "--out", str(tmp_path)]
    assert main(argv) == 0
    assert "massless layer at node 18 component 0" in capsys.readouterr().out
    argv = ["modes", "--model-file", str(DATA / "beam.op4"), "--contact", "18:0:1e-3", "-n", "1",
            "--out", str(tmp_path)]
    assert main(argv) == 0
    assert "massless layer at node 18 component 0" in capsys.readouterr().out
