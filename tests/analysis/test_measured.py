"""Measured backbone CSV files: formats, units, errors, overlay."""

import numpy as np
import pytest

import mmshbm
from mmshbm.analysis.measured import MeasuredBackbone, load_measured


def _write(tmp_path, text, name="m.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_minimal_file(tmp_path):
    m = load_measured(_write(tmp_path, "frequency,amplitude\n46.0,0.0005\n55.5,0.002\n"))
    np.testing.assert_array_equal(m.frequency, [46.0, 55.5])
    np.testing.assert_array_equal(m.amplitude, [0.0005, 0.002])
    assert m.contact_force is None and len(m) == 2 and m.source == "m.csv"


def test_units_comments_separators_and_force(tmp_path):
    text = ("# PLL run 3\n\nfrequency [Hz];amplitude (m);contact_force_N;operator\n"
            "50;0.001;12.5;ab\n56;0.003;;cd\n")
    m = load_measured(_write(tmp_path, text))
    np.testing.assert_array_equal(m.frequency, [50.0, 56.0])
    assert m.contact_force[0] == 12.5 and np.isnan(m.contact_force[1])


def test_branch_csv_is_a_measured_file(tmp_path):
    b = mmshbm.backbone(mmshbm.OneDofOscillator().model(), harmonics=3, max_amplitude=2.0)
    m = load_measured(b.to_csv(tmp_path / "b.csv"))
    np.testing.assert_array_equal(m.frequency, b.frequency)
    np.testing.assert_array_equal(m.contact_force, b.contact_force_max)


@pytest.mark.parametrize("text, match", [
    ("", "empty"),
    ("frequency,amplitude\n", "no data"),
    ("frequency,force\n1,2\n", "lacks"),
    ("frequency_hz,amplitude_mm\n50,1\n", "'mm'"),
    ("frequency,amplitude\n50,abc\n", "line 2"),
    ("frequency,amplitude\n50\n", "fields"),
    ("frequency,amplitude\n-5,0.001\n", "> 0"),
    ("frequency,amplitude\n5,-0.001\n", ">= 0"),
    ("frequency,amplitude\n5,inf\n", "finite"),
    ("frequency,frequency,amplitude\n5,5,1\n", "twice"),
])
def test_errors_name_file_and_line(tmp_path, text, match):
    with pytest.raises(ValueError, match=match):
        load_measured(_write(tmp_path, text))
    with pytest.raises(ValueError, match="cannot read"):
        load_measured(tmp_path / "missing.csv")


def test_from_arrays_checks():
    with pytest.raises(ValueError):
        MeasuredBackbone.from_arrays([1.0, 2.0], [0.1])
    with pytest.raises(ValueError):
        MeasuredBackbone.from_arrays([1.0], [0.1], contact_force=[1.0, 2.0])


def test_overlay_from_path(tmp_path):
    from mmshbm.plotting import plot_backbone

    b = mmshbm.backbone(mmshbm.OneDofOscillator().model(), harmonics=3, max_amplitude=2.0)
    path = _write(tmp_path, "frequency,amplitude\n0.17,1.5\n0.18,1.8\n")
    fig = plot_backbone(b, measured=path, reference_lines=False)
    meas = [ln for ln in fig.axes[0].get_lines() if ln.get_label().startswith("measured")]
    assert len(meas) == 1
    np.testing.assert_allclose(meas[0].get_ydata(), [1.5, 1.8])  # gap = 1 m


def test_peak_force_overlay(tmp_path):
    from mmshbm.plotting import plot_peak_contact_force

    b = mmshbm.backbone(mmshbm.OneDofOscillator().model(), harmonics=3, max_amplitude=2.0)
    path = _write(tmp_path, "frequency,amplitude,contact_force\n0.17,1.5,0.4\n0.18,1.8,\n")
    fig = plot_peak_contact_force(b, measured=path, path=tmp_path / "p.png")
    model_line, meas = fig.axes[0].get_lines()
    np.testing.assert_array_equal(model_line.get_ydata(), b.contact_force_max)
    np.testing.assert_array_equal(meas.get_ydata(), [0.4, np.nan])
