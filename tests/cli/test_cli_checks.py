"""The command line cannot mislead: warnings, exit codes, validated options, limits, help."""

import argparse
import json
import os
import stat

import numpy as np
import pytest

import mmshbm
from mmshbm.cli import build_parser, main
from mmshbm.cli import common as cli_common

SMALL = ["--elements", "4", "-H", "3", "--max-amplitude", "3"]


def test_penalty_cli_warns_another_family(tmp_path, capsys):
    # reached its bounds, on another family: exit 1
    assert main(["backbone", "--method", "penalty", "--out", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert "mmshbm backbone: warning: penalty branch leaves the family of linear mode 1" in err
    assert "Traceback" not in err and "warnings.warn" not in err


def test_short_run_exits_1_with_the_reason(tmp_path, capsys):
    assert main(["backbone", *SMALL, "--max-steps", "3", "--out", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert "ended short of its bounds" in err and "max_steps = 3" in err


def test_study_counts_incomplete_runs_and_says_why(tmp_path, capsys):
    argv = ["study", "-H", "1", "3", "--elements", "4", "--max-amplitude", "3", "--max-steps", "6",
            "--executor", "serial", "--out", str(tmp_path)]
    assert main(argv) == 1
    out, err = capsys.readouterr()
    assert "2 runs: 0 reached their bounds, 2 incomplete" in out
    rows = [line for line in out.splitlines() if line.startswith("H3 ")]
    assert len(rows) == 1 and "short: stopped at" in rows[0] and "step budget" in rows[0]
    assert err == ""  # the findings are the table's, not a warning each
    table = (tmp_path / "study_table.txt").read_text()
    assert "not reached: stopped at" in table  # the empty cells and convergence rows say why
    assert "incomplete: method=mmshbm, elements=4, harmonics=3" in table
    assert "the step budget max_steps = 6 ran out" in table
    assert "  mmshbm branch ended short of its bounds at 1.11 gaps of 3" in table
    assert "outside the amplitude range" not in table  # an empty cell is the table's note, not a warning


@pytest.mark.parametrize("argv, name", [
    (["backbone", "--max-amplitude", "0"], "--max-amplitude"),
    (["backbone", "--max-steps", "0"], "--max-steps"),
    (["backbone", "--gap", "0"], "--gap"),
    (["backbone", "--E", "-1"], "--E"),
    (["backbone", "--grading", "nan"], "--grading"),
    (["study", "--workers", "0"], "--workers"),
    (["study", "--amplitudes", "1", "0"], "--amplitudes"),
    (["modes", "-n", "0"], "-n"),
    (["fit", "45.8", "--mass", "0"], "--mass"),
    (["plot", "x.npz", "--points", "-1"], "--points"),
    (["bench", "--repeats", "0"], "--repeats"),
])
def test_zero_and_negative_are_refused(argv, name, tmp_path, capsys):
    assert main([*argv, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert name in err and len(err.splitlines()) == 1


def _options(parser):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from ((name, a) for a in sub._actions)
        else:
            yield "mmshbm", action


def test_every_numeric_option_is_validated():
    """No option takes a bare int or float: each uses a validating type (0 is a value)."""
    bare = [(cmd, a.option_strings or a.dest) for cmd, a in _options(build_parser())
            if a.type in (int, float)]
    assert bare == []


def test_help_is_plain_text_with_defaults(capsys):
    for argv in (["-h"], ["backbone", "-h"], ["study", "-h"], ["plot", "-h"]):
        assert main(argv) == 0
        text = capsys.readouterr().out
        assert "``" not in text and "::" not in text
    assert main(["backbone", "-h"]) == 0
    text = capsys.readouterr().out
    assert "(default: mmshbm)" in text and "(default 5)" in text


def test_verbose_after_the_subcommand():
    parser = build_parser()
    assert parser.parse_args(["modes", "-v"]).verbose == 1
    assert parser.parse_args(["-v", "modes"]).verbose == 1
    assert parser.parse_args(["modes", "-vv"]).verbose == 2
    assert parser.parse_args(["modes"]).verbose == 0


def test_harmonics_beyond_memory_refused_before_allocation(tmp_path, capsys):
    assert main(["backbone", "-H", "5000", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "harmonics = 5000" in err and "GiB of memory" in err and "MemoryError" not in err


def test_memory_limit_environment(monkeypatch):
    from mmshbm.methods.limits import estimate_memory

    model = mmshbm.default_beam().model(21)
    est = estimate_memory(model, "mmshbm", 1000)
    assert 1.5 * 2**30 < est < 3 * 2**30  # measured peak 2.3 GB (the issue)
    monkeypatch.setenv("MMSHBM_MEMORY_LIMIT", str(est // 2))
    with pytest.raises(ValueError, match="harmonics = 1000 .* about H = 500 fits"):
        mmshbm.backbone(model, harmonics=1000)
    monkeypatch.setenv("MMSHBM_MEMORY_LIMIT", "many")
    with pytest.raises(ValueError, match="MMSHBM_MEMORY_LIMIT"):
        mmshbm.backbone(model, harmonics=3)


def test_small_run_fits_without_asking_the_system(monkeypatch):
    from mmshbm.methods import limits

    model = mmshbm.default_beam().model(21)
    est = limits.estimate_memory(model, "mmshbm", 5)
    assert est <= limits._SMALL_RUN_BYTES

    def unavailable():
        raise AssertionError("memory_limit read")

    monkeypatch.setattr(limits, "memory_limit", unavailable)
    assert limits.check_resources(model, "mmshbm", {"harmonics": 5}) == est
    monkeypatch.setenv("MMSHBM_MEMORY_LIMIT", str(est // 2))  # the user's limit applies to every run
    with pytest.raises(AssertionError, match="memory_limit read"):
        limits.check_resources(model, "mmshbm", {"harmonics": 5})


def test_large_run_is_announced(caplog):
    from mmshbm.methods.limits import check_resources

    model = mmshbm.default_beam().model(21)
    with caplog.at_level("WARNING", logger="mmshbm.methods.limits"):
        check_resources(model, "mmshbm", {"harmonics": 1000})
    assert "expect a run of minutes" in caplog.text


def test_progress_counts_amplitude_toward_its_bound():
    from mmshbm.methods.backbone import _amplitude_progress

    seen = []
    bar, callback = _amplitude_progress("mmshbm", 10e-3, 1e-3, lambda u, r: seen.append(r["amplitude"]))
    try:
        assert bar.total == pytest.approx(10.0)  # gaps, not max_steps + 1
        callback(None, {"amplitude": 2.5e-3, "frequency": 50.0})
        assert bar.n == pytest.approx(2.5) and seen == [2.5e-3]
        callback(None, {"amplitude": 10e-3, "frequency": 60.0})
        assert bar.n == pytest.approx(bar.total)
    finally:
        bar.close()


@pytest.mark.parametrize("content, expected", [
    (bytes(range(256)) * 2, "not an .npz archive"),
    (b"frequency_hz,amplitude_m\n1,2\n", "text file"),
    (b"", "is empty"),
    (b"\x93NUMPY", "single NumPy array"),
])
def test_plot_wrong_formats_have_own_messages(content, expected, tmp_path, capsys):
    path = tmp_path / "garbage.npz"
    path.write_bytes(content)
    assert main(["plot", str(path), "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert expected in err and "pickle" not in err


def test_plot_other_npz_formats(tmp_path, capsys):
    np.savez(tmp_path / "obj.npz", metadata=np.array([{"a": 1}], dtype=object))
    np.savez(tmp_path / "plain.npz", a=np.arange(3))
    mmshbm.default_beam().model(4).save_npz(tmp_path / "model.npz")
    (tmp_path / "folder.npz").mkdir()
    expected = {"obj.npz": "holds Python objects", "plain.npz": "not an mmshbm results file",
                "model.npz": "is a model file", "folder.npz": "is a folder", "missing.npz": "no such file"}
    for name, text in expected.items():
        assert main(["plot", str(tmp_path / name), "--out", str(tmp_path)]) == 2
        err = capsys.readouterr().err
        assert text in err and "allow_pickle" not in err, (name, err)


def test_fit_inconsistent_frequencies_not_identifiable(tmp_path, capsys):
    # the case: three equal frequencies for modes 1..3, rms error 160 %
    assert main(["fit", "45.8", "45.8", "45.8", "--out", str(tmp_path)]) == 1
    record = json.loads((tmp_path / "fit.json").read_text())
    assert record["identifiable"] is False
    out = capsys.readouterr().out
    assert "NOT identifiable" in out and "do not increase with the mode number" in out
    assert main(["fit", "45.8", "286.5", "--out", str(tmp_path)]) == 0  # consistent data still fit
    assert json.loads((tmp_path / "fit.json").read_text())["identifiable"] is True


def test_files_have_umask_permissions(tmp_path):
    old = os.umask(0o022)
    try:
        ck = str(tmp_path / "run.ckpt")
        assert main(["backbone", *SMALL, "--checkpoint", ck, "--out", str(tmp_path)]) == 0
        for name in ("backbone.npz", "run.ckpt", "backbone.csv"):
            assert stat.S_IMODE((tmp_path / name).stat().st_mode) == 0o644, name
        os.umask(0o027)
        branch = mmshbm.results.branch.Branch.load(tmp_path / "backbone.npz")
        assert stat.S_IMODE(branch.save(tmp_path / "again.npz").stat().st_mode) == 0o640
    finally:
        os.umask(old)


def test_csv_numbers_short_and_exact(tmp_path):
    assert main(["backbone", *SMALL, "--out", str(tmp_path)]) == 0
    branch = mmshbm.results.branch.Branch.load(tmp_path / "backbone.npz")
    lines = (tmp_path / "backbone.csv").read_text().splitlines()
    rows = [line.split(",") for line in lines[1:]]
    assert float(rows[0][0]) == branch.frequency[0]
    for row, f, a, e, s in zip(rows, branch.frequency, branch.amplitude, branch.energy, branch.step_size,
                               strict=True):
        assert [float(row[0]), float(row[1]), float(row[2]), float(row[5])] == [f, a, e, s]  # exact
        assert all(len(x) <= 24 for x in row)
    assert rows[1][5] == repr(float(branch.step_size[1]))  # repr: shortest round-trip text, not %.17g
    assert "0.10000000000000001" not in (tmp_path / "backbone.csv").read_text()


def test_validators_accept_good_values():
    assert cli_common.positive_int("3") == 3
    assert cli_common.non_negative_float("0") == 0.0 and cli_common.non_negative_int("0") == 0
    assert cli_common.positive_float("1e-3") == 1e-3
    for bad in ("0", "-1", "inf", "nan", "x"):
        with pytest.raises(argparse.ArgumentTypeError):
            cli_common.positive_float(bad)


def test_elements_beyond_memory_refused_before_assembly(tmp_path, capsys):
    assert main(["backbone", "--elements", "100000000000", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "100000000000 elements" in err and "GiB of memory" in err


def test_many_elements_announced(caplog):
    from mmshbm.methods.limits import check_beam_elements

    with caplog.at_level("WARNING", logger="mmshbm.methods.limits"):
        check_beam_elements(100_000)
    assert "minutes per backbone" in caplog.text


def test_plot_repeats_the_findings(tmp_path, capsys):
    assert main(["backbone", *SMALL, "--max-steps", "3", "--out", str(tmp_path)]) == 1
    capsys.readouterr()
    assert main(["plot", str(tmp_path / "backbone.npz"), "--kind", "backbone", "--out", str(tmp_path)]) == 0
    assert "mmshbm plot: warning: mmshbm branch ended short of its bounds" in capsys.readouterr().err


def test_backbone_names_resonances_and_jumps_and_follows_the_path_on_request(tmp_path, capsys):
    """H = 7: the family warning says where the excursions are and how to leave them out,
    the truncation effects come as one warning, and stdout names the 6:1 and 5:1
    resonances with mode 2 and the jumps; --follow path stays on the 6:1 tongue."""
    assert main(["backbone", "-H", "7", "-v", "--out", str(tmp_path)]) == 0  # -v: every finding
    out, err = capsys.readouterr()
    assert "internal resonances: 6Ω≈f₂" in out and "5Ω≈f₂" in out
    assert "jumps over tongues: " in out
    warnings_ = [line for line in err.splitlines() if "warning:" in line]
    assert len(warnings_) == 2
    assert "follows the family of linear mode 1 past internal resonances" in warnings_[0]
    assert "branch.family_front()" in warnings_[0]
    assert "passes the stop" in warnings_[1] and "pulls" in warnings_[1]
    assert main(["backbone", "-H", "7", "--follow", "path", "--max-amplitude", "2",
                 "--out", str(tmp_path / "path")]) == 0
    out, err = capsys.readouterr()
    assert "jumps over tongues" not in out and "leaves the family of linear mode 1" in err
    branch = mmshbm.load(tmp_path / "path" / "backbone.npz")
    assert branch.metadata["continuation"]["follow"] == "path"
    assert branch.frequency[-1] < 48.5  # on the tongue at f2/6 = 47.7 Hz, not the backbone
