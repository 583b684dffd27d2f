"""Shared fixtures: session-scoped robots and a seeded random generator."""

from __future__ import annotations

import os
import sys

import numpy as np
import pytest
from hypothesis import settings

from workbench import Robot, load_robot

# Property tests draw the same examples on every run: CI cannot flake on a rare draw.
settings.register_profile("workbench", derandomize=True, deadline=None)
settings.load_profile("workbench")

PUMA_NAMES = ("puma560", "puma560-kang")

# Bytecode is cached even where PYTHONDONTWRITEBYTECODE is set (as in many container
# images): each of the suite's Python processes (pytest-xdist workers, command-line
# runs, notebook kernels) would otherwise compile every module it imports from
# source again, a few seconds each. Set here, before the workers start.
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
sys.dont_write_bytecode = False

# No progress lines from the command line (tests compare stderr exactly; a loaded
# machine or a cold Numba cache would add one). test_cli_habits turns them on.
os.environ["WORKBENCH_PROGRESS"] = "0"

#: Files run first: the documentation build executes every notebook (about a
#: minute in one worker), so it starts at once and overlaps everything else.
_FIRST = ("test_docs.py",)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """The slowest file first (pytest-xdist then keeps this order, pyproject.toml)."""
    items.sort(key=lambda item: item.path.name not in _FIRST)  # stable sort


@pytest.fixture(scope="session")
def puma() -> Robot:
    """Angeles' PUMA 560 (Table I)."""
    return load_robot("puma560")


@pytest.fixture(scope="session")
def puma_kang() -> Robot:
    """Kang's PUMA 560 (Table 1)."""
    return load_robot("puma560-kang")


@pytest.fixture(scope="session", params=PUMA_NAMES)
def any_puma(request: pytest.FixtureRequest) -> Robot:
    """Each PUMA model in turn."""
    return load_robot(request.param)


@pytest.fixture()
def rng() -> np.random.Generator:
    """A seeded generator (numpy seeding does not control pin.randomConfiguration)."""
    return np.random.default_rng(0)


def random_configurations(
    robot: Robot, rng: np.random.Generator, count: int
) -> np.ndarray:
    """``count`` configurations uniform within the joint limits, shape (count, nq)."""
    return rng.uniform(robot.lower, robot.upper, size=(count, robot.nq))


def run_cli(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    """Run the command line in-process: (exit code, stdout, stderr)."""
    from workbench.cli import main

    try:
        code = main(list(argv))
    except SystemExit as exit_:  # argparse's own errors
        code = int(exit_.code or 0)
    out, err = capsys.readouterr()
    return code, out, err
