"""The README runs as written: its Python snippets and its command lines."""

import os
import re
import shlex
import warnings

import pytest
from locations import ROOT

from mmshbm import BranchWarning
from mmshbm.cli import main

README = (ROOT / "README.md").read_text()


def _python_blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", README, flags=re.S)


def _command_lines() -> list[str]:
    section = README.split("## Command line", 1)[1].split("\n## ", 1)[0]
    return [line.split("#", 1)[0].strip() for line in section.splitlines() if line.startswith("    mmshbm ")]


@pytest.fixture()
def in_tmp(tmp_path):
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        yield tmp_path
    finally:
        os.chdir(cwd)


def test_python_snippets_run(in_tmp):
    blocks = _python_blocks()
    assert len(blocks) >= 2
    namespace: dict = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BranchWarning)  # the baselines' branches warn, as documented
        for block in blocks:
            exec(compile(block, "README.md", "exec"), namespace)  # noqa: S102 - the README's own code
    model, branch = namespace["model"], namespace["branch"]
    # as the snippets' comments say
    assert [round(f, 2) for f in model.linear_frequencies(3)] == [45.81, 286.13, 796.93]
    assert (branch.completed, branch.status) == (True, "bound:amplitude")
    assert round(namespace["chain_branch"].frequency_at(2, unit="gap"), 2) == 15.80
    assert (in_tmp / "backbone.npz").exists()


@pytest.mark.slow  # ~30 s, most of it `mmshbm bench --quick`
def test_command_lines_run(in_tmp, capsys):
    commands = _command_lines()
    assert any(c.startswith("mmshbm study") for c in commands) and len(commands) >= 7
    (in_tmp / "lab.csv").write_text("frequency,amplitude\n46.0,0.0012\n50.0,0.0015\n55.0,0.002\n")
    for command in commands:
        argv = shlex.split(command)[1:]
        if argv[0] == "plot":  # plots the backbone written by the main job
            assert main(["backbone"]) == 0
        assert main(argv) == 0, (command, capsys.readouterr().err[-2000:])
    assert (in_tmp / "out" / "backbone_backbone.png").exists()


def test_quick_start_commands_are_documented():
    assert "pip install . && mmshbm backbone" in README
    assert "pip install '.[test]' && python -m pytest -q" in README


def test_readme_is_a_front_door():
    """At most 250 lines, and every page it links to exists."""
    assert len(README.splitlines()) <= 250
    root = ROOT
    links = re.findall(r"\]\(((?:docs|examples)/[^)#]+)", README)
    assert len(links) >= 10
    assert [link for link in links if not (root / link).exists()] == []
