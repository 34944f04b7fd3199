"""The package's layers: every import points down (or sideways inside a layer), and no
module imports itself back through others.

Layers, bottom to top: the model, the FE builders, the numerical core beside the contact
laws (core's fused residuals call the laws' kernels, the laws' data use core's
condensation: one layer, kept acyclic by the cycle test), results, the methods, the
analyses, and on top io, plots and the command line. Function-level (lazy)
imports count as much as module-level ones.
"""

import ast
import pathlib

import pytest

PACKAGE = pathlib.Path(__file__).resolve().parents[1] / "mmshbm"

#: prefix of a dotted module name -> layer (the longest prefix wins)
LAYERS = {
    "mmshbm._validate": 0,
    "mmshbm._warnings": 0,
    "mmshbm._files": 0,
    "mmshbm._threads": 0,
    "mmshbm._aliases": 0,
    "mmshbm._kernel_cache": 0,
    "mmshbm.model": 1,
    "mmshbm.fe": 2,
    "mmshbm.core": 3,
    "mmshbm.contact": 3,  # beside core: used by core and methods, uses core's condensation
    "mmshbm.results": 4,
    "mmshbm.methods": 5,
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
    """Dotted mmshbm modules that ``module`` imports, anywhere in its body."""
    is_package = path.name == "__init__.py"
    package = module if is_package else module.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
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
    return {m for m in found if m != "mmshbm"}


MODULES = _modules()
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
