"""The ``mmshbm`` command line, called in-process through ``mmshbm.cli.main``."""

import json

import numpy as np
import pytest

import mmshbm
from mmshbm.cli import main
from mmshbm.io import load
from mmshbm.results.branch import Branch

SMALL = ["--elements", "4", "-H", "3", "--max-amplitude", "3"]


def test_version_and_help(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"mmshbm {mmshbm.__version__}"
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    for cmd in ("modes", "backbone", "study", "fit", "bench", "plot"):
        assert cmd in out


def test_default_backbone(tmp_path, capsys, monkeypatch):
    """``mmshbm backbone`` alone: the default beam, 21 elements, H = 5, into ./out."""
    monkeypatch.chdir(tmp_path)
    assert main(["backbone"]) == 0
    out = tmp_path / "out"
    for name in ("backbone.csv", "backbone.png", "backbone.npz", "frequency_energy.png"):
        assert (out / name).stat().st_size > 0, name
    branch = Branch.load(out / "backbone.npz")
    assert branch.harmonics == 5 and branch.metadata["model"]["n_elements"] == 21
    assert branch.amplitude[-1] == pytest.approx(10 * branch.gap, rel=1e-9)
    data = np.loadtxt(out / "backbone.csv", delimiter=",", skiprows=1)
    np.testing.assert_array_equal(data[:, 0], branch.frequency)
    assert "wrote out/backbone.png" in capsys.readouterr().out


def test_backbone_options_reach_the_run(tmp_path):
    assert main(["backbone", *SMALL, "--gap", "0.002", "--E", "1e11", "--out", str(tmp_path)]) == 0
    b = Branch.load(tmp_path / "backbone.npz")
    assert (b.harmonics, b.metadata["model"]["n_elements"], b.gap) == (3, 4, 0.002)
    assert b.metadata["model"]["E"] == 1e11
    assert b.amplitude.max() == pytest.approx(0.006, rel=1e-9)


def test_checkpoint_and_resume_are_passed_through(tmp_path, monkeypatch):
    import mmshbm.methods.backbone as api

    seen = {}
    real = api.backbone

    def spy(model, **kwargs):
        seen.update(kwargs)
        kwargs.pop("checkpoint", None)
        kwargs.pop("resume", None)
        return real(model, **kwargs)

    monkeypatch.setattr(api, "backbone", spy)
    assert main(["backbone", *SMALL, "--out", str(tmp_path)]) == 0
    assert "checkpoint" not in seen and "resume" not in seen
    ck = str(tmp_path / "ck.npz")
    assert main(["backbone", *SMALL, "--checkpoint", ck, "--resume", ck, "--out", str(tmp_path)]) == 0
    assert seen["checkpoint"] == ck and seen["resume"] == ck


def test_checkpoint_then_resume_equals_one_run(tmp_path):
    assert main(["backbone", *SMALL, "--out", str(tmp_path / "full")]) == 0
    ck = str(tmp_path / "ck" / "c.npz")  # the folder is created
    argv = ["backbone", *SMALL, "--max-steps", "5", "--checkpoint", ck, "--out", str(tmp_path / "a")]
    assert main(argv) == 1  # short of its bounds
    assert Branch.load(tmp_path / "a" / "backbone.npz").status == "max_steps"
    assert main(["backbone", *SMALL, "--resume", ck, "--out", str(tmp_path / "b")]) == 0
    full, resumed = (Branch.load(tmp_path / d / "backbone.npz") for d in ("full", "b"))
    assert resumed.status == "bound:amplitude"
    np.testing.assert_array_equal(resumed.states, full.states)


def test_modes(tmp_path, capsys):
    assert main(["modes", "-n", "2", "--elements", "8", "--out", str(tmp_path)]) == 0
    rows = np.loadtxt(tmp_path / "modes.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(rows[:, 1], mmshbm.default_beam().model(8).linear_frequencies(2), rtol=1e-9)


@pytest.mark.parametrize("argv", [
    ["backbone", "--elements", "0"],
    ["backbone", "--bogus"],
    ["backbone", "-H", "three"],
    ["nonsense"],
    ["plot", "/nonexistent/file.npz"],
    ["fit", "-5"],
    ["backbone", "--measured", "/nonexistent.csv", *SMALL],
    ["study", "--figure2", "-H", "3"],
    ["study", "--param", "gap"],
    ["backbone", "--proximal", "residual", "--method", "penalty", *SMALL],
])
def test_errors_are_one_line_exit_2(argv, tmp_path, capsys):
    assert main([*argv, "--out", str(tmp_path)] if argv[0] != "nonsense" else argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("mmshbm") and ": error: " in err
    assert len(err.splitlines()) == 1 and "Traceback" not in err


def test_study_figure2(tmp_path, capsys):
    assert main(["study", "--figure2", "--executor", "serial", "--max-amplitude", "4",
                 "--out", str(tmp_path)]) == 0
    for name in ("figure2.png", "figure2_table.csv", "figure2_table.txt", "figure2.npz"):
        assert (tmp_path / name).stat().st_size > 0, name
    lines = (tmp_path / "figure2_table.csv").read_text().splitlines()
    assert lines[0].split(",")[:3] == ["method", "elements", "harmonics"]
    assert [tuple(r.split(",")[1:3]) for r in lines[1:]] == [("8", "1"), ("8", "3"), ("8", "5"),
                                                             ("21", "1"), ("21", "3"), ("21", "5")]
    study = load(tmp_path / "figure2.npz")
    f = study.branch(harmonics=5, elements=21).frequency_at(1.5 * 1e-3)
    assert f"{f:.10g}" == lines[6].split(",")[3]
    assert "Convergence: steps between successive runs" in (tmp_path / "figure2_table.txt").read_text()


def test_study_grid_with_parameter(tmp_path):
    assert main(["study", "-H", "3", "--elements", "4", "--param", "gap=0.001,0.002", "--amplitudes", "2",
                 "--executor", "serial", "--max-amplitude", "3", "--out", str(tmp_path)]) == 0
    study = load(tmp_path / "study.npz")
    assert [r["gap"] for r in study.runs] == [0.001, 0.002]
    assert (tmp_path / "study.png").is_file() and (tmp_path / "study_table.csv").is_file()


def test_fit(tmp_path):
    from dataclasses import replace

    from mmshbm.analysis.identification import beam_frequencies

    f = beam_frequencies(replace(mmshbm.default_beam(), E=200e9), 21, 2)
    assert main(["fit", *(f"{x:.12g}" for x in f), "--out", str(tmp_path)]) == 0
    record = json.loads((tmp_path / "fit.json").read_text())
    assert record["E"] == pytest.approx(200e9, rel=1e-8) and record["rho"] == 7850.0
    assert (tmp_path / "fit.txt").is_file()


def test_plot_saved_branch(tmp_path):
    assert main(["backbone", *SMALL, "--out", str(tmp_path)]) == 0
    argv = ["plot", str(tmp_path / "backbone.npz"), "--points", "1.5", "2.5", "--out", str(tmp_path)]
    assert main(argv) == 0
    for kind in ("backbone", "energy", "peak_force", "signals", "contact_force", "harmonics"):
        assert (tmp_path / f"backbone_{kind}.png").stat().st_size > 0, kind


def test_bench(tmp_path, monkeypatch):
    """The wiring only (the benchmark itself is tested with mmshbm.analysis.benchmarking)."""
    import importlib
    import sys
    import types

    try:
        benchmarking = importlib.import_module("mmshbm.analysis.benchmarking")
    except ImportError:  # not written yet: a stand-in module with the agreed functions
        benchmarking = types.ModuleType("mmshbm.analysis.benchmarking")
        monkeypatch.setitem(sys.modules, "mmshbm.analysis.benchmarking", benchmarking)
    calls = {}

    def fake(**kwargs):
        calls.update(kwargs)
        return [{"method": "mmshbm"}]

    monkeypatch.setattr(benchmarking, "compare_methods", fake, raising=False)
    monkeypatch.setattr(benchmarking, "format_table", lambda rows: "table", raising=False)
    monkeypatch.setattr(benchmarking, "write_results", lambda rows, out: [out / "bench.csv"], raising=False)
    assert main(["bench", "--quick", "--model", "oscillator", "--target", "1e-3", "--methods", "mmshbm",
                 "--amplitude", "3", "--out", str(tmp_path)]) == 0
    assert calls == {"model": "oscillator", "quick": True, "target": 1e-3, "methods": ("mmshbm",),
                     "amplitude_gaps": 3.0}
    calls.clear()
    assert main(["bench", "--out", str(tmp_path)]) == 0
    assert calls == {"model": "beam21", "quick": False}  # the rest: compare_methods' defaults
