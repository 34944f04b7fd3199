"""fit_material: round trips on synthetic frequencies of beams with known E and rho."""

from dataclasses import replace

import numpy as np
import pytest

import mmshbm
from mmshbm.analysis.identification import beam_frequencies, fit_material

BEAM = mmshbm.default_beam()
TRUE = replace(BEAM, E=195e9, rho=7700.0)


@pytest.fixture(scope="module")
def measured():
    return beam_frequencies(TRUE, 21, 3)


def test_round_trip_E_and_rho_with_mass(measured):
    mass = TRUE.rho * TRUE.area * TRUE.length
    fitted, report = mmshbm.fit_material(BEAM, measured, fit=("E", "rho"), mass=mass)
    assert fitted.E == pytest.approx(195e9, rel=1e-8)
    assert fitted.rho == pytest.approx(7700.0, rel=1e-8)
    assert report.identifiable and report.success
    assert report.rms_relative_error < 1e-9
    np.testing.assert_allclose(report.frequencies, measured, rtol=1e-9)
    assert (fitted.length, fitted.nu, fitted.gap) == (BEAM.length, BEAM.nu, BEAM.gap)


def test_round_trip_E_with_known_density(measured):
    start = replace(BEAM, rho=TRUE.rho)
    fitted, report = fit_material(start, measured)
    assert fitted.E == pytest.approx(TRUE.E, rel=1e-8) and fitted.rho == TRUE.rho
    assert report.parameters == ("E",) and report.condition_number == pytest.approx(1.0, rel=1e-6)


def test_frequencies_alone_fix_only_the_ratio(measured):
    """K ∝ E and M ∝ rho exactly: without the mass the fit matches the frequencies, finds
    E/rho, and says the split is not identifiable."""
    fitted, report = fit_material(BEAM, measured, fit=("E", "rho"))
    assert report.ratio == pytest.approx(TRUE.E / TRUE.rho, rel=1e-8)
    assert not report.identifiable and report.notes
    np.testing.assert_allclose(report.frequencies, measured, rtol=1e-9)


def test_selected_modes_and_noise():
    f = beam_frequencies(TRUE, 8, 3)[[0, 2]] * np.array([1.001, 0.999])
    fitted, report = fit_material(replace(BEAM, rho=TRUE.rho), f, n_elements=8, modes=[1, 3])
    assert list(report.modes) == [1, 3]
    # least squares in log: the two 0.1 % errors cancel in E to first order (E ∝ f²)
    assert fitted.E == pytest.approx(TRUE.E, rel=3e-6)
    np.testing.assert_allclose(np.abs(report.relative_residuals), 1e-3, rtol=1e-2)
    assert "modes 1, 3" in report.summary()


@pytest.mark.parametrize("kwargs, error", [
    ({"measured_frequencies": [-1.0]}, ValueError),
    ({"measured_frequencies": [np.nan]}, ValueError),
    ({"measured_frequencies": []}, ValueError),
    ({"measured_frequencies": [40.0], "modes": [0]}, ValueError),
    ({"measured_frequencies": [40.0, 50.0], "modes": [1, 1]}, ValueError),
    ({"measured_frequencies": [40.0], "fit": ("nu",)}, ValueError),
    ({"measured_frequencies": [40.0], "mass": -1.0}, ValueError),
])
def test_bad_input(kwargs, error):
    with pytest.raises(error):
        fit_material(BEAM, **kwargs)
    with pytest.raises(TypeError):
        fit_material("beam", [40.0])
