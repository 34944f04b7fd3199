"""One registry of methods: every switch on a method's name reads its capabilities
(:data:`mmshbm.methods.registry.METHOD_INFO`), and the CLI's method choices come from it."""

from __future__ import annotations

import ast

import pytest
from locations import PACKAGE as PACKAGE_DIR

from mmshbm._method_info import benchmarked_methods
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


def _dispatch_tables(rel: str) -> list[int]:
    """Lines of dict literals keyed by two or more method names with "module:class" values."""
    lines = []
    for node in ast.walk(ast.parse((PACKAGE / rel).read_text())):
        if isinstance(node, ast.Dict):
            keys = [k.value for k in node.keys if isinstance(k, ast.Constant)]
            paths = [v.value for v in node.values if isinstance(v, ast.Constant) and isinstance(v.value, str)]
            if sum(k in NAMES for k in keys) >= 2 and any(":" in v for v in paths):
                lines.append(node.lineno)
    return lines


def test_method_switches_in_the_whole_package_read_the_registry():
    """Outside the registry (and its table in _method_info.py) at most five comparisons
    of a method name, and no table of problem classes by method name."""
    modules = [str(p.relative_to(PACKAGE)) for p in sorted(PACKAGE.rglob("*.py"))]
    modules = [m for m in modules if m not in ("methods/registry.py", "_method_info.py")]
    found = {rel: lines for rel in modules if (lines := _name_comparisons(rel) + _dispatch_tables(rel))}
    assert sum(len(v) for v in found.values()) <= 5, found


def test_the_probes_see_a_switch_and_a_table(tmp_path, monkeypatch):
    (tmp_path / "probe.py").write_text('T = {"mmshbm": "a.b:C", "penalty": "a.c:D"}\n'
                                       'def f(method):\n    return method == "shooting"\n')
    monkeypatch.setitem(globals(), "PACKAGE", tmp_path)
    assert _name_comparisons("probe.py") == [3] and _dispatch_tables("probe.py") == [1]


@pytest.mark.parametrize("command, option, expected", [
    ("backbone", "--method", backbone_methods()),
    ("study", "--methods", backbone_methods()),
    ("frf", "--method", forced_methods()),
    ("bench", "--methods", benchmarked_methods()),
])
def test_cli_method_choices_come_from_the_registry(command, option, expected):
    parser = build_parser()
    sub = next(a for a in parser._subparsers._group_actions if a.choices and command in a.choices)
    action = next(a for a in sub.choices[command]._actions if option in a.option_strings)
    assert list(action.choices) == expected
    assert "penalty-reduced" in backbone_methods() and "mmshbm" in expected


def test_stability_and_bench_read_capabilities():
    from mmshbm.analysis.benchmarking import METHOD_NAMES
    from mmshbm.methods.mms.stability import branch_stability

    assert benchmarked_methods() == ["mmshbm", "penalty", "shooting"] == list(METHOD_NAMES)
    assert {m for m, info in METHOD_INFO.items() if info.floquet_trivial} == {"mmshbm", "epmc"}

    class PenaltyBranch:
        method = "penalty"

    with pytest.raises(ValueError, match=r"methods \['epmc', 'mmshbm'\], got 'penalty'"):
        branch_stability(PenaltyBranch())


def test_capabilities_of_the_switches():
    assert method_info("shooting").harmonic_balance is False
    assert method_info("mmshbm").damped_variant == "epmc"
    assert method_info("no-such-method").display_name == "no-such-method"
    assert not method_info("mmshbm").baseline and method_info("penalty").baseline
