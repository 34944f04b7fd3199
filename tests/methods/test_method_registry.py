"""One registry of methods: every switch on a method's name reads its capabilities
(:data:`mmshbm.methods.registry.METHOD_INFO`), and the CLI's method choices come from it."""

from __future__ import annotations

import ast

import pytest
from locations import PACKAGE as PACKAGE_DIR

from mmshbm.cli import build_parser
from mmshbm.methods.frequency_response import FORCED_METHODS
from mmshbm.methods.registry import METHOD_INFO, METHODS, backbone_methods, forced_methods, method_info

PACKAGE = PACKAGE_DIR
NAMES = set(METHODS)
#: the modules whose method switches go through the registry
SWITCHING = ["methods/limits.py", "methods/runner.py", "methods/backbone.py", "results/branch.py",
             "cli/backbone.py", "cli/frf.py", "cli/study.py"]


def test_every_method_has_its_capabilities():
    assert set(METHOD_INFO) == NAMES
    for name, info in METHOD_INFO.items():
        assert info.display_name and info.memory_model in {"condensed", "assembled", "time-march"}, name
        assert info.damped_variant is None or info.damped_variant in NAMES
        assert info.harmonic_balance == (info.memory_model != "time-march"), name


def test_the_forced_methods_have_forced_problems():
    assert set(FORCED_METHODS) == set(forced_methods())


def _name_comparisons(rel: str) -> list[int]:
    tree = ast.parse((PACKAGE / rel).read_text())
    lines = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare):
            consts = [c for c in [node.left, *node.comparators] if isinstance(c, ast.Constant)]
            if any(c.value in NAMES for c in consts):
                lines.append(node.lineno)
    return lines


def test_no_method_name_switches_outside_the_registry():
    found = {rel: _name_comparisons(rel) for rel in SWITCHING}
    assert sum(len(v) for v in found.values()) <= 5, found


@pytest.mark.parametrize("command, option, expected", [
    ("backbone", "--method", backbone_methods()),
    ("study", "--methods", backbone_methods()),
    ("frf", "--method", forced_methods()),
])
def test_cli_method_choices_come_from_the_registry(command, option, expected):
    parser = build_parser()
    sub = next(a for a in parser._subparsers._group_actions if a.choices and command in a.choices)
    action = next(a for a in sub.choices[command]._actions if option in a.option_strings)
    assert list(action.choices) == expected
    assert "penalty-reduced" in backbone_methods() and "mmshbm" in expected


def test_capabilities_of_the_switches():
    assert method_info("shooting").harmonic_balance is False
    assert method_info("mmshbm").damped_variant == "epmc"
    assert method_info("no-such-method").display_name == "no-such-method"
    assert not method_info("mmshbm").baseline and method_info("penalty").baseline
