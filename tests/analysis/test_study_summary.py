"""A study prints one findings table and a count, not a warning per finding; the runs'
own warnings (also those raised in worker processes) go to the report file."""

import warnings

import pytest

import mmshbm
from mmshbm import BranchWarning, ModelWarning
from mmshbm.analysis import runspec, studies
from mmshbm.cli import main
from mmshbm.harmonic.modal import ModalCondensation

GRID = ["study", "-H", "1", "3", "5", "--elements", "4", "6", "--max-amplitude", "3", "--amplitudes", "2",
        "--executor", "serial"]


@pytest.fixture
def model_warning(monkeypatch):
    """Every modal condensation warns that a harmonic reaches its left-out modes (as the
    default beam at H = 15 does in some runs of the 35-run study)."""
    def check_range(self, omega, harmonics):
        warnings.warn("harmonic 15 of Ω = 1 Hz reaches 2 Hz, near or past the first mode the modal "
                      "condensation leaves out", ModelWarning, stacklevel=2)
        return False

    monkeypatch.setattr(ModalCondensation, "check_range", check_range)


def test_the_study_prints_a_row_per_run_and_a_count(tmp_path, capsys):
    assert main([*GRID, "--out", str(tmp_path)]) == 0
    out, err = capsys.readouterr()
    lines = out.splitlines()
    # header, 6 runs, the count, where the details are, the files written: 35 runs give 39 lines
    assert len(lines) == 6 + 4
    head = ["run", "status", "family", "truncation", "effects", "skipped", "(gaps)", "notes"]
    assert lines[0].split() == head
    assert [ln.split()[:3] for ln in lines[1:7]] == [[f"H{h},", "4", "el."] for h in (1, 3, 5)] + \
        [[f"H{h},", "6", "el."] for h in (1, 3, 5)]
    assert all("complete" in ln for ln in lines[1:7])
    assert lines[7].startswith("6 runs: 6 reached their bounds, 0 incomplete")
    assert "with truncation effects" in lines[7]
    assert f"{tmp_path}/study_table.txt" in lines[8] and lines[9].startswith("wrote ")
    assert err == ""
    details = (tmp_path / "study_table.txt").read_text()
    assert "run method=mmshbm, elements=6, harmonics=5:\n  mmshbm branch" in details


def test_verbose_prints_the_report(tmp_path, capsys):
    assert main([*GRID[:1], "-H", "3", "--elements", "4", "--max-amplitude", "3", "--amplitudes", "2",
                 "--executor", "serial", "-v", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "Frequency (Hz) at tip amplitude" in out and "Details per run" in out


def test_warnings_inside_a_run_are_recorded_not_shown(model_warning, tmp_path, capsys):
    spec = studies.grid_specs(harmonics=(3,), elements=(4,), max_amplitude=2e-3, backend="modal")[0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing escapes the worker's function
        branch = runspec.execute(spec)
    assert branch.metadata["run_warnings"] == [
        "ModelWarning: harmonic 15 of Ω = 1 Hz reaches 2 Hz, near or past the first mode the modal "
        "condensation leaves out"]
    capsys.readouterr()  # (info logs of the run above when an earlier test left the logger at -v)
    assert main(["study", "-H", "3", "--elements", "4", "--max-amplitude", "2", "--param", "backend=modal",
                 "--executor", "serial", "--out", str(tmp_path)]) == 0
    out, err = capsys.readouterr()
    assert err == ""  # no raw warning, no source line
    assert "1 warning" in out.splitlines()[1]
    assert "condensation leaves out" in (tmp_path / "study_table.txt").read_text()


def test_run_study_warns_once_with_the_counts():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        study = studies.run_study(harmonics=(1, 3), elements=(4,), executor="serial", max_amplitude=3.0,
                                  unit="gap")
    messages = [str(w.message) for w in caught if issubclass(w.category, BranchWarning)]
    assert len(messages) == 1
    assert messages[0].startswith("study: 2 runs: 2 reached their bounds, 0 incomplete; 2 with truncation")
    assert "study.findings()" in messages[0]
    rows = study.findings().splitlines()
    assert len(rows) == 1 + 2 + 1 and rows[1].startswith("H1 ") and rows[2].startswith("H3 ")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        studies.run_study(harmonics=(1,), elements=(4,), executor="serial", max_amplitude=3.0, unit="gap",
                          warn=False)
    assert isinstance(study.branches[0], mmshbm.Branch)


def test_other_warnings_from_the_package_are_one_line(monkeypatch, tmp_path, capsys):
    """A warning of another category raised in the package's code (here a RuntimeWarning
    from the condensation) is one line on the terminal, named by its category, never the
    interpreter's two lines with the source line."""
    import mmshbm.harmonic.modal as modal

    def check_range(self, omega, harmonics):
        warnings.warn("overflow in a test", UserWarning, stacklevel=1)  # raised in mmshbm/harmonic/modal.py
        return True

    monkeypatch.setattr(modal.ModalCondensation, "check_range", check_range)
    monkeypatch.setattr(check_range, "__code__", check_range.__code__.replace(co_filename=modal.__file__))
    argv = ["backbone", "--elements", "4", "-H", "3", "--max-amplitude", "2", "--out", str(tmp_path)]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "mmshbm backbone: warning: UserWarning: overflow in a test" in err
    assert "warnings.warn(" not in err and "modal.py:" not in err


def test_a_baseline_on_another_family_is_named_in_its_row():
    study = studies.run_study(harmonics=(3,), elements=(4,), methods=("mmshbm", "shooting"),
                              executor="serial", max_amplitude=2.0, unit="gap", warn=False)
    rows = dict(line.split(maxsplit=1) for line in study.findings().splitlines()[1:3])
    shooting = study.branch(method="shooting")
    end = shooting.amplitude[shooting.family_front()].max() / shooting.gap
    assert end < 1.5  # shooting's orbits leave mode 1 just above grazing (docs/shooting.md)
    assert f"another family above {end:.3g} gaps" in rows["shooting"]
    assert "another family" not in rows["mmshbm"]


@pytest.mark.slow
def test_the_35_run_study_prints_at_most_40_lines(tmp_path, capfd):
    """A grid of the size of the README's convergence grid (its seven H by five meshes, 35
    runs), as a user runs it (process pool): 39 lines on stdout, nothing on stderr (no
    warning lines, no raw warnings from the workers, whose every run has findings). The
    meshes are of 4-8 elements up to 1.5 gaps, not the README's 8-200 up to 5: the lines
    count the runs, not their size (13.8 s of processor time for the README's grid, 5.7 s
    for this one)."""
    argv = ["study", "-H", "1", "3", "5", "7", "9", "11", "15", "--elements", "4", "5", "6", "7", "8",
            "--max-amplitude", "1.5", "--amplitudes", "1.2", "--out", str(tmp_path)]
    assert main(argv) == 0
    out, err = capfd.readouterr()
    lines = out.splitlines()
    assert len(lines) == 35 + 4 <= 40
    assert lines[36].startswith("35 runs: 35 reached their bounds") and "with truncation effects" in lines[36]
    assert err == ""
