"""What a new user meets on the first day: answers outside a branch, models the methods
cannot run, messages in the units the user typed, resumed runs with other settings,
swapped matrices, failed starts, progress in a log, figures that say what they show."""

import re
import warnings

import numpy as np
import pytest

import mmshbm
from mmshbm import BranchWarning


@pytest.fixture(scope="module")
def oscillator_branch():
    """The 1-DOF impact oscillator's backbone up to 3 gaps (gap 1 m), H = 5."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BranchWarning)
        return mmshbm.backbone(mmshbm.one_dof_oscillator(), harmonics=5, max_amplitude=3.0)


# ---------------------------------------------------------------------- a. solve_at outside the branch
def test_solve_at_beyond_the_branch_is_nan_and_warns_as_frequency_at(oscillator_branch):
    b = oscillator_branch
    assert b.amplitude[b.family_front()].max() == pytest.approx(3.0, rel=1e-9)
    with pytest.warns(BranchWarning, match="outside the amplitude range"):
        assert np.isnan(b.frequency_at(50, unit="gap"))
    with pytest.warns(BranchWarning, match=r"50 m \(50 gaps\) outside the amplitude range.*0\.5 m.*3 m"):
        points = b.solve_at([50, 2], unit="gap")
    assert points.records["solved"].tolist() == [0, 1]
    assert np.isnan(points.frequency[0]) and np.isnan(points.amplitude[0])
    assert np.isnan(points.states[0]).all()
    # the solved entry is the pinned solve frequency_at makes (same computation, Newton tolerance)
    assert points.amplitude[1] == pytest.approx(2.0, rel=1e-8)
    assert points.frequency[1] == pytest.approx(b.frequency_at(2, unit="gap"), rel=1e-9)


def test_solve_at_inside_the_branch_does_not_warn(oscillator_branch):
    with warnings.catch_warnings():
        warnings.simplefilter("error", BranchWarning)
        points = oscillator_branch.solve_at([1.5, 2.5], unit="gap")
    assert points.records["solved"].tolist() == [1, 1]


def test_solve_at_with_stand_in_marks_the_nearest_front_point(oscillator_branch):
    b = oscillator_branch
    with warnings.catch_warnings():
        warnings.simplefilter("error", BranchWarning)
        points = b.solve_at([50], unit="gap", stand_in=True)
    assert points.records["solved"].tolist() == [0]
    assert points.amplitude[0] == pytest.approx(b.amplitude[b.family_front()[-1]], rel=1e-9)


# ---------------------------------------------------------------------- b. a model without contacts
def _linear_chain():
    """Two masses and a massless node on springs, with no stop and no friction."""
    M = np.diag([1.0, 1.0, 0.0])
    K = np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]])
    return mmshbm.Model.from_matrices(M, K, contact_dof=[], gap=[], stop_side=[], amplitude_dof=0)


@pytest.mark.parametrize("method", ["mmshbm", "penalty", "shooting"])
@pytest.mark.parametrize("max_amplitude", [None, 0.1])
def test_backbone_of_a_model_without_contact_says_so(method, max_amplitude):
    with pytest.raises(ValueError, match="no contact.*backbone of a linear model is its linear mode"):
        mmshbm.backbone(_linear_chain(), method=method, max_amplitude=max_amplitude)


@pytest.mark.parametrize("method", ["mmshbm", "penalty"])
def test_forced_response_of_a_model_without_contact_says_so(method):
    model = _linear_chain().with_damping(modal_ratio=0.01)
    with pytest.raises(ValueError, match="no contact.*forced response of a linear model is linear"):
        mmshbm.frequency_response(model, [1.0, 0.0, 0.0], (0.1, 0.3), method=method)


# ---------------------------------------------------------------------- c. amplitudes in the user's units
def test_a_max_amplitude_below_the_default_start_starts_below_it():
    model = mmshbm.one_dof_oscillator(gap=2.0)  # the mass on k1 = 1 N/m while the contact is open
    branch = mmshbm.backbone(model, harmonics=3, max_amplitude=0.45 * model.gap)
    assert branch.status == "bound:amplitude"
    assert branch.metadata["start_amplitude"] < 0.45 * model.gap
    assert branch.amplitude[-1] == pytest.approx(0.45 * model.gap, rel=1e-9)
    # below the gap the backbone is the linear mode, sqrt(k1/m)/(2π) Hz (to the Newton tolerance)
    np.testing.assert_allclose(branch.frequency, 1 / (2 * np.pi), rtol=1e-9)


def test_a_start_above_max_is_refused_in_metres_and_gaps():
    model = mmshbm.one_dof_oscillator(gap=2.0)
    message = (r"start_amplitude \(1\.2 m = 0\.6 gaps\) must be below max_amplitude \(1 m = 0\.5 gaps\): "
               "lower start_amplitude or raise max_amplitude")
    with pytest.raises(ValueError, match=message):
        mmshbm.backbone(model, max_amplitude=1.0, start_amplitude=1.2)


def test_cli_backbone_with_a_max_amplitude_below_half_a_gap(tmp_path, capsys):
    from mmshbm.cli import main

    path = tmp_path / "oscillator.npz"
    mmshbm.one_dof_oscillator(gap=2.0).save_npz(path)
    code = main(["backbone", "--model-file", str(path), "-H", "3", "--max-amplitude", "0.4", "--out",
                 str(tmp_path)])
    assert code == 0, capsys.readouterr().err
    amplitude = np.loadtxt(tmp_path / "backbone.csv", delimiter=",", skiprows=1)[:, 1]
    assert amplitude[-1] == pytest.approx(0.4 * 2.0, rel=1e-9)


def test_cli_max_amplitude_in_gaps_of_a_model_without_gap(tmp_path, capsys):
    from mmshbm.cli import main

    model = _linear_chain().with_friction(2, 0.3, normal_load=1.0)
    path = tmp_path / "friction.npz"
    model.save_npz(path)
    assert main(["backbone", "--model-file", str(path), "--max-amplitude", "2", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "--max-amplitude is in gaps, and this model has no stop with a positive gap" in err


# ---------------------------------------------------------------------- d. resuming with other settings
def test_resume_with_another_h_names_h(tmp_path):
    model = mmshbm.one_dof_oscillator()
    path = tmp_path / "osc.ckpt"
    mmshbm.backbone(model, harmonics=5, max_steps=3, checkpoint=path)
    with pytest.raises(ValueError, match=r"harmonics \(H\): file 5, now 8; the number of unknowns: file 8, "
                                         r"now 11; resume with the file's settings"):
        mmshbm.backbone(model, harmonics=8, n_samples=128, resume=path)
    # every setting that differs, not the first only (N follows H by default)
    with pytest.raises(ValueError, match=r"harmonics \(H\): file 5, now 15; n_samples \(N\): file 128, "
                                         "now 256"):
        mmshbm.backbone(model, harmonics=15, resume=path)


# ---------------------------------------------------------------------- e. M and K swapped
def test_swapped_mass_and_stiffness_are_named():
    beam = mmshbm.default_beam().model(4)
    massless = beam.c.tolist()  # the tip node's deflection and rotation
    message = re.escape(f"K is zero on the rows of DOFs {massless}, where M is not") + ".*may be swapped"
    with pytest.raises(ValueError, match=message):
        mmshbm.Model.from_matrices(beam.K, beam.M, beam.contact_dof, beam.gap)
    M = np.diag([1.0, 0.0])
    K = np.array([[5.0, -4.0], [-4.0, 4.0]])
    with pytest.raises(ValueError, match=r"DOFs \[1\], where M is not.*M has 0 zero row.*may be swapped"):
        mmshbm.Model.from_matrices(K, M, 1, 1.0)
    assert mmshbm.Model.from_matrices(M, K, 1, 1.0).c.tolist() == [1]  # the right order is accepted


# ---------------------------------------------------------------------- f. a forced start in contact
@pytest.fixture(scope="module")
def beam_in_contact_at_44_hz():
    """The default beam (21 elements), 0.5 % modal damping, 2.3 N at the last node with
    mass: at 44 Hz its linear response passes the stop (1.36 gaps at the tip)."""
    model = mmshbm.default_beam().model(21).with_damping(modal_ratio=0.005)
    force = np.zeros(model.n_dof)
    force[int(model.l[model.l < model.amplitude_dof][-2])] = 2.3
    return model, force


def test_penalty_forced_response_starts_in_contact(beam_in_contact_at_44_hz):
    """The start at 44 Hz failed at every H and N (the linear response is 1.36 gaps there,
    not aliasing); continued in force level from below the stop it converges, onto the
    response MMS-HBM starts on, to the penalty error (k_p = 10³ k_c)."""
    model, force = beam_in_contact_at_44_hz
    from mmshbm.methods.penalty.forced import PenaltyForcedProblem

    linear = PenaltyForcedProblem(model, force, harmonics=5)
    assert linear.monitor(linear.linear_response_point(44.0))["amplitude"] > 1.3 * model.gap
    pen = mmshbm.frequency_response(model, force, (44.0, 60.0), harmonics=5, method="penalty", max_steps=2)
    mms = mmshbm.frequency_response(model, force, (44.0, 60.0), harmonics=5, max_steps=2, stability=False)
    assert pen.status == "max_steps" and len(pen) == 3
    assert pen.frequency[0] == pytest.approx(44.0, rel=1e-9) and pen.contact_force_max[0] > 0
    # both in contact at 44 Hz; penalty-HBM is softer by its penetration, of order k_c/k_p of the force
    assert pen.amplitude[0] == pytest.approx(mms.amplitude[0], rel=0.05)


def test_a_failed_forced_start_warns_with_its_status(beam_in_contact_at_44_hz):
    model, force = beam_in_contact_at_44_hz
    message = (r"shooting frequency response is empty: its first point at 44 Hz did not converge \(.*\); "
               r"the linear response there swings 1\.36 gaps, past the stop")
    with pytest.warns(BranchWarning, match=message):
        resp = mmshbm.frequency_response(model, force, (44.0, 60.0), method="shooting", max_steps=2)
    assert len(resp) == 0 and not resp.completed
    assert resp.status.startswith("start failed")


# ---------------------------------------------------------------------- g. progress in a pipe
def test_verbose_backbone_writes_progress_lines_when_stderr_is_not_a_terminal(monkeypatch, capsys):
    import mmshbm._progress as progress

    monkeypatch.setattr(progress, "LINE_INTERVAL_S", 0.0)  # a line per point
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BranchWarning)
        branch = mmshbm.backbone(mmshbm.one_dof_oscillator(), harmonics=3, max_amplitude=2.0, verbose=True)
    lines = capsys.readouterr().err.splitlines()
    points = [line for line in lines if line.startswith("mmshbm backbone: ")]
    assert len(points) == len(branch) + 1  # one per point and the last
    assert points[0].startswith("mmshbm backbone: 0.5/2 gap, 0.1592 Hz, 1 points [")
    last = f"mmshbm backbone: 2/2 gap, {branch.frequency[-1]:.4g} Hz, {len(branch)} points, done ["
    assert points[-1].startswith(last)


def test_line_progress_writes_at_most_one_line_per_interval():
    import io

    from mmshbm._progress import LineProgress

    out = io.StringIO()
    bar = LineProgress("study", unit="run", total=40, file=out, interval=3600.0)
    for k in range(40):
        bar.set_postfix_str(f"run {k}", refresh=False)
        bar.update(1)
    bar.close()
    bar.close()
    lines = out.getvalue().splitlines()
    assert len(lines) == 2
    assert lines[0].startswith("study: 1/40 run, run 0 [")
    assert lines[1].startswith("study: 40/40 run, run 39, done [")


def test_verbose_forced_response_writes_progress_lines(monkeypatch, capsys):
    import mmshbm._progress as progress

    monkeypatch.setattr(progress, "LINE_INTERVAL_S", 0.0)
    model = mmshbm.one_dof_oscillator().with_damping(modal_ratio=0.02)
    resp = mmshbm.frequency_response(model, [0.1, 0.0], (0.1, 0.12), harmonics=3, verbose=True)
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.startswith("mmshbm frequency response")]
    assert len(lines) == len(resp) + 1 and lines[0].startswith("mmshbm frequency response: 1 pt, 0.1 Hz, ")


# ---------------------------------------------------------------------- h. figures that say what they show
def test_frf_plot_names_its_dof_and_measure():
    from mmshbm.plotting.response import plot_frequency_response

    model = mmshbm.default_beam().model(4).with_damping(modal_ratio=0.005)
    force = np.zeros(model.n_dof)
    force[4] = 2.3  # the deflection of the last node with mass
    resp = mmshbm.frequency_response(model, force, (40.0, 41.0), harmonics=3, stability=False)
    ax = plot_frequency_response(resp).axes[0]
    tip = 2 * 4 - 2  # the tip node's deflection w, the 4-element beam's contact DOF
    assert ax.get_title() == f"forced response at DOF {tip} (tip deflection w)"
    assert ax.get_ylabel() == "tip amplitude: max |q| over a period / gap"
    assert plot_frequency_response(resp, title="mine").axes[0].get_title() == "mine"


def test_frequency_energy_plot_has_a_title(oscillator_branch):
    from mmshbm import plotting
    from mmshbm.plotting.data import BranchData

    for shown in (oscillator_branch, BranchData.of(oscillator_branch)):  # the CLI draws BranchData
        assert plotting.plot_frequency_energy(shown).axes[0].get_title() == (
            "frequency–energy plot of nonlinear mode 1 (H5)")
