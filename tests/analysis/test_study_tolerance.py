"""Studies with a tolerance: the plumbing of ``tol`` to every run, the H of each cell, and
the mesh errors of a table (mmshbm.analysis.study_tolerance)."""

import warnings

import numpy as np

import mmshbm
from mmshbm.analysis.studies import run_study
from mmshbm.analysis.study_tolerance import (
    cell_harmonics,
    mesh_error_lines,
    study_mesh_errors,
    tolerance_lines,
)
from mmshbm.analysis.tables import FrequencyTable


def test_tol_reaches_every_run_and_the_cells_say_their_H():
    """Oscillator k2/k1 = 4: below grazing (0.5 gap) H stays at the start; above it (2
    gaps) the run started at H = 4 was raised; every run met the tolerance."""
    model = mmshbm.OneDofOscillator(m=1.0, k1=1.0, k2=4.0, gap=1.0).model()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        study = run_study(model=model, harmonics=(4, 8), tol=1e-4, max_amplitude=3.0, unit="gap",
                          executor="serial")
    for coords, b in zip(study.runs, study.branches, strict=True):
        assert b.metadata["tolerance"]["tol"] == 1e-4
        assert b.metadata["tolerance"]["start_harmonics"] == coords["harmonics"]
    H = cell_harmonics(study, [0.5, 2.0], "gap")
    assert H[0, 0] == 4 and H[1, 0] == 8 and H[0, 1] > 4 and H[1, 1] >= 8
    lines = tolerance_lines(study)
    assert lines[0] == "tolerance met at every point in 2 of 2 runs"


def _table(elements, freqs, amplitudes=(1.0, 2.0)):
    runs = [{"method": "mmshbm", "elements": n, "harmonics": 5} for n in elements]
    return FrequencyTable(axes=["method", "elements", "harmonics"], runs=runs,
                          amplitudes=np.asarray(amplitudes, dtype=float), unit="gap",
                          frequency=np.asarray(freqs, dtype=float), status=["complete"] * len(runs))


def test_mesh_errors_of_a_table():
    """f(n) = 50 + 30 n^-2 at the first amplitude (asymptotic, limit 50), oscillating at the
    second (not monotone)."""
    n = (8, 16, 32)
    freqs = [[50 + 30 * k ** -2.0, s] for k, s in zip(n, (50.0, 50.2, 50.1), strict=True)]
    out = study_mesh_errors(_table(n, freqs))
    assert [a for _, a, _ in out] == [1.0, 2.0]
    (c0, _, first), (_, _, second) = out
    assert c0 == {"method": "mmshbm", "harmonics": 5}
    assert first.asymptotic and abs(first.extrapolated - 50) < 1e-10
    lines = mesh_error_lines(_table(n, freqs))
    assert "mesh error of the 32-element run" in lines[0] and "not monotone" in lines[1]
    assert study_mesh_errors(_table((8, 16), freqs[:2])) == []
