"""``python -m validation nlvib``'s plumbing (the NLvib runs themselves need Octave and NLvib,
and stay out of the test suite): the Octave patch of NLvib's solve_and_continue.m on a copy,
a folder that is not NLvib refused by name, and the drivers the cases call present."""

import re

import pytest

from validation import nlvib_compare


def test_patch_replaces_the_nested_optimset_on_a_copy(tmp_path):
    src = tmp_path / "NLvib" / "SRC"
    src.mkdir(parents=True)
    original = ("    Solopt = optimset(optimset(@fsolve),'Display','off',...%'iter',...\n"
                "        'Jacobian','on','MaxIter',50);\n")
    (src / "solve_and_continue.m").write_text(original)
    (src / "HB_residual.m").write_text("% residual\n")
    dest = nlvib_compare.patched_nlvib(tmp_path / "NLvib", tmp_path / "copy")
    text = (dest / "solve_and_continue.m").read_text()
    assert "optimset(@fsolve)" not in text
    assert "Solopt = optimset('Display','off'" in text
    assert (dest / "HB_residual.m").read_text() == "% residual\n"
    assert (src / "solve_and_continue.m").read_text() == original  # the checkout untouched


def test_a_folder_without_nlvib_is_refused_by_name(tmp_path):
    with pytest.raises(FileNotFoundError, match="--nlvib .*solve_and_continue.m"):
        nlvib_compare.patched_nlvib(tmp_path, tmp_path / "copy")


def test_every_case_calls_a_driver_of_the_repository():
    for case, (call, kind) in nlvib_compare.CASES.items():
        name = re.match(r"(\w+)\(", call).group(1)
        assert (nlvib_compare.HERE / f"{name}.m").is_file(), case
        assert kind in ("1e7", "1e9", "oscillator")


def test_the_command_says_when_octave_is_missing(monkeypatch, capsys, tmp_path):
    from validation.__main__ import main

    monkeypatch.setattr(nlvib_compare, "octave_available", lambda: None)
    assert main(["nlvib", "--nlvib", str(tmp_path), "--out", str(tmp_path / "out")]) == 2
    assert "octave is not on PATH" in capsys.readouterr().err
