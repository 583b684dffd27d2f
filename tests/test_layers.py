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
    "atomic_files": 0,
    "json_numbers": 0,
    "_sigint": 0,
    "validation": 0,
    "paper_data": 0,
    "_compiled": 0,
    "_lazy": 0,
    "_dispatchers": 0,
    "_dask": 0,
    "progress": 0,
    "model": 1,
    "poses": 2,
    "ik": 3,
    "singularities": 4,
    "collision": 4,
    "trajectory": 5,
    "planning": 6,
    "motion": 6,
    "tasks": 7,
    "export": 7,
    "workspace": 7,
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


def _absolute(module: str, node: ast.ImportFrom) -> str:
    """The absolute module a ``from ... import`` in ``module`` names (PEP 328)."""
    if node.level == 0:
        return node.module or ""
    package = module.split(".")
    if not MODULES[module].name == "__init__.py":
        package = package[:-1]  # a plain module's package is its folder
    base = package[: len(package) - (node.level - 1)]
    return ".".join([*base, node.module] if node.module else base)


def _imported_names(module: str) -> set[tuple[str, str | None]]:
    """Every ``(workbench module, name)`` a module imports, at any depth of its code.

    Relative imports are resolved against the module's package. ``name`` is the
    name taken from the module (``from m import name``), None for ``import m``;
    ``from package import submodule`` yields the submodule with name None.
    """
    found: set[tuple[str, str | None]] = set()
    tree = ast.parse(MODULES[module].read_text(), filename=str(MODULES[module]))
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            source = _absolute(module, node)
            if not source.startswith("workbench"):
                continue
            for alias in node.names:
                candidate = f"{source}.{alias.name}"
                if candidate in MODULES:  # ``from workbench import ik`` names a module
                    found.add((candidate, None))
                else:
                    found.add((source, alias.name))
        elif isinstance(node, ast.Import):
            found.update(
                (a.name, None) for a in node.names if a.name.startswith("workbench")
            )
    return found


def _imports(module: str) -> set[str]:
    """Every ``workbench...`` module a module imports, at any depth of its code."""
    return {source for source, _ in _imported_names(module)}


MODULES: dict[str, Path] = {
    _module_name(p): p for p in sorted(PACKAGE.rglob("*.py")) if "_urdf" not in p.parts
}


def _layer(module: str) -> int:
    top = module.split(".")[1]
    if top not in LAYERS:
        raise AssertionError(f"{module}: folder {top!r} has no layer in LAYERS")
    return LAYERS[top]


@pytest.mark.slow
@pytest.mark.parametrize("module", sorted(set(MODULES) - FRONT_DOORS))
def test_module_imports_only_its_layer_or_lower(module: str) -> None:
    own = _layer(module)
    upward = sorted(
        f"{dep} (layer {_layer(dep)})"
        for dep in _imports(module)
        if dep not in FRONT_DOORS and _layer(dep) > own
    )
    assert not upward, f"{module} (layer {own}) imports a higher layer: {upward}"


@pytest.mark.slow
def test_no_import_cycle() -> None:
    graph = {
        m: {d for d in _imports(m) if d in MODULES and d != m}
        for m in MODULES
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


def _package(module: str) -> str:
    """The folder below ``workbench`` a module is in (``ik`` for ``workbench.ik.x``).

    A top-level module (``workbench.errors``) is a package of its own.
    """
    return module.split(".")[1]


def _crosses_privately(module: str, source: str, name: str | None) -> bool:
    """Whether ``module`` takes a private module or name of another package.

    The package root's own modules (``workbench._compiled``, the compiled-code
    layer) are shared internals that any folder may import; their private
    names are not.
    """
    if source == "workbench" or _package(source) == _package(module):
        return False
    below = source.split(".")[2:]  # the path inside the other package
    return any(part.startswith("_") for part in below) or (name or "").startswith("_")


@pytest.mark.parametrize("module", sorted(set(MODULES) - FRONT_DOORS))
def test_no_private_name_crosses_packages(module: str) -> None:
    """Packages meet through public names: private modules and names stay inside."""
    crossing = sorted(
        source if name is None else f"{source}:{name}"
        for source, name in _imported_names(module)
        if _crosses_privately(module, source, name)
    )
    assert not crossing, f"{module} imports private names of other packages: {crossing}"


@pytest.mark.parametrize(
    ("module", "statement", "expected"),
    [
        ("workbench.poses.rigid", "from ..cli import main", "workbench.cli"),
        ("workbench.poses.rigid", "from . import rotations", "workbench.poses"),
        ("workbench.poses", "from .rigid import x", "workbench.poses.rigid"),
        (
            "workbench.ik.closed_form",
            "from ..model.robot import R",
            "workbench.model.robot",
        ),
        (
            "workbench.ik.numerical",
            "from workbench.model import Robot",
            "workbench.model",
        ),
    ],
)
def test_relative_imports_are_resolved(
    module: str, statement: str, expected: str
) -> None:
    node = ast.parse(statement).body[0]
    assert isinstance(node, ast.ImportFrom)
    assert _absolute(module, node) == expected
