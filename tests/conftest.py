"""Shared fixtures: session-scoped robots and a seeded random generator."""

from __future__ import annotations

import fcntl
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

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


#: Markers that make a test slow as well (the fast tier leaves them out).
_SLOW_TIERS = ("browser", "docs")


@pytest.hookimpl(tryfirst=True)  # before ``-m`` deselects by these markers
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Mark the tiers, then put the slowest file first.

    A test that uses the ``chromium`` fixture is a ``browser`` test; every
    ``browser`` and ``docs`` test is ``slow`` too (``docs/development.md``).
    pytest-xdist then keeps this order (pyproject.toml).
    """
    for item in items:
        if "chromium" in getattr(item, "fixturenames", ()):
            item.add_marker(pytest.mark.browser)
        if any(item.get_closest_marker(tier) for tier in _SLOW_TIERS):
            item.add_marker(pytest.mark.slow)
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


def _apt_get(*args: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
    return subprocess.run(
        ["apt-get", *args], env=env, capture_output=True, text=True, timeout=1200
    )


@pytest.fixture(scope="session")
def chromium() -> str:
    """Path of the chromium binary, installed with apt-get when missing (root).

    Test workers (pytest -n) each run this fixture: a file lock lets one of them
    install while the others wait, instead of racing for dpkg's own lock.
    """
    lock = Path(tempfile.gettempdir()) / "workbench-chromium-install.lock"
    with lock.open("w") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        return _find_or_install_chromium()


def _find_or_install_chromium() -> str:
    found = shutil.which("chromium")
    if found:
        return found
    if shutil.which("apt-get") is None:
        pytest.skip("chromium is missing and there is no apt-get to install it")
    if not hasattr(os, "geteuid") or os.geteuid() != 0:
        pytest.skip(
            "chromium is missing; installing it needs root: apt-get install -y chromium"
        )
    result = _apt_get("install", "-y", "chromium")
    if result.returncode != 0:  # stale or empty package lists
        _apt_get("update")
        result = _apt_get("install", "-y", "chromium")
    found = shutil.which("chromium")
    if result.returncode != 0 or found is None:
        reason = (result.stderr.strip().splitlines() or ["no output"])[-1]
        pytest.skip(f"cannot install chromium with apt-get: {reason}")
    return found
