"""Command line for models as FE packages export them:
``--model-file`` with mass on the contact DOF, ``--contact-layer`` / ``--massless-contact``,
``mmshbm fit ... --measured``."""

import json
import re

import numpy as np
import pytest

from mmshbm.analysis.contact_fit import backbone_frequencies
from mmshbm.cli import main
from mmshbm.fe.euler_bernoulli import cantilever_model
from mmshbm.results.branch import Branch

GAP = 1e-3
SMALL = ["-H", "3", "--max-amplitude", "2"]


@pytest.fixture(scope="module")
def exported():
    """An 8-element cantilever as an FE package exports it: mass on every DOF."""
    return cantilever_model(0.5, 0.020, 0.0135, 210e9, 7850.0, 8, GAP)


@pytest.fixture()
def model_file(exported, tmp_path):
    path = tmp_path / "exported.npz"
    exported.save_npz(path)
    return str(path)


def test_penalty_runs_the_exported_model(model_file, tmp_path):
    out = tmp_path / "out"
    argv = ["backbone", "--model-file", model_file, "--method", "penalty", *SMALL, "--out", str(out)]
    assert main(argv) == 0
    branch = Branch.load(out / "backbone.npz")
    assert branch.method == "penalty" and branch.amplitude[-1] == pytest.approx(2 * GAP, rel=1e-6)


def test_mms_hbm_refuses_it_and_names_the_conversions(model_file, tmp_path, capsys):
    assert main(["backbone", "--model-file", model_file, *SMALL, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "carries mass" in err and "with_contact_layer" in err and "with_massless_contact" in err


def test_contact_layer_option(model_file, exported, tmp_path):
    out = tmp_path / "out"
    argv = ["backbone", "--model-file", model_file, "--contact-layer", "2e7", *SMALL, "--out", str(out)]
    assert main(argv) == 0
    branch = Branch.load(out / "backbone.npz")
    model = branch.get_model()
    assert model.same_as(exported.with_contact_layer(2e7))
    assert branch.amplitude[-1] == pytest.approx(2 * GAP, rel=1e-6)


def test_contact_layer_default_on_the_beam(tmp_path):
    out = tmp_path / "out"
    assert main(["backbone", "--elements", "8", "--contact-layer", "default", *SMALL, "--out", str(out)]) == 0
    model = Branch.load(out / "backbone.npz").get_model()
    assert model.n_dof == 17 and model.description["massless_tip"] is False
    assert model.description["contact_layer"]["factor"] == [pytest.approx(1e5)]


def test_massless_contact_option_says_what_it_did(model_file, tmp_path, capsys):
    """The conversion's report is a warning line on stderr (the CLI prints warnings)."""
    out = tmp_path / "out"
    code = main(["backbone", "--model-file", model_file, "--massless-contact", *SMALL, "--out", str(out)])
    err = capsys.readouterr().err
    said = r"warning: .*DOFs \[14, 15\]: .*\(8\.53 %.*f1 45\.118 -> 53\.228 Hz \(\+17\.97 %\)"
    assert re.search(said, err), err
    assert code == 0
    assert Branch.load(out / "backbone.npz").get_model().c.tolist() == [14, 15]
    assert main(["modes", "--model-file", model_file, "--massless-contact", "14", "--out", str(out)]) == 0
    assert re.search(r"warning: .*DOFs \[14\]", capsys.readouterr().err)


@pytest.mark.parametrize("argv, message", [
    (["--contact-layer", "-1"], "stiffness must be positive and finite"),
    (["--contact-layer", "stiff"], "expected a stiffness in N/m or 'default'"),
    (["--massless-contact", "14", "14"], "names DOF 14 twice"),
    (["--massless-contact", "99"], "dofs[0] = 99 is out of range"),
    (["--contact-layer", "1e7", "--massless-contact"], "not allowed with argument"),
])
def test_bad_conversion_options(model_file, tmp_path, capsys, argv, message):
    assert main(["backbone", "--model-file", model_file, *argv, *SMALL, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert message in err, err


def test_fit_contact_stiffness_from_a_measured_backbone(exported, model_file, tmp_path, capsys):
    k_true = 4e6
    amplitudes = np.linspace(1.2, 1.8, 5) * GAP
    f = backbone_frequencies(exported.with_contact_layer(k_true), amplitudes)
    csv = tmp_path / "measured.csv"
    np.savetxt(csv, np.column_stack([f, amplitudes]), delimiter=",", header="frequency_hz,amplitude_m",
               comments="")
    out = tmp_path / "out"
    assert main(["fit", "--model-file", model_file, "--measured", str(csv), "--out", str(out)]) == 0
    record = json.loads((out / "fit.json").read_text())["contact_layer"]
    assert record["stiffness"] == pytest.approx(k_true, rel=1e-6) and record["identifiable"]
    assert "fitted the contact-layer stiffness" in capsys.readouterr().out


def test_fit_material_then_contact_on_the_beam(tmp_path):
    """E from the full-mass beam's frequency, then k: both come back."""
    from dataclasses import replace

    import mmshbm

    beam = replace(mmshbm.default_beam(), E=200e9)
    model = beam.model(8, massless_tip=False)
    amplitudes = np.array([1.2, 1.4, 1.6]) * GAP
    f = backbone_frequencies(model.with_contact_layer(3e6), amplitudes)
    csv = tmp_path / "measured.csv"
    np.savetxt(csv, np.column_stack([f, amplitudes]), delimiter=",", header="frequency,amplitude",
               comments="")
    f1 = model.linear_frequencies(1)[0]
    out = tmp_path / "out"
    assert main(["fit", f"{f1:.15g}", "--elements", "8", "--measured", str(csv), "--initial", "1e7",
                 "--out", str(out)]) == 0
    record = json.loads((out / "fit.json").read_text())
    assert record["E"] == pytest.approx(200e9, rel=1e-9) and record["massless_tip"] is False
    assert record["contact_layer"]["stiffness"] == pytest.approx(3e6, rel=1e-5)


def test_fit_needs_something_to_fit(tmp_path, capsys):
    assert main(["fit", "--out", str(tmp_path)]) == 2
    assert "give measured frequencies" in capsys.readouterr().err
