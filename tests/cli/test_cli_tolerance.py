"""``mmshbm frf --tol``: the tolerance summary line, the files' error columns, bad input."""

import numpy as np
import pytest

from mmshbm.cli import main


@pytest.mark.parametrize("argv", [
    ["frf", "-H", "5", "--tol", "1e-3"],
    ["frf", "--max-harmonics", "16"],
])
def test_errors_are_one_line_exit_2(argv, tmp_path, capsys):
    assert main([*argv, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and ("--tol" in err or "either" in err)


def test_frf_tol_prints_the_summary_and_writes_the_errors(tmp_path, capsys):
    """Below grazing (40-44 Hz on the 8-element beam) the response is linear: met
    everywhere at the start H."""
    argv = ["frf", "--elements", "8", "--range", "40", "44", "--tol", "1e-3", "--out", str(tmp_path)]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "tolerance 0.001 met at every point of the response" in out
    table = np.genfromtxt(tmp_path / "frf.csv", delimiter=",", names=True)
    assert np.all(table["amplitude_error"] <= 1e-3) and np.all(table["harmonics"] == 8)
