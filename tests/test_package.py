"""Packaging: public names, entry point, no hidden imports of viewers."""

from __future__ import annotations

import importlib.metadata
import subprocess
import sys

import pytest

import workbench


def test_all_names_exist_and_are_sorted() -> None:
    assert workbench.__all__ == sorted(workbench.__all__)
    missing = [name for name in workbench.__all__ if not hasattr(workbench, name)]
    assert missing == []


def test_console_script_points_at_main() -> None:
    scripts = importlib.metadata.entry_points(group="console_scripts")
    (entry,) = [e for e in scripts if e.name == "workbench"]
    assert entry.load() is workbench.cli.main


@pytest.mark.slow
@pytest.mark.subprocess
def test_core_import_does_not_pull_viewers_or_pyplot() -> None:
    code = (
        "import sys, workbench, workbench.ik;"
        "print(any(m in sys.modules for m in ('matplotlib.pyplot', 'meshcat')))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    )
    assert out.stdout.strip() == "False"


@pytest.mark.slow
@pytest.mark.subprocess
def test_help_lists_every_command() -> None:
    out = subprocess.run(
        [sys.executable, "-m", "workbench", "--help"], capture_output=True, text=True
    )
    assert out.returncode == 0
    for command in ("fk", "urdf", "demo"):
        assert command in out.stdout
