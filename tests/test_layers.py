"""The folder layout is the architecture: data flows one way through the layers.

A module may import from its own layer or a lower one, never a higher one, and no two
modules import each other (directly or round a longer loop). Imports inside functions
count too, so a lazy import cannot hide an upward dependency.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "workbench"

#: Lowest layer first. The key is the first part of the module path below ``workbench``.
LAYERS: dict[str, int] = {
    "errors": 0,
    "validation": 0,
    "paper_data": 0,
    "_compiled": 0,
    "model": 1,
    "poses": 2,
    "ik": 3,
    "singularities": 4,
    "collision": 4,
    "trajectory": 5,
    "planning": 6,
    "tasks": 7,
    "export": 7,
    "plots": 8,
    "viz": 8,
    "reports": 9,
    "demo": 10,
    "cli": 11,
}
#: The package's front door and ``python -m workbench`` may import anything.
FRONT_DOORS = {"workbench", "workbench.__main__"}


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _imports(path: Path) -> set[str]:
    """Every ``workbench...`` module a file imports, at any depth of its code."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.ImportFrom) and node.module:
            if node.level == 0 and node.module.startswith("workbench"):
                found.add(node.module)
                for alias in node.names:  # ``from workbench import ik`` names a module
                    candidate = f"{node.module}.{alias.name}"
                    if candidate in MODULES:
                        found.add(candidate)
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.startswith("workbench"))
    return found


MODULES: dict[str, Path] = {
    _module_name(p): p for p in sorted(PACKAGE.rglob("*.py")) if "_urdf" not in p.parts
}


def _layer(module: str) -> int:
    top = module.split(".")[1]
    if top not in LAYERS:
        raise AssertionError(f"{module}: folder {top!r} has no layer in LAYERS")
    return LAYERS[top]


@pytest.mark.parametrize("module", sorted(set(MODULES) - FRONT_DOORS))
def test_module_imports_only_its_layer_or_lower(module: str) -> None:
    own = _layer(module)
    upward = sorted(
        f"{dep} (layer {_layer(dep)})"
        for dep in _imports(MODULES[module])
        if dep not in FRONT_DOORS and _layer(dep) > own
    )
    assert not upward, f"{module} (layer {own}) imports a higher layer: {upward}"


def test_no_import_cycle() -> None:
    graph = {
        m: {d for d in _imports(p) if d in MODULES and d != m}
        for m, p in MODULES.items()
        if m not in FRONT_DOORS
    }
    # A package imports its own submodules to re-export them; that edge is no cycle.
    for m, deps in graph.items():
        graph[m] = {d for d in deps if not d.startswith(m + ".")}
    done: set[str] = set()

    def visit(node: str, path: list[str]) -> None:
        if node in path:
            cycle = [*path[path.index(node) :], node]
            raise AssertionError("import cycle: " + " -> ".join(cycle))
        if node in done:
            return
        for dep in sorted(graph.get(node, ())):
            visit(dep, [*path, node])
        done.add(node)

    for module in sorted(graph):
        visit(module, [])


def test_every_folder_has_a_layer() -> None:
    folders = {
        p.name for p in PACKAGE.iterdir() if p.is_dir() and p.name != "__pycache__"
    }
    modules = {p.stem for p in PACKAGE.glob("*.py")} - {"__init__", "__main__"}
    assert (folders | modules) - {"_urdf"} <= set(LAYERS)
