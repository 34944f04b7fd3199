"""Every result says what it is: family, contact admissibility, completeness."""

import warnings

import numpy as np
import pytest

import mmshbm
from mmshbm import BranchWarning
from mmshbm.harmonic.modal_energy import kinetic_energy_shares
from mmshbm.results.branch import Branch
from mmshbm.results.diagnostics import CheckThresholds, _coefficients, check_branch, mode_shares


def _run(*args, **kwargs):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", BranchWarning)
        branch = mmshbm.backbone(*args, **kwargs)
    return branch, [str(w.message) for w in caught if issubclass(w.category, BranchWarning)]


def test_penalty_default_turns_into_another_family(beam21):
    # the case: penalty-HBM turns back at 59.8 Hz and climbs the 5:1 tongue to 10 gaps at 58.56 Hz
    branch, messages = _run(beam21, method="penalty")
    assert branch.completed
    assert branch.frequency.max() == pytest.approx(59.8, abs=0.1)
    assert branch.frequency[-1] == pytest.approx(58.56, abs=0.05)
    share = branch.records["mode_share"]
    assert share[0] == pytest.approx(1.0, abs=1e-9)  # the linear mode itself
    assert share[-1] < 0.05  # at 10 gaps the motion is another mode's
    family = [m for m in messages if "leaves the family of linear mode 1" in m]
    assert len(family) == 1 and "another family" in family[0]
    assert [f.kind for f in branch.findings][0] == "left_family"


def test_shooting_default_is_another_family(beam21):
    # the case: a vertical line at 45.8-45.9 Hz up to 10 gaps, energy 7392 J
    branch, messages = _run(beam21, method="shooting")
    assert branch.energy[-1] == pytest.approx(7392, rel=0.01)
    assert branch.records["mode_share"][-1] < 0.05
    assert any("leaves the family" in m and "another family" in m for m in messages)


def test_mode_share_two_routes_agree(beam21):
    """coefficients(u) and the DFT of the time signals (shooting's route) give the same shares."""
    branch, _ = _run(beam21, harmonics=3, max_amplitude=2.5e-3)

    class SignalsOnly:  # the solver without coefficients(), as shooting
        def __init__(self, solver):
            self.solver, self.model, self.mode = solver, solver.model, 1

        def time_signals(self, u, dofs, n):
            return self.solver.time_signals(u, dofs, n)

    _, Phi = beam21.linear_modes(1)
    for i in (0, len(branch) // 2, len(branch) - 1):
        u = branch.states[i]
        omega = 2 * np.pi * branch.frequency[i]
        a = kinetic_energy_shares(Phi, None, _coefficients(branch.solver, u, 64), omega, beam21.M)[0][0, 1]
        b = kinetic_energy_shares(Phi, None, _coefficients(SignalsOnly(branch.solver), u, 64), omega,
                                  beam21.M)[0][0, 1]
        assert a == pytest.approx(b, abs=1e-10)
        assert a == pytest.approx(branch.records["mode_share"][i], abs=1e-12)


def test_oscillator_share_is_one():
    """A one-DOF structure has one mode: all the energy is in it (over all harmonics), most
    of it at the fundamental (the impacts put a little into its odd harmonics), nothing
    leaves the family."""
    branch, messages = _run(mmshbm.OneDofOscillator(1, 1, 4, 1).model(), harmonics=10, max_amplitude=3.0)
    np.testing.assert_allclose(branch.records["modal_shares"][:, 0, :].sum(axis=1), 1.0, atol=1e-12)
    assert branch.records["mode_share"].min() > 0.95
    assert not any("family" in m for m in messages)


def test_truncated_series_penetration_and_tension_are_reported():
    """H = 3 on the oscillator: the series passes the stop; the figures are those of the
    signals computed independently on a fine grid, and a larger tolerance silences it."""
    model = mmshbm.OneDofOscillator(1, 1, 4, 1).model()
    branch, messages = _run(model, harmonics=3, max_amplitude=3.0)
    kinds = [f.kind for f in branch.findings]
    assert "penetration" in kinds and "negative_force" in kinds
    pen = next(f for f in branch.findings if f.kind == "penetration")
    _, q = branch.time_signals(pen.first, dofs=[model.contact_dof], n_samples=4096)
    deepest = max((model.stop_side * branch.time_signals(i, [model.contact_dof], n_samples=4096)[1][0]
                   - model.gap).max() / model.gap for i in range(len(branch)))
    assert pen.value == pytest.approx(deepest, rel=1e-3)
    assert (model.stop_side * q[0] - model.gap).max() > 0.05 * model.gap
    assert any("passes the stop" in m for m in messages)
    quiet = check_branch(branch, CheckThresholds(penetration=10.0, negative_force=10.0), warn=False)
    assert [f.kind for f in quiet] == []


def test_incomplete_branch(beam21):
    branch, messages = _run(beam21, harmonics=3, max_steps=4)
    assert branch.status == "max_steps" and not branch.completed
    assert any("ended short of its bounds" in m and "max_steps = 4" in m for m in messages)


def _constructed(amplitude, status):
    n = len(amplitude)
    return Branch(frequency=np.linspace(1.0, 2.0, n), amplitude=np.asarray(amplitude, dtype=float),
                  energy=np.ones(n), contact_force_max=np.zeros(n), newton_iterations=np.zeros(n, int),
                  step_size=np.ones(n), states=np.zeros((n, 3)), status=status, method="mmshbm", harmonics=1)


def test_completed_means_reached_bounds():
    grown = [1e-4, 5e-3, 1e-2]
    assert _constructed(grown, "bound:amplitude").completed
    assert _constructed(grown, "bound:frequency").completed
    for status in ("max_steps", "ds_min: step size fell below 1e-06", "start failed: x", "interrupted"):
        assert not _constructed(grown, status).completed


@pytest.mark.parametrize("amplitude", [
    [1e-4, 5e-3, 0.0],  # turned back and hit the amplitude's lower bound, 0
    [1e-4, 1e-4 * (1 + 1e-9)],  # never left its start: equal to far below the step tolerance
    [1e-4],  # the start alone
    [1e-4, 5e-3, 5e-5],  # came back below its start, to a frequency bound
])
def test_a_backbone_back_at_its_start_is_not_completed(amplitude):
    branch = _constructed(amplitude, "bound:amplitude")
    assert not branch.completed
    assert not _constructed(amplitude, "bound:frequency").completed
    finding = [f for f in check_branch(branch, warn=False) if f.kind == "incomplete"]
    assert len(finding) == 1 and "no larger amplitude than its start" in finding[0].message


def test_checks_survive_save_and_load(beam21, tmp_path):
    branch, _ = _run(beam21, harmonics=3, max_steps=4)
    loaded = Branch.load(branch.save(tmp_path / "b.npz"))
    assert [f.kind for f in loaded.findings] == [f.kind for f in branch.findings]
    np.testing.assert_array_equal(loaded.records["mode_share"], branch.records["mode_share"])
    # an old file without mode_share: computed on check()
    del loaded.records["mode_share"]
    loaded.metadata.pop("checks")
    with pytest.warns(BranchWarning, match="ended short"):
        loaded.check()
    np.testing.assert_allclose(loaded.records["mode_share"], branch.records["mode_share"], atol=1e-12)


def test_mode_shares_explicit_mode(beam21):
    branch, _ = _run(beam21, harmonics=3, max_amplitude=1.5e-3)
    first = mode_shares(branch, mode=1)
    second = mode_shares(branch, mode=2)
    assert np.all(first + second <= 1 + 1e-12)
    assert second[0] == pytest.approx(0.0, abs=1e-12)


def test_thresholds_validated():
    with pytest.raises(ValueError, match="min_mode_share"):
        CheckThresholds(min_mode_share=-1)
    with pytest.raises(ValueError, match="n_samples"):
        CheckThresholds(n_samples=2)


def test_a_path_back_below_grazing_left_its_family():
    """2-mass chain, host of 0.17 kg in a clearance, open modes 4.147 / 5.023 Hz: plain
    path following folds near 4.98 Hz and comes back below its grazing amplitude (no
    contact there: a linear mode's orbit; from there it passes linear mode 2 and climbs to
    the bound at 127 Hz), with the fundamental's majority all the way. The check says it
    left the family where it first went below grazing; a path that only rises past
    grazing (the stiff chain) is not flagged."""
    from validation import corpus

    model = corpus.generate(31, 31)[30].model()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        path = mmshbm.backbone(model, harmonics=15, max_amplitude=10 * model.gap, follow="path")
    grazing = next(sp.index for sp in path.special_points if sp.kind == "grazing")
    below = np.flatnonzero(path.amplitude[grazing + 1:] < 0.9 * path.amplitude[grazing]) + grazing + 1
    assert len(below)
    left = [f for f in path.metadata["checks"] if f["kind"] == "left_family"]
    assert len(left) == 1 and "below its grazing amplitude" in left[0]["message"]
    assert left[0]["first"] == below[0] and left[0]["last"] == len(path) - 1
    assert min(path.records["fundamental_share"][:below[0] + 1]) >= 0.5  # the share alone saw nothing
    M = np.diag([1.0, 1.0, 0.0])
    K = np.array([[2000.0, -1000, 0], [-1000, 6000, -5000], [0, -5000, 5000]])
    chain = mmshbm.Model.from_matrices(M, K, contact_dof=2, gap=0.01, stop_side=1)
    rising = mmshbm.backbone(chain, harmonics=7, follow="path")
    assert not [f for f in rising.metadata["checks"] if f["kind"] == "left_family"]
