"""MMS-HBM on models as FE packages export them, through the contact layer:
the rigid limit of the layer, 10 gaps on the first-mode family, the CLI road."""

import numpy as np
import pytest
from shared_models import GAP, H_SEC, B, E, L

import mmshbm
from mmshbm.harmonic.modal_energy import kinetic_energy_shares

K_S = 3 * (E * B * H_SEC**3 / 12) / L**3  # static tip stiffness of the cantilever (N/m)
K_P = 1e3 * K_S  # NLvib's penalty spring


def mode_shares(branch, model, point, n_modes=4, n_samples=64):
    """Share of each linear mode in the period-mean kinetic energy at ``point``."""
    _, Phi = model.linear_modes(n_modes)
    _, q = branch.time_signals(point, None, n_samples)
    F = np.fft.rfft(q, axis=1) / n_samples * 2
    H = branch.harmonics
    Q = np.zeros((model.n_dof, 2 * H + 1))
    Q[:, 0] = F[:, 0].real / 2
    Q[:, 1::2] = F[:, 1:H + 1].real
    Q[:, 2::2] = -F[:, 1:H + 1].imag
    shares, _ = kinetic_energy_shares(Phi, None, Q, 2 * np.pi * branch.frequency[point], model.M)
    return shares.sum(axis=1)


def test_mms_hbm_runs_the_exported_model_to_10_gaps_on_the_first_mode_family(full_mass):
    """With the tip's mass kept and a contact layer k_p, MMS-HBM goes through the 5:1
    internal resonance with mode 2 (where mode 2 carries nearly all the kinetic energy) and
    comes back onto the first-mode family, up to 10 gaps."""
    model = full_mass.with_contact_layer(K_P)
    branch = mmshbm.backbone(model, harmonics=5, n_samples=1024)
    assert branch.status == "bound:amplitude" and branch.amplitude[-1] == pytest.approx(10 * GAP, rel=1e-9)
    f1, f_bilinear = model.linear_frequencies(1)[0], model.zero_gap_frequency()
    assert f1 < branch.frequency[-1] < f_bilinear  # measured 68.67 Hz in (45.12, 73.41)
    tongue = [mode_shares(branch, model, i)[1] for i in range(len(branch))]
    assert max(tongue) > 0.9  # inside the 5:1 tongue mode 2 dominates (measured 1.00)
    end = mode_shares(branch, model, len(branch) - 1)
    assert end[0] > 0.5 and end[0] == end.max()  # measured: mode 1 0.65, mode 2 0.35
    # MMS-HBM's own records: modal_shares summed over the harmonics, and mode_share (the
    # fundamental harmonic only, what decides family membership)
    assert branch.records["modal_shares"][-1][0].sum() == pytest.approx(end[0], abs=1e-9)
    assert 0.5 < branch.records["mode_share"][-1] <= end[0]
    # the tip (DOF 40, with mass) swings as far away from the stop as the massless node
    _, q = branch.time_signals(len(branch) - 1, [40, model.n_dof - 1], 4096)
    assert (-q[0]).max() == pytest.approx((-q[1]).max(), rel=1e-4)


def test_contact_layer_converges_to_the_rigid_limit_at_rate_one(full_mass):
    """The layer is a spring in series: the backbone at 1.5 gaps moves by k_s/k, so the
    differences between successive decades of k shrink tenfold (observed rate 1.00)."""
    factors = 10.0 ** np.arange(2, 7)
    f = []
    for factor in factors:
        branch = mmshbm.backbone(full_mass.with_contact_layer(factor * K_S), harmonics=5,
                                 max_amplitude=1.5 * GAP)
        assert branch.status == "bound:amplitude"
        f.append(branch.frequency[-1])
    steps = np.abs(np.diff(f))
    rates = -np.diff(np.log10(steps))
    np.testing.assert_allclose(rates, 1.0, atol=0.05)  # measured 0.977, 0.998, 1.000
    assert np.all(np.diff(f) > 0)  # stiffer contact, higher frequency
    # distance of the default (1e5 k_s) to the limit, by Richardson extrapolation: measured 6.8e-6
    f_limit = f[-1] + steps[-1] / 9
    default = mmshbm.backbone(full_mass.with_contact_layer(), harmonics=5, max_amplitude=1.5 * GAP)
    assert abs(default.frequency[-1] / f_limit - 1) < 1e-5


def test_mms_hbm_refuses_the_exported_model_and_names_the_conversions(full_mass):
    with pytest.raises(ValueError, match="with_contact_layer.*with_massless_contact"):
        mmshbm.backbone(full_mass, harmonics=5)
