"""Small things a new user meets first: help texts, user model files, default_beam's
overrides, the README's promises, forced responses of undamped models, baselines that turn
into another family."""

import argparse
import types
from pathlib import Path

import numpy as np
import pytest
from locations import ROOT

import mmshbm
from mmshbm.cli import build_parser, main

README = " ".join((ROOT / "README.md").read_text().split())


def _chain(tmp_path, with_contact=True) -> Path:
    """Two masses on springs and a massless contact node: 2 modes."""
    M = np.diag([1.0, 1.0, 0.0])
    K = np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]])
    path = tmp_path / "chain.npz"
    if with_contact:
        mmshbm.Model.from_matrices(M, K, contact_dof=2, gap=0.1).save_npz(path)
    else:
        np.savez(path, M=M, K=K)
    return path


def _subparsers():
    parser = build_parser()
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return sub.choices


def test_frf_help_shows_a_percent_sign(capsys):
    assert main(["frf", "--help"]) == 0
    out = capsys.readouterr().out
    assert "0.5 % modal damping" in " ".join(out.split()) and "%%" not in out


def test_every_option_has_help():
    missing = [(name, a.option_strings) for name, p in _subparsers().items() for a in p._actions
               if a.option_strings and not a.help]
    assert missing == []


def test_measured_help_gives_the_csv_format():
    for name, p in _subparsers().items():
        for a in p._actions:
            if "--measured" in a.option_strings and name != "fit":
                assert "frequency (Hz) and amplitude (m)" in a.help and "contact_force (N)" in a.help, name


def test_modes_of_a_model_with_fewer_modes_than_asked(tmp_path, capsys):
    assert main(["modes", "--model-file", str(_chain(tmp_path)), "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    K_open = np.array([[2.0, -1.0], [-1.0, 1.0]])  # the contact node condensed (its spring in series)
    f = np.sqrt(np.linalg.eigvalsh(K_open)) / (2 * np.pi)
    assert "the model has 2 DOFs with mass: 2 modes" in out
    assert f"mode 1: {f[0]:.4f} Hz" in out and f"mode 2: {f[1]:.4f} Hz" in out and "mode 3" not in out


def test_raw_model_file_takes_contact_options(tmp_path, capsys):
    raw = _chain(tmp_path, with_contact=False)
    assert main(["modes", "--model-file", str(raw), "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "give --contact-dof" in err and "contact_dof=" not in err
    assert main(["modes", "--model-file", str(raw), "--contact-dof", "2", "--out", str(tmp_path)]) == 2
    assert "give --gap" in capsys.readouterr().err
    argv = ["modes", "--model-file", str(raw), "--contact-dof", "2", "--gap", "0.1", "--stop-side", "-1",
            "-n", "2", "--out", str(tmp_path)]
    assert main(argv) == 0
    assert "mode 2:" in capsys.readouterr().out
    assert main([*argv[:-2], "--stop-side", "2", "--out", str(tmp_path)]) == 2
    assert "--stop-side" in capsys.readouterr().err


def test_default_beam_takes_overrides():
    beam = mmshbm.default_beam(E=200e9, gap=2e-3)
    assert (beam.E, beam.gap, beam.rho) == (200e9, 2e-3, 7850.0)
    assert mmshbm.default_beam() == mmshbm.default_beam(gap=1e-3)
    f = [mmshbm.default_beam(E=E).model(8).linear_frequencies(1)[0] for E in (210e9, 105e9)]
    assert f[1] / f[0] == pytest.approx(2 ** -0.5, rel=1e-3)  # bending frequencies go as sqrt(E)
    with pytest.raises(TypeError, match="unknown field youngs_modulus; the beam's fields: length"):
        mmshbm.default_beam(youngs_modulus=1.0)
    with pytest.raises(ValueError, match="E must be positive"):
        mmshbm.default_beam(E=-1.0)


def test_a_contact_dof_with_mass_as_the_readme_says():
    assert "`from_matrices` accepts a contact DOF with mass" in README
    assert "a contact DOF with mass given to MMS-HBM" in README
    model = mmshbm.Model.from_matrices(np.eye(2), [[2.0, -1.0], [-1.0, 1.0]], contact_dof=1, gap=0.1)
    with pytest.raises(ValueError, match="carries mass.*with_contact_layer.*with_massless_contact"):
        mmshbm.backbone(model)
    branch = mmshbm.backbone(model, method="penalty", max_amplitude=0.2)
    assert branch.completed


def test_forced_response_of_an_undamped_model_is_refused():
    from mmshbm.model.damping import model_has_damping

    model = mmshbm.OneDofOscillator(1, 1, 4, 1).model()
    for undamped in (model, model.with_damping(modal_ratio=0.0)):
        assert not model_has_damping(undamped)
        with pytest.raises(ValueError, match=r"no damping.*with_damping.*mmshbm\.backbone\(model\)"):
            mmshbm.frequency_response(undamped, [1.0, 0.0], (0.1, 0.3))
    assert model_has_damping(model.with_damping(modal_ratio=0.01))
    # a dissipative attribute besides the viscous matrix (a friction law) counts as damping
    assert model_has_damping(types.SimpleNamespace(damping=None, friction=(object(),)))
    assert not model_has_damping(types.SimpleNamespace(damping=None, friction=()))
    assert not model_has_damping(types.SimpleNamespace(damping=None, friction=None))


def test_frf_without_damping_is_refused_with_the_options(tmp_path, capsys):
    for extra in (["--damping", "0"], ["--rayleigh", "0", "0"]):
        assert main(["frf", *extra, "--out", str(tmp_path)]) == 2
        err = capsys.readouterr().err
        assert "needs damping" in err and "--damping > 0 or --rayleigh" in err and "mmshbm backbone" in err


def test_shooting_baseline_on_another_family_exits_1(tmp_path, capsys):
    assert main(["backbone", "--method", "shooting", "--out", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert "shooting branch: the backbone of linear mode 1 ends at 1.01 gaps (45.89 Hz)" in err
    assert "another family" in err and "(exit code 1)" in err
