"""Contact-layer stiffness from a measured backbone, on synthetic
measurements made with a known stiffness."""

import numpy as np
import pytest
from shared_models import GAP, H_SEC, B, E, L

import mmshbm
from mmshbm.analysis.contact_fit import backbone_frequencies
from mmshbm.analysis.identification import fit_contact_stiffness
from mmshbm.analysis.measured import MeasuredBackbone

K_S = 3 * (E * B * H_SEC**3 / 12) / L**3
K_TRUE = 150 * K_S  # a compliant contact element: 3.1e6 N/m
AMPLITUDES = np.linspace(1.2, 2.0, 9) * GAP  # above grazing, below the first corner


@pytest.fixture(scope="module")
def synthetic(full_mass):
    return backbone_frequencies(full_mass.with_contact_layer(K_TRUE), AMPLITUDES)


def test_frequencies_at_amplitudes_are_refined_not_interpolated(full_mass, synthetic):
    """Against the continuation's own refinement onto an amplitude bound (another code path)."""
    layered = full_mass.with_contact_layer(K_TRUE)
    for a, f in zip(AMPLITUDES[::4], synthetic[::4], strict=True):
        branch = mmshbm.backbone(layered, 5, max_amplitude=a)
        assert f == pytest.approx(branch.frequency[-1], rel=1e-9)  # measured 3e-11
    assert np.isnan(backbone_frequencies(layered, [1e-3 * 30], max_steps=20)[0])


def test_noise_free_measurement_gives_back_the_stiffness(full_mass, synthetic, tmp_path):
    path = tmp_path / "backbone.csv"
    np.savetxt(path, np.column_stack([synthetic, AMPLITUDES]), delimiter=",", header="frequency,amplitude",
               comments="")
    model, report = fit_contact_stiffness(full_mass, path)  # the start comes from the scan
    assert report.success and report.identifiable
    assert report.stiffness == pytest.approx(K_TRUE, rel=1e-6)  # measured 1.6e-9
    assert report.relative_std < 1e-6 and report.rms_relative_error < 1e-9
    assert model.description["contact_layer"]["stiffness"] == [report.stiffness]
    assert np.all(report.sensitivity > 0)  # a stiffer contact raises every frequency


def test_noisy_measurement_is_recovered_within_its_stated_uncertainty(full_mass, synthetic):
    """0.1 % frequency noise: k within 2σ, and σ what the known noise level predicts
    (σ_n/‖J‖, Gauss-Newton), up to the scatter of the residual estimate (m = 9).
    Monte Carlo over 40 noise draws (docs/fe_models.md): empirical std of ln k 0.138, mean
    stated σ 0.122 (σ_n/‖J‖ = 0.128), the 95 % interval holds k in 39 of 40."""
    noise = 1e-3
    rng = np.random.default_rng(7)
    measured = MeasuredBackbone.from_arrays(synthetic * (1 + noise * rng.standard_normal(len(synthetic))),
                                            AMPLITUDES)
    _, report = fit_contact_stiffness(full_mass, measured, initial=1e3 * K_S)
    assert report.success and report.identifiable
    err = abs(np.log(report.stiffness / K_TRUE))
    assert err <= 2 * report.relative_std
    lo, hi = report.interval
    assert lo < K_TRUE < hi
    predicted = noise / np.linalg.norm(report.sensitivity)
    assert 0.5 < report.relative_std / predicted < 2.0
    assert report.rms_relative_error == pytest.approx(noise, rel=0.6)


def test_a_nearly_rigid_contact_is_only_a_lower_bound(full_mass):
    f = backbone_frequencies(full_mass.with_contact_layer(1e7 * K_S), AMPLITUDES[:3])
    rng = np.random.default_rng(3)
    measured = MeasuredBackbone.from_arrays(f * (1 + 1e-3 * rng.standard_normal(3)), AMPLITUDES[:3])
    _, report = fit_contact_stiffness(full_mass, measured, initial=1e6 * K_S, max_iterations=2)
    assert not report.identifiable and report.relative_std > 1
    assert any("lower bound" in n or "hardly depends on k" in n for n in report.notes)


def test_bad_input_is_named(full_mass, synthetic):
    measured = MeasuredBackbone.from_arrays(synthetic, AMPLITUDES)
    with pytest.raises(ValueError, match="is massless"):
        fit_contact_stiffness(mmshbm.default_beam().model(8), measured)
    below = MeasuredBackbone.from_arrays([45.0, 45.1], [0.5e-3, 0.9e-3])
    with pytest.raises(ValueError, match="no measured point .* lies above the gap"):
        fit_contact_stiffness(full_mass, below)
    with pytest.raises(ValueError, match="initial must be positive"):
        fit_contact_stiffness(full_mass, measured, initial=-1.0)
    with pytest.raises(ValueError, match="amplitude_range"):
        fit_contact_stiffness(full_mass, measured, amplitude_range=(2e-3, 1e-3))
