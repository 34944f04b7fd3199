"""The package's layers: every import points down (or sideways inside a layer), and no
module imports itself back through others.

Layers, bottom to top: the model, the FE builders, the numerical core beside the contact
laws (core's fused residuals call the laws' kernels, the laws' data use core's
condensation: one layer, kept acyclic by the cycle test), the family following (an event
plug-in of the driver that core does not know), results, the methods, the
analyses, and on top io, plots and the command line. Function-level (lazy)
imports count as much as module-level ones, and so do imports by name:
``importlib.import_module("mmshbm...")`` and ``__import__`` with a constant (or
``f"{__name__}..."``) name, and ``"mmshbm.module:attr"`` strings (entry points resolved at
run time).
"""

import ast
import pathlib

import pytest
from locations import PACKAGE as PACKAGE_DIR

PACKAGE = PACKAGE_DIR

#: prefix of a dotted module name -> layer (the longest prefix wins)
LAYERS = {
    "mmshbm._validate": 0,
    "mmshbm._warnings": 0,
    "mmshbm._files": 0,
    "mmshbm._threads": 0,
    "mmshbm._progress": 0,
    "mmshbm._kernel_cache": 0,
    "mmshbm._entry_points": 0,
    "mmshbm._method_info": 0,
    "mmshbm.model": 1,
    "mmshbm.elements": 1,  # beside the model: a model holds its elements, which know no model
    "mmshbm.fe": 2,
    "mmshbm.harmonic": 2,  # beside fe: the linear structure per harmonic, uses only the model
    "mmshbm.core": 3,
    "mmshbm.contact": 3,  # beside core: used by core and methods, uses core's condensation
    "mmshbm.family": 3.5,  # above core: an event plug-in the methods pass to the driver; below results
    "mmshbm.results": 4,
    "mmshbm.methods": 5,
    "mmshbm.exact": 5,  # the public home of methods.exact
    "mmshbm.analysis": 6,
    "mmshbm.io": 7,
    "mmshbm.plotting": 7,
    "mmshbm.cli": 7,
    "mmshbm.__main__": 8,
    "mmshbm._precompile": 8,
}


def _layer(module: str) -> int:
    best = max((p for p in LAYERS if module == p or module.startswith(p + ".")), key=len, default=None)
    if best is None:
        raise AssertionError(f"module {module} has no layer: add it to LAYERS")
    return LAYERS[best]


def _modules() -> dict[str, pathlib.Path]:
    out = {}
    for path in PACKAGE.rglob("*.py"):
        rel = path.relative_to(PACKAGE.parent).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _imports(module: str, path: pathlib.Path) -> set[str]:
    """Dotted mmshbm modules that ``module`` imports, anywhere in its body: import
    statements, and imports by name (:func:`_named_imports`)."""
    is_package = path.name == "__init__.py"
    package = module if is_package else module.rpartition(".")[0]
    found = set()
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.startswith("mmshbm"))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if not target.startswith("mmshbm"):
                continue
            modules = _modules()
            for alias in node.names:  # `from pkg import submodule`
                sub = f"{target}.{alias.name}"
                found.add(sub if sub in modules else target)
    found |= _named_imports(module, tree)
    return {m for m in found if m != "mmshbm"}


def _constant_name(node: ast.AST, module: str) -> str | None:
    """The text of a constant string, or of ``f"{__name__}.rest"`` in ``module``; else None."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return node.value
    if isinstance(node, ast.JoinedStr):
        parts = []
        for value in node.values:
            if isinstance(value, ast.Constant):
                parts.append(str(value.value))
            elif isinstance(value.value, ast.Name) and value.value.id == "__name__":
                parts.append(module)
            else:
                return None
        return "".join(parts)
    return None


def _owning_module(dotted: str) -> str | None:
    """The longest package module that ``dotted`` names (or lies in: "pkg.mod.attr")."""
    parts = dotted.split(".")
    for n in range(len(parts), 0, -1):
        candidate = ".".join(parts[:n])
        if candidate in MODULE_NAMES:
            return candidate
    return None


def _named_imports(module: str, tree: ast.AST) -> set[str]:
    """Modules imported by name: ``importlib.import_module(name)`` / ``__import__(name)``
    with a constant name (a relative one with its ``package`` argument ``__name__`` or
    ``__package__``), and constant ``"mmshbm.module:attr"`` strings anywhere."""
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and node.args:
            func = node.func
            name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", None)
            if name in ("import_module", "__import__"):
                target = _constant_name(node.args[0], module)
                if target and target.startswith("."):
                    package = module if MODULES[module].name == "__init__.py" else module.rpartition(".")[0]
                    level = len(target) - len(target.lstrip("."))
                    base = package.split(".")[: len(package.split(".")) - (level - 1)]
                    target = ".".join(base + [target.lstrip(".")])
                if target and target.startswith("mmshbm"):
                    owner = _owning_module(target)
                    if owner:
                        found.add(owner)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            text = node.value
            if text.startswith("mmshbm.") and text.count(":") == 1 and " " not in text:
                owner = _owning_module(text.partition(":")[0])
                if owner:
                    found.add(owner)
    return found


MODULES = _modules()
MODULE_NAMES = set(MODULES)
GRAPH = {m: _imports(m, p) for m, p in MODULES.items() if m != "mmshbm"}


@pytest.mark.parametrize("module", sorted(GRAPH))
def test_imports_point_down(module):
    upward = sorted(t for t in GRAPH[module] if _layer(t) > _layer(module))
    assert not upward, f"{module} (layer {_layer(module)}) imports higher layers: {upward}"


def test_no_import_cycles():
    """Depth-first search for a cycle among the package's own modules."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m):
        state[m] = 1
        stack.append(m)
        for t in sorted(GRAPH.get(m, ())):
            # `from mmshbm.core import x` loads mmshbm.core/__init__ too; ignore the facade
            if t not in GRAPH:
                continue
            if state.get(t) == 1:
                cycle = stack[stack.index(t):] + [t]
                raise AssertionError("import cycle: " + " -> ".join(cycle))
            if state.get(t) is None:
                visit(t)
        stack.pop()
        state[m] = 2

    for m in sorted(GRAPH):
        if m not in state:
            visit(m)


def test_modules_are_small():
    """One concern per module: none grows past ~500 lines (kernels excepted up to 600)."""
    too_long = {m: n for m, p in MODULES.items() if (n := len(p.read_text().splitlines())) > 600}
    assert not too_long, f"split these modules: {too_long}"


@pytest.mark.parametrize("source", [
    'import importlib\ndef f():\n    return importlib.import_module("mmshbm.methods.registry").make_problem',
    'ENTRY = {"backbone": "mmshbm.methods.backbone:backbone"}',
    'def f():\n    return __import__("mmshbm.analysis.studies")',
])
def test_imports_by_name_are_seen(source, tmp_path):
    """A results module that reaches the methods or analyses by a name string is caught."""
    path = tmp_path / "probe.py"
    path.write_text(source)
    found = _imports("mmshbm.results.probe", path)
    assert found and all(_layer(t) > _layer("mmshbm.results.probe") for t in found), found
