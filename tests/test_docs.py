"""The documentation site builds in strict mode, with executed notebooks.

The build executes every notebook (``mkdocs-jupyter``, ``allow_errors: false``): it
is how the test suite runs them, once. pytest-xdist runs the tests of a file in one
worker (``--dist loadfile``, pyproject.toml), so the site is built once.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from workbench.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """Build the site once: strict (no broken link, no missing reference)."""
    pytest.importorskip("mkdocs")
    pytest.importorskip("mkdocs_jupyter")
    out = tmp_path_factory.mktemp("site")
    result = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
        cwd=ROOT,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"},
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert result.returncode == 0, result.stderr[-6000:]
    return out


def test_every_page_is_built(site) -> None:
    for page in (
        "index.html",
        "getting-started/index.html",
        "cli/index.html",
        "interface/index.html",
        "papers/index.html",
        "errata-kang-ik/index.html",
        "api/ik/index.html",
    ):
        assert (site / page).is_file(), page


@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=lambda path: path.stem)
def test_notebook_is_executed_with_its_figures(site, notebook: Path) -> None:
    page = (site / "notebooks" / notebook.stem / "index.html").read_text("utf-8")
    assert "jp-OutputArea-output" in page, f"no output in {notebook.name}"
    if notebook.stem.startswith(("03", "04", "05", "06")):
        assert "data:image/png;base64" in page, f"no figure in {notebook.name}"


def test_cli_page_has_every_command(site) -> None:
    page = (site / "cli" / "index.html").read_text("utf-8")
    for action in build_parser()._actions:
        for command in getattr(action, "choices", None) or {}:
            assert f"workbench {command}" in page, command
    assert "usage: workbench urdf from-dh" in page


def test_api_reference_documents_public_names(site) -> None:
    page = (site / "api" / "ik" / "index.html").read_text("utf-8")
    for name in ("analytic", "analytic_batch", "numeric", "IKResult"):
        assert re.search(rf'id="workbench\.ik\.{name}"', page), name
