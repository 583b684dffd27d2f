"""docs/interface.md against the code: its names, flags and JSON keys.

The contract is read as written. Python names: every ``from workbench... import``
line of its ``python`` blocks imports from a package (``workbench`` or
``workbench.<package>``, never a module inside one) and every name on it resolves;
every ``<module>.<name>`` of a module imported there (``ik.analytic``), every
``robot.<name>`` and every dotted ``workbench.<...>`` name in the page resolves.
Commands: each row of the command table starts with the command's usage, whose
flags are exactly the parser's (``--package-dir``, ``--xacro-arg`` and
``--srdf`` come with ``--robot``, as the page says; ``-h``/``--help`` is
argparse's own); a flag with fixed choices lists exactly them (``--format
ros2-bag|urscript|csv``); every flag named in a code span elsewhere (``fishcut
--servo-rate``) exists. JSON: each
command's ``--json`` is run in-process on a small case and every key it prints is
named in its row (a row may take in another's with "keys of `workbench COMMAND`";
the keys of a dict written ``name: {kind: ...}`` or ``{label: ...}`` are data, not
names).
"""

from __future__ import annotations

import argparse
import importlib
import json
import re
import shutil
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

from tests.conftest import run_cli
from workbench.cli import build_parser

INTERFACE = Path(__file__).resolve().parents[1] / "docs" / "interface.md"
TEXT = INTERFACE.read_text(encoding="utf-8")
LINES = TEXT.splitlines()

#: argparse's own option: on every parser, never in the usage rows.
HELP = frozenset({"-h", "--help"})
#: "Every command that takes --robot also takes --package-dir DIR ..., --xacro-arg
#: ... and --srdf FILE"
#: (Command line).
IMPLIED = {"--robot": ("--package-dir", "--xacro-arg", "--srdf")}
#: A flag as written in a usage: ``--pick-xyz-quat-wxyz``, ``-v``.
FLAG = re.compile(r"(?<![\w-])(--?[a-zA-Z][\w-]*)")
#: A flag and its choices as written in a usage: ``--measure reachability\|dexterity``.
CHOICES = re.compile(r"(--[\w-]+) ((?:[\w-]+\\\|)+[\w-]+)")
#: Placeholders of the keys of a dict whose keys are data (``branches: {label: ...}``).
DATA_KEY = re.compile(r"(\w+): \{(?:kind|label)\b")
#: A reference to another row's keys: ``keys of `workbench plan pick-place```.
KEYS_OF = re.compile(r"keys of `workbench ([a-z][a-z -]*?)`")


# --- reading the page ----------------------------------------------------------
@dataclass(frozen=True)
class Block:
    """A fenced ``python`` block: its first line number in the page and its lines."""

    start: int
    lines: tuple[str, ...]


def _python_blocks() -> list[Block]:
    blocks, current, start = [], None, 0
    for number, line in enumerate(LINES, start=1):
        if current is None and line.strip() == "```python":
            current, start = [], number + 1
        elif current is not None and line.strip() == "```":
            blocks.append(Block(start, tuple(current)))
            current = None
        elif current is not None:
            current.append(line)
    return blocks


BLOCKS = _python_blocks()


def _block_lines() -> Iterator[tuple[int, str]]:
    for block in BLOCKS:
        for offset, line in enumerate(block.lines):
            yield block.start + offset, line


def _code(line: str) -> str:
    """A line of a block without its comment."""
    return line.split("#", 1)[0]


@dataclass(frozen=True)
class ImportLine:
    line: int
    module: str
    names: tuple[str, ...]

    def __str__(self) -> str:
        return f"docs/interface.md:{self.line}: from {self.module} import ..."


def _import_lines() -> list[ImportLine]:
    found = []
    for number, line in _block_lines():
        match = re.match(r"\s*from (workbench[\w.]*) import (.+)", _code(line))
        if match:
            names = tuple(n.strip() for n in match.group(2).strip("() ").split(","))
            found.append(ImportLine(number, match.group(1), names))
    return found


IMPORTS = _import_lines()


def _text_outside_blocks() -> str:
    return re.sub(r"```.*?```", "", TEXT, flags=re.DOTALL)


def _code_spans(text: str) -> list[str]:
    return re.findall(r"`([^`\n]+)`", text)


@dataclass(frozen=True)
class Row:
    """A row of the command table: the command path, its usage, JSON cell, line."""

    path: tuple[str, ...]
    usage: str
    json_keys: str
    line: int


def _split_cells(line: str) -> list[str]:
    cells = re.split(r"(?<!\\)\|", line.strip())
    return [cell.strip() for cell in cells[1:-1]]


def _command_path(usage: str, parser: argparse.ArgumentParser) -> tuple[str, ...]:
    """The subcommand words at the start of a usage (``workspace map``)."""
    words = _code_spans(usage)[0].split()
    assert words[0] == "workbench", usage
    path: list[str] = []
    for word in words[1:]:
        choices = _subcommands(parser)
        if word not in choices:
            break
        path.append(word)
        parser = choices[word]
    return tuple(path)


def _rows() -> list[Row]:
    parser = build_parser()
    rows = []
    for number, line in enumerate(LINES, start=1):
        if line.startswith("| `workbench"):
            cells = _split_cells(line)
            assert len(cells) == 3, f"docs/interface.md:{number}: 3 cells expected"
            usage, _, keys = cells
            rows.append(Row(_command_path(usage, parser), usage, keys, number))
    return rows


# --- the parser ------------------------------------------------------------------
def _subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def _parsers() -> dict[tuple[str, ...], argparse.ArgumentParser]:
    """Every parser of ``workbench.cli.main``, by command path (() the top one)."""
    found: dict[tuple[str, ...], argparse.ArgumentParser] = {}

    def visit(parser: argparse.ArgumentParser, path: tuple[str, ...]) -> None:
        found[path] = parser
        for name, sub in _subcommands(parser).items():
            visit(sub, (*path, name))

    visit(build_parser(), ())
    return found


PARSERS = _parsers()
ROWS = _rows()


def _options(parser: argparse.ArgumentParser) -> dict[str, argparse.Action]:
    return {
        option: action
        for action in parser._actions
        for option in action.option_strings
        if option not in HELP
    }


def _name(path: tuple[str, ...]) -> str:
    return " ".join(("workbench", *path))


# --- Python names ------------------------------------------------------------------
def _resolve(module: ModuleType, dotted: str) -> bool:
    value: Any = module
    for part in dotted.split("."):
        if not hasattr(value, part):
            submodule = f"{getattr(value, '__name__', '')}.{part}"
            if not isinstance(value, ModuleType):
                return False
            try:
                value = importlib.import_module(submodule)
            except ModuleNotFoundError:
                return False
            continue
        value = getattr(value, part)
    return True


def test_every_imported_name_resolves() -> None:
    missing = []
    for line in IMPORTS:
        module = importlib.import_module(line.module)
        missing += [f"{line}: no {n}" for n in line.names if not hasattr(module, n)]
    assert not missing, "names of the contract that do not resolve:\n" + "\n".join(
        missing
    )


def test_imports_come_from_packages() -> None:
    """``from workbench.ik import x``, never ``from workbench.ik.solver import x``.

    The modules directly under ``workbench`` (``workbench.validation``) are
    their own package (layer 0 of ``docs/interface.md``).
    """
    deep = [
        f"{line} (a module of a package; import from {line.module.rsplit('.', 1)[0]})"
        for line in IMPORTS
        if line.module.count(".") > 1
    ]
    assert not deep, "import lines into modules, not packages:\n" + "\n".join(deep)


PACKAGE = Path(__file__).resolve().parents[1] / "workbench"
ROOT = PACKAGE.parent
PACKAGES = sorted(p.name for p in PACKAGE.iterdir() if (p / "__init__.py").is_file())
#: ``from workbench.<package>.<module> import``, in a page or a notebook cell.
DEEP_IMPORT = re.compile(r"from (workbench\.\w+\.\w+[\w.]*) import")


@pytest.mark.parametrize("package", PACKAGES)
def test_every_package_exports_through_its_init(package: str) -> None:
    """Each package's ``__init__`` lists its public names in ``__all__``."""
    module = importlib.import_module(f"workbench.{package}")
    names = getattr(module, "__all__", None)
    assert names, f"workbench.{package} has no __all__"
    missing = [name for name in names if not hasattr(module, name)]
    assert not missing, f"workbench.{package}.__all__ names what it lacks: {missing}"
    private = [name for name in names if name.startswith("_")]
    assert not private, f"workbench.{package}.__all__ exports private names: {private}"


def _pages() -> list[Path]:
    return [
        ROOT / "README.md",
        *sorted((ROOT / "docs").glob("*.md")),
        *sorted((ROOT / "notebooks").glob("*.ipynb")),
    ]


def test_pages_import_from_packages() -> None:
    """README, docs and notebooks import public names from packages too."""
    deep = [
        f"{page.relative_to(ROOT)}:{number}: from {match} import"
        for page in _pages()
        for number, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1)
        for match in DEEP_IMPORT.findall(line)
    ]
    assert not deep, "imports from modules inside packages:\n" + "\n".join(deep)


def _module_aliases() -> dict[str, str]:
    """Modules imported whole in the blocks: ``from workbench import ik`` -> ik."""
    aliases = {}
    for line in IMPORTS:
        module = importlib.import_module(line.module)
        for name in line.names:
            if isinstance(getattr(module, name, None), ModuleType):
                aliases[name] = f"{line.module}.{name}"
    return aliases


def test_module_attributes_resolve() -> None:
    """``ik.analytic``, ``singularities.compute_joint_grid`` (comments too)."""
    aliases = _module_aliases()
    assert {"ik", "trajectory", "planning", "singularities"} <= set(aliases)
    pattern = re.compile(
        rf"(?<![\w./-])({'|'.join(map(re.escape, aliases))})\.(\w+(?:\.\w+)*)"
    )
    missing = []
    for number, line in _block_lines():
        for alias, dotted in pattern.findall(line):
            if not _resolve(importlib.import_module(aliases[alias]), dotted):
                missing.append(f"docs/interface.md:{number}: {alias}.{dotted}")
    assert not missing, "names of the contract that do not resolve:\n" + "\n".join(
        missing
    )


def test_robot_attributes_resolve(puma) -> None:
    missing = []
    for number, line in _block_lines():
        for name in re.findall(r"(?<![\w.])robot\.(\w+)", line):
            if not hasattr(puma, name):
                missing.append(f"docs/interface.md:{number}: robot.{name}")
    assert not missing, "Robot has no:\n" + "\n".join(missing)


def test_dotted_workbench_names_resolve() -> None:
    """``workbench.json_numbers.to_json_ready``, ``workbench.DISTRIBUTION`` ..."""
    import workbench

    missing = []
    for number, line in enumerate(LINES, start=1):
        for dotted in re.findall(r"(?<![\w./-])workbench((?:\.\w+)+)", line):
            if not _resolve(workbench, dotted.lstrip(".")):
                missing.append(f"docs/interface.md:{number}: workbench{dotted}")
    assert not missing, "names of the contract that do not resolve:\n" + "\n".join(
        missing
    )


# --- command-line flags ------------------------------------------------------------
def test_every_command_has_one_row() -> None:
    leaves = {p for p, parser in PARSERS.items() if not _subcommands(parser)}
    rows = [row.path for row in ROWS]
    assert sorted(set(rows)) == sorted(rows), "commands with two rows"
    missing = sorted(_name(p) for p in (leaves | {()}) - set(rows))
    assert not missing, f"commands without a row in the command table: {missing}"
    assert set(rows) <= leaves | {()}, "rows of no command"  # () the options before it


def test_groups_have_no_options() -> None:
    """``workbench plan`` and the like only hold subcommands."""
    groups = [p for p, parser in PARSERS.items() if p and _subcommands(parser)]
    extra = {_name(p): sorted(_options(PARSERS[p])) for p in groups}
    assert not any(extra.values()), extra


@pytest.mark.parametrize("row", ROWS, ids=lambda row: _name(row.path))
def test_usage_lists_exactly_the_parser_flags(row: Row) -> None:
    options = _options(PARSERS[row.path])
    listed = set(FLAG.findall(row.usage))
    for flag, implied in IMPLIED.items():
        if flag in listed:
            listed.update(implied)
    where = f"docs/interface.md:{row.line} `{_name(row.path)}`"
    unknown = sorted(listed - set(options))
    assert not unknown, f"{where} lists flags the parser does not have: {unknown}"
    unlisted = sorted(set(options) - listed)
    assert not unlisted, f"{where} does not list the parser's flags: {unlisted}"


@pytest.mark.parametrize("row", ROWS, ids=lambda row: _name(row.path))
def test_choices_are_the_parser_choices(row: Row) -> None:
    options = _options(PARSERS[row.path])
    for flag, written in CHOICES.findall(row.usage):
        choices = options[flag].choices
        assert choices is not None, f"{_name(row.path)} {flag}: no fixed choices"
        assert set(written.split("\\|")) == set(choices), (
            f"docs/interface.md:{row.line} `{_name(row.path)} {flag}`: "
            f"lists {written.split(chr(92) + '|')}, the parser takes {list(choices)}"
        )


def _prose_flags() -> Iterator[tuple[tuple[str, ...], str, str]]:
    """(command path, flag, code span) of each ``command --flag`` span outside the
    table and the blocks (a group with one subcommand stands for it: ``plan``)."""
    parser = PARSERS[()]
    text = "\n".join(
        line for line in _text_outside_blocks().splitlines() if not line.startswith("|")
    )
    for span in _code_spans(text):
        words = span.split()
        if words and words[0] == "workbench":
            words = words[1:]
        path: tuple[str, ...] = ()
        current = parser
        for word in words:
            choices = _subcommands(current)
            if word not in choices:
                break
            path, current = (*path, word), choices[word]
        if not path:
            continue
        while len(_subcommands(current)) == 1:
            ((name, current),) = _subcommands(current).items()
            path = (*path, name)
        for flag in FLAG.findall(span):
            yield path, flag, span


def test_flags_named_in_the_text_exist() -> None:
    missing = [
        f"`{span}`: {_name(path)} has no {flag}"
        for path, flag, span in _prose_flags()
        if flag not in _options(PARSERS[path]) and flag not in HELP
    ]
    assert not missing, "flags of the text the parser does not have:\n" + "\n".join(
        missing
    )


# --- JSON keys ---------------------------------------------------------------------
def _row(path: tuple[str, ...]) -> Row:
    (row,) = [row for row in ROWS if row.path == path]
    return row


def _keys_text(row: Row, seen: tuple[tuple[str, ...], ...] = ()) -> str:
    """The row's JSON cell with the cells of the rows it takes the keys of."""
    text = row.json_keys
    for command in KEYS_OF.findall(text):
        path = tuple(command.split())
        if path not in seen and path != row.path:
            text += " " + _keys_text(_row(path), (*seen, row.path))
    return text


def _json_keys(value: Any, data_keyed: set[str], path: str = "") -> Iterator[str]:
    """Every key name in a JSON value, with its path (keys of data dicts skipped)."""
    if isinstance(value, dict):
        data = path.rsplit(".", 1)[-1] in data_keyed
        for key, item in value.items():
            below = f"{path}.{'*' if data else key}".lstrip(".")
            if not data:
                yield below
            yield from _json_keys(item, data_keyed, below)
    elif isinstance(value, list):
        for item in value:
            yield from _json_keys(item, data_keyed, path + "[]")


@pytest.fixture(scope="module")
def inputs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder with a DH table, a small workspace map and a task CSV."""
    from tests._cli_fuzz import DH_ROW, SMALL_MAP
    from workbench.cli import main

    folder = tmp_path_factory.mktemp("contract")
    (folder / "t.json").write_text(json.dumps({"name": "t", "joints": [DH_ROW] * 6}))
    assert main(["-q", *SMALL_MAP, str(folder / "map.zarr")]) == 0
    plan = f"plan pick-place --robot puma560 --pick-deg {ZERO6} --place-deg 10 "
    plan += "0 0 0 0 0 --duration 1 --rate 10 --no-collision --csv"
    assert main(["-q", *plan.split(), str(folder / "traj.csv")]) == 0
    from workbench import load_robot
    from workbench.collision import get_angeles_obstacle_scene, write_scene

    write_scene(
        get_angeles_obstacle_scene(load_robot("puma560")), folder / "obstacle.json"
    )
    (folder / "task.csv").write_text(
        "x,y,z,qx,qy,qz,qw\n0.45,0.1,0.3,1,0,0,0\n0.4,-0.1,0.35,1,0,0,0\n"
    )
    return folder


PICK = "0.5 0.1 0.3 0 1 0 0"
MBM_PANDA = Path(__file__).parent / "data" / "motionbenchmaker" / "panda"
PLACE = "0.4 -0.3 0.4 0 1 0 0"
ZERO6 = "0 0 0 0 0 0"
REPORT = "report singularities --grid 4 --svd-grid 4 --no-progress --robot"
#: One small case per command and per kind of output it has (six and seven axes,
#: closed form and numeric, feasible and not); ``{dir}`` is the inputs folder.
JSON_CASES = {
    "fk": f"fk --robot puma560 --deg {ZERO6}",
    "ik-6r": f"ik --robot puma560 --xyz-quat-wxyz {PICK} --all",
    "ik-7r": f"ik --robot iiwa14 --xyz-quat-wxyz {PICK} --feasible",
    "ik-numeric": f"ik --robot generic6r --xyz-quat-wxyz {PICK}",
    "ik-out-of-reach": "ik --robot puma560 --xyz-quat-wxyz 5 0 0 1 0 0 0",
    "singularities-6r": f"singularities --robot puma560 --deg {ZERO6}",
    "singularities-7r": "singularities --robot iiwa14 --deg 10 10 10 10 10 10 10",
    **{
        f"report-{robot}": f"{REPORT} {robot} --out {{dir}}/{robot}.html"
        for robot in ("puma560", "ur5", "iiwa14", "panda")
    },
    "report-trajectory": (
        f"{REPORT} puma560 --trajectory {{dir}}/traj.csv --out {{dir}}/traj.html"
    ),
    "plan-joint-values": (
        "plan pick-place --robot puma560 --pick-deg 0 45 200 -100 30 10 "
        "--place-deg 150 -100 -10 100 -70 170 --duration 10 --rate 20"
    ),
    "plan-avoid": (
        "plan pick-place --robot puma560 --pick-deg 0 45 200 -100 30 10 "
        "--place-deg 150 -100 -10 100 -70 170 --duration 10 --rate 20 "
        "--scene {dir}/obstacle.json --acceleration-limit 4 --avoid"
    ),
    "plan-7r-poses": (
        f"plan pick-place --robot iiwa14 --pick-xyz-quat-wxyz {PICK} "
        f"--place-xyz-quat-wxyz {PLACE} --duration 2 --rate 20"
    ),
    "urdf-from-dh": "urdf from-dh {dir}/t.json --out {dir}/t.urdf",
    "urdf-srdf": "urdf srdf --robot puma560",
    "fishcut-6r": "fishcut",
    "fishcut-7r": "fishcut --robot iiwa14 --no-collision",
    "export": "export --format csv --pick-place --no-collision --out {dir}/e.csv",
    "workspace-map": (
        "workspace map --robot puma560 --resolution 0.4 --orientations 8 "
        "--workers 1 --out {dir}/m.zarr"
    ),
    "workspace-place": (
        "workspace place --robot puma560 --map {dir}/map.zarr --region 0 0.4 0 0.4 "
        "--resolution 0.2 --yaw-step 90 --top 2 --targets {dir}/task.csv"
    ),
    "workspace-report": "workspace report {dir}/map.zarr --out {dir}/w.html",
    "demo": "demo --out {dir}/demo --no-plots",
    "motion-bench": (
        f"motion bench {MBM_PANDA} --robot {MBM_PANDA}/panda.urdf "
        "--acceleration-limit 15 --scenario table_pick --no-verify"
    ),
}


@pytest.mark.slow
@pytest.mark.parametrize("case", JSON_CASES)
def test_every_json_key_is_listed(case: str, capsys, inputs) -> None:
    argv = JSON_CASES[case].replace("{dir}", str(inputs)).split()
    if case == "demo":
        shutil.rmtree(inputs / "demo", ignore_errors=True)
    code, out, err = run_cli(capsys, *argv, "--json")
    assert code in (0, 3), f"{' '.join(argv)}: exit {code}: {err}"
    parser = PARSERS[()]
    path = _command_path(f"`workbench {' '.join(argv)}`", parser)
    row = _row(path)
    text = _keys_text(row)
    data_keyed = set(DATA_KEY.findall(text))
    printed = sorted(set(_json_keys(json.loads(out), data_keyed)))
    unlisted = [
        key
        for key in printed
        if not re.search(rf"(?<![\w-]){re.escape(key.rsplit('.', 1)[-1])}(?!\w)", text)
    ]
    assert not unlisted, (
        f"docs/interface.md:{row.line} `{_name(path)}` (JSON keys) does not list "
        f"keys that `{' '.join(argv[:3])} ... --json` prints: {unlisted}"
    )
