"""Phase resonance, damped-mode plots, the ``frf`` command, and damping against the
internal-resonance tongues."""

from __future__ import annotations

import numpy as np
import pytest
from finite_differences import assert_jacobian

import mmshbm
from mmshbm.analysis.phase_resonance import compare_backbones, phase_resonance_backbone
from mmshbm.cli import main
from mmshbm.methods.mms.phase_resonance import PhaseResonanceProblem
from mmshbm.plotting.response import (
    plot_damping_ratio,
    plot_frequency_response,
    plot_phase_resonance,
    stability_runs,
)
from mmshbm.results.response import FrequencyResponse

ZETA = 0.02


@pytest.fixture(scope="module")
def osc():
    return mmshbm.OneDofOscillator(1, 1, 4, 1).model().with_damping(modal_ratio=ZETA)


def test_phase_resonance_of_the_oscillator(osc):
    b = phase_resonance_backbone(osc, [1.0, 0.0], harmonics=10, max_amplitude=4.0)
    assert b.method == "phase_resonance" and b.completed
    np.testing.assert_allclose(b.records["phase"], np.pi / 2, atol=1e-9)
    # linear regime: the force that holds amplitude A at resonance is 2 ζ k A (k = 1, ω = 1)
    assert b.records["force"][0] == pytest.approx(2 * ZETA * b.amplitude[0], rel=1e-9)
    assert b.frequency[0] == pytest.approx(1 / (2 * np.pi), rel=1e-10)
    # the stop stiffens it: frequency and force grow with the amplitude
    assert np.all(np.diff(b.frequency[b.amplitude > 1.01]) > 0)
    p = PhaseResonanceProblem(osc, [1.0, 0.0], harmonics=4)
    rng = np.random.default_rng(5)
    u = p.linear_point(0.5)
    u[:-2] += 0.3 * rng.standard_normal(len(u) - 2)
    u[p.n_c + p.contact_rows[0]] += 2.0
    R, J = p.evaluate(u)
    assert_jacobian(lambda v: p.evaluate(v, False), u, J, 1e-5)
    with pytest.raises(ValueError, match="needs a damped model"):
        phase_resonance_backbone(mmshbm.OneDofOscillator().model(), [1.0, 0.0])


def test_three_backbones_of_the_oscillator():
    """Points refined onto equal amplitudes: with C = 2ζω M (one DOF) the EPMC's ξ cancels the
    damping exactly, so the damped mode is the conservative one; the phase-resonance backbone
    differs by O(ζ²) (measured −1.9e-5 at ζ = 0.02, −1.9e-7 at ζ = 0.002)."""
    undamped = mmshbm.OneDofOscillator(1, 1, 4, 1).model().with_damping(modal_ratio=0.0)
    gaps = {}
    for zeta in (0.02, 0.002):
        m = mmshbm.OneDofOscillator(1, 1, 4, 1).model().with_damping(modal_ratio=zeta)
        A = 3.0
        fc = mmshbm.backbone(undamped, harmonics=10, max_amplitude=A).frequency[-1]
        fe = mmshbm.backbone(m, harmonics=10, max_amplitude=A).frequency[-1]
        fp = phase_resonance_backbone(m, [1.0, 0.0], harmonics=10, max_amplitude=A).frequency[-1]
        assert fe == pytest.approx(fc, rel=1e-12)
        gaps[zeta] = fp / fc - 1
    assert 50 < gaps[0.02] / gaps[0.002] < 200 and abs(gaps[0.002]) < 1e-6


def test_compare_backbones_returns_the_three(osc):
    c = compare_backbones(osc, [1.0, 0.0], harmonics=6, max_amplitude=3.0, amplitudes=[1.5, 2.5])
    assert {b.method for k, b in c.items() if k in ("conservative", "epmc", "phase_resonance")} == {
        "mmshbm", "epmc", "phase_resonance"}
    assert all(np.all(np.isfinite(v)) and v.shape == (2,) for v in c["table"].values())


def test_plots(osc, tmp_path):
    r = mmshbm.frequency_response(osc, [0.1, 0.0], (0.1, 0.3), harmonics=8)
    assert stability_runs(np.array([1, 1, 0, 0, 1], bool)) == [(0, 3, True), (2, 5, False), (4, 5, True)]
    epmc = mmshbm.backbone(osc, harmonics=8, max_amplitude=3.0)
    fig = plot_frequency_response(r, backbone=epmc, marks="all", path=tmp_path / "frf.png")
    ax = fig.axes[0]
    styles = {line.get_linestyle() for line in ax.get_lines()}
    assert "--" in styles and "-" in styles  # unstable parts dashed
    assert (tmp_path / "frf.png").stat().st_size > 0
    pr = phase_resonance_backbone(osc, [1.0, 0.0], harmonics=8, max_amplitude=3.0)
    measured = tmp_path / "m.csv"
    measured.write_text("frequency_hz,amplitude_m\n0.17,1.2\n0.19,2.0\n")
    plot_phase_resonance(pr, epmc, mmshbm.backbone(mmshbm.OneDofOscillator().model(), harmonics=8,
                                                    max_amplitude=3.0), measured=measured,
                         path=tmp_path / "pr.png")
    plot_damping_ratio(epmc, path=tmp_path / "d.png")
    assert (tmp_path / "pr.png").stat().st_size > 0 and (tmp_path / "d.png").stat().st_size > 0


def test_frf_command(tmp_path, capsys):
    out = tmp_path / "o"
    code = main(["frf", "--elements", "4", "-H", "3", "--force", "0.5", "--range", "40", "70",
                 "--out", str(out)])
    assert code == 0
    r = FrequencyResponse.load(out / "frf.npz")
    assert r.completed and r.harmonics == 3 and r.metadata["model"]["n_elements"] == 4
    assert r.get_model().damping is not None
    for name in ("frf.csv", "frf.png"):
        assert (out / name).stat().st_size > 0
    assert main(["frf", "--range", "60", "40", "--out", str(out)]) == 2
    assert "empty or inverted" in capsys.readouterr().err
    assert main(["frf", "--damping", "-0.1", "--out", str(out)]) == 2
    assert "argument --damping: must be a finite number >= 0" in capsys.readouterr().err  # the option itself


def test_damping_of_the_higher_modes_removes_the_tongues():
    """Conservative H = 7 on the default beam, plainly path-followed, is captured by the 6:1
    tongue (kΩ ≈ f2) below 1.4 gaps (the default family following jumps it instead); the
    damped mode with the higher modes damped passes it by itself and reaches 10 gaps."""
    beam = mmshbm.default_beam().model(21)
    cons = mmshbm.backbone(beam, harmonics=7, max_steps=150, follow="path")
    f2 = beam.linear_frequencies(2)[1]
    # captured: it ends off the first-mode family, locked near f2/6 (it loops there, or
    # climbs the tongue as mode 2's own nonlinear mode)
    assert cons.records["mode_share"][-1] < 0.5 and abs(6 * cons.frequency[-1] / f2 - 1) < 0.03
    damped = beam.with_damping(modal_ratio=[0.005] + [0.05] * (len(beam.l) - 1))
    b = mmshbm.backbone(damped, harmonics=7)
    assert b.status == "bound:amplitude" and 65 < b.frequency[-1] < 72
    assert b.damping_ratio[0] == pytest.approx(0.005, rel=1e-10)
