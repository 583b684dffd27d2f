"""A command imports what it uses: ``fk`` and ``ik`` load no map, plot or viewer code.

Nor does ``workbench --help``, which registers every command (their arguments
are cheap to define). Nor Numba: ``fk`` runs no kernel, ``ik`` of one pose of a
six-axis arm runs them interpreted (``workbench._compiled.interpreted``).

Each case runs in a new Python process (this one has imported everything) and
lists the heavy packages in ``sys.modules`` after the command ran.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys

import pytest

pytestmark = pytest.mark.subprocess

#: Packages no ``fk`` or ``ik`` needs: the workspace maps' (Zarr, Dask), the
#: figures' and the viewer's.
NEVER = ("zarr", "dask", "distributed", "matplotlib", "meshcat")
#: Packages of the compiled kernels (and SciPy, which Numba imports).
KERNELS = ("numba", "llvmlite", "scipy")

_PROBE = """
import json, sys
from workbench.cli import main
code = main(sys.argv[1:])
modules = sorted({name.split(".")[0] for name in sys.modules})
print(json.dumps({"code": code, "modules": modules}))
"""

FK = ["fk", "--robot", "puma560", "--deg", "10", "20", "30", "40", "50", "60"]
IK = ["ik", "--robot", "puma560", "--xyz-quat-wxyz", "0.4", "0.1", "0.3"]
IK += ["0", "1", "0", "0"]


def _imported(*argv: str) -> tuple[int, set[str]]:
    """(exit code, top-level modules imported) of ``workbench ARGV``, a new process."""
    done = subprocess.run(
        [sys.executable, "-c", _PROBE, *argv],
        capture_output=True,
        text=True,
        check=True,
        timeout=300,
    )
    result = json.loads(done.stdout.splitlines()[-1])
    return result["code"], set(result["modules"])


@pytest.mark.parametrize(
    ("argv", "absent"),
    [
        (FK, NEVER + KERNELS),
        (["-q", *FK, "--json"], NEVER + KERNELS),
        (IK, NEVER + KERNELS),
        ([*IK[:2], "ur5", *IK[3:], "--all", "--json"], NEVER + KERNELS),
        (["ik", "--help"], NEVER + KERNELS),
        (["--help"], NEVER + KERNELS),
        (["workspace", "map", "--help"], NEVER + KERNELS),
    ],
    ids=["fk", "fk-json", "ik", "ik-ur5-all", "ik-help", "help", "workspace-help"],
)
def test_command_imports_only_what_it_uses(argv: list[str], absent: tuple) -> None:
    code, modules = _imported(*argv)
    assert code == 0
    assert "pinocchio" in modules  # the probe sees what the command imported
    assert sorted(modules & set(absent)) == []


def test_help_lists_every_command() -> None:
    """``workbench --help`` still lists every command (the whole parser)."""
    done = subprocess.run(
        [sys.executable, "-m", "workbench", "--help"],
        capture_output=True,
        text=True,
        check=True,
        timeout=300,
    )
    from workbench.cli import _COMMANDS

    listed = set(re.findall(r"^    (\w+)", done.stdout, flags=re.MULTILINE))
    assert listed >= set(_COMMANDS)
