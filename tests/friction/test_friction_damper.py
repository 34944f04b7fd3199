"""The beam with a friction damper on its tip (fe/damper) and the optimal-normal-load study
(analysis/friction_study): the study's limits against the linear closed forms of the
Jenkins oscillator, the model's layout, the command line."""

import numpy as np
import pytest

import mmshbm
from mmshbm.analysis.friction_study import normal_load_study
from mmshbm.cli import main

M_, K1, K2, C_, F_ = 1.0, 1.0, 2.0, 0.05, 0.1


def jenkins(normal_load, mu=0.5):
    """Mass m on spring k1 to ground and spring k2 to a massless node with Coulomb friction."""
    M = np.diag([M_, 0.0])
    K = np.array([[K1 + K2, -K2], [-K2, K2]])
    base = mmshbm.Model.from_matrices(M, K, [], [], [], damping=np.diag([C_, 0.0]), amplitude_dof=0)
    return base.with_friction(1, mu, normal_load=normal_load)


def linear_peak(k):
    """Resonance amplitude (m) and frequency (Hz) of m x'' + c x' + k x = F cos Ωt."""
    zeta = C_ / (2 * np.sqrt(k * M_))
    f_peak = np.sqrt(k / M_) * np.sqrt(1 - 2 * zeta**2) / (2 * np.pi)
    return F_ / (k * 2 * zeta * np.sqrt(1 - zeta**2)), f_peak


def test_the_study_meets_the_free_and_stuck_closed_forms_and_finds_an_interior_optimum():
    """N = 0 is the free structure (k1), N = 1000 N sticks throughout (k1 + k2): their peaks
    are linear closed forms. The search stops within xtol = 1e-5 of the peak frequency; the
    amplitude's relative error is then about (δf/f)²/(2ζ²) <= (1e-5)²/(2 · 0.0144²) = 2.4e-7,
    asserted at 2e-6. In between friction damps both: the curve has an interior minimum."""
    study = normal_load_study(jenkins, [0.0, 0.05, 0.1, 0.2, 0.4, 1000.0], [F_, 0.0], (0.08, 0.5),
                              harmonics=15, n_grid=40)
    assert study.converged.all()
    for i, k in ((0, K1), (-1, K1 + K2)):
        a, f = linear_peak(k)
        assert study.peak_amplitude[i] == pytest.approx(a, rel=2e-6)
        assert study.peak_frequency[i] == pytest.approx(f, rel=2e-3)
    n_opt, a_opt = study.optimum
    assert 0.0 < n_opt < 1000.0
    assert a_opt < 0.5 * min(study.peak_amplitude[0], study.peak_amplitude[-1])
    assert "optimum" in study.to_text()


def test_the_tip_damper_model():
    beam = mmshbm.default_beam()
    model = mmshbm.tip_damper_model(n_elements=8, mu=0.3, normal_load=2.0)
    tip, _ = beam.tip_dofs(8)
    assert model.contacts == () and len(model.friction) == 1
    fc = model.friction[0]
    assert (fc.dof, fc.mu, fc.normal_load) == (tip, 0.3, 2.0)
    assert model.amplitude_dof == tip - 2
    assert model.M[tip, tip] == 0 and model.M[tip - 2, tip - 2] > 0
    np.testing.assert_array_equal(model.K.toarray(), beam.model(8).K.toarray())
    x = beam.node_coordinates(8)
    mid = mmshbm.tip_damper_model(n_elements=8, at=0.5)
    node = mid.amplitude_dof // 2 + 1
    assert abs(x[node] / x[-1] - 0.5) == pytest.approx(np.min(np.abs(x[1:-1] / x[-1] - 0.5)))
    force = mmshbm.tip_damper_force(mid, 2.0)
    assert force[mid.amplitude_dof] == 2.0 and np.count_nonzero(force) == 1
    for bad in ({"at": 1.0}, {"modal_damping": -0.1}, {"normal_load": -1.0}, {"mu": -0.5}):
        with pytest.raises(ValueError, match=next(iter(bad))):
            mmshbm.tip_damper_model(n_elements=8, **bad)


def test_normal_load_study_on_the_command_line(tmp_path, capsys):
    args = ["study", "--param", "normal_load=0,0.5", "--param", "band=40,60", "--elements", "4", "-H", "3",
            "--workers", "1", "--out", str(tmp_path)]
    assert main(args) == 0
    assert "optimum" in capsys.readouterr().out
    table = np.loadtxt(tmp_path / "normal_load.csv", delimiter=",", skiprows=1)
    assert table.shape == (2, 6)
    assert table[1, 1] < table[0, 1]  # the damper lowers the peak
    assert (tmp_path / "normal_load.png").stat().st_size > 0
    assert main(["study", "--param", "normal_load=1", "--param", "gap=0.001", "--out", str(tmp_path)]) != 0
    assert "normal_load, mu, at, band and force" in capsys.readouterr().err
