"""The documentation site builds in strict mode, with executed notebooks.

The build executes every notebook (``mkdocs-jupyter``, ``allow_errors: false``): it
is how the test suite runs them, once. pytest-xdist runs the tests of a file in one
worker (``--dist loadfile``, pyproject.toml), so the site is built once.
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import pytest

from workbench.cli import build_parser

pytestmark = pytest.mark.docs

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
#: Notebooks whose output is a 3D page, not a matplotlib figure.
PAGE_NOTEBOOKS = ("07_viewer",)
#: A Sphinx role left as text: ``:func:`` then a code span.
RAW_ROLE = re.compile(r":(?:func|class|meth|mod|data|attr|exc|obj):(?:<code>|`)")


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


@pytest.mark.subprocess
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


@pytest.mark.subprocess
@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=lambda path: path.stem)
def test_notebook_is_executed_with_its_figures(site, notebook: Path) -> None:
    page = (site / "notebooks" / notebook.stem / "index.html").read_text("utf-8")
    assert "jp-OutputArea-output" in page, f"no output in {notebook.name}"
    if notebook.stem not in PAGE_NOTEBOOKS:
        assert "data:image/png;base64" in page, f"no figure in {notebook.name}"


@pytest.mark.subprocess
def test_cli_page_has_every_command(site) -> None:
    page = (site / "cli" / "index.html").read_text("utf-8")
    for action in build_parser()._actions:
        for command in getattr(action, "choices", None) or {}:
            assert f"workbench {command}" in page, command
    assert "usage: workbench urdf from-dh" in page


@pytest.mark.subprocess
def test_api_reference_documents_public_names(site) -> None:
    page = (site / "api" / "ik" / "index.html").read_text("utf-8")
    for name in ("analytic", "analytic_batch", "numeric", "IKResult"):
        assert re.search(rf'id="workbench\.ik\.{name}"', page), name


@pytest.mark.subprocess
def test_api_pages_link_sphinx_roles(site) -> None:
    pages = sorted((site / "api").glob("*/index.html"))
    assert len(pages) >= 10
    links = 0
    for page in pages:
        text = page.read_text("utf-8")
        assert not RAW_ROLE.search(text), page
        assert "<autoref" not in text, page  # every one resolved or degraded
        links += len(
            re.findall(r'<a class="autorefs autorefs-internal"[^>]*><code>', text)
        )
    assert links >= 90  # of ~125 roles; the others name objects no page shows
    page = (site / "api" / "singularities" / "index.html").read_text("utf-8")
    assert re.search(
        r'<a class="autorefs autorefs-internal"[^>]*'
        r'href="#workbench\.singularities\.compute_wrist_point"><code>'
        r"compute_wrist_point</code></a>",
        page,
    )


@pytest.mark.subprocess
def test_not_found_page_links_from_the_site_root(site) -> None:
    page = (site / "404.html").read_text("utf-8")
    assert 'href="/assets/stylesheets/' in page
    assert 'href="/api/ik/"' in page
    assert "fonts.googleapis.com" not in page  # the site works offline


@pytest.fixture(scope="module")
def hooks() -> ModuleType:
    """``docs/hooks.py``, imported as MkDocs imports it (from its path)."""
    spec = importlib.util.spec_from_file_location(
        "docs_hooks", ROOT / "docs" / "hooks.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def package(hooks):
    """The workbench package as mkdocstrings loads it, with the roles extension."""
    import griffe

    extensions = griffe.load_extensions(hooks.SphinxRoles)
    return griffe.load("workbench", extensions=extensions)


def test_sphinx_roles_resolve_from_where_they_sit(hooks, package) -> None:
    report = package["reports.singularity_report"]
    assert hooks._resolve(report, "build_singularity_report") == (
        "workbench.reports.singularity_report.build_singularity_report"
    )
    start = package["viz._server.LiveServer.start"]
    assert hooks._resolve(start.parent, "url") == "workbench.viz._server.LiveServer.url"
    common = package["cli._common"]
    assert hooks._resolve(common, "InputError") == "workbench.errors.InputError"
    assert hooks._resolve(common, "numpy.linalg.det") == "numpy.linalg.det"


@pytest.mark.parametrize(
    ("role", "identifier", "shown"),
    [
        (":func:`build_singularity_report`", "build_singularity_report", None),
        (
            ":data:`~workbench.ik.DLS_EPSILON`",
            "workbench.ik.DLS_EPSILON",
            "DLS_EPSILON",
        ),
        (
            ":meth:`the report <write_singularity_report>`",
            "write_singularity_report",
            "the report",
        ),
        (":py:class:`SingularityReport`", "SingularityReport", None),
    ],
)
def test_sphinx_role_becomes_an_optional_autoref(
    hooks, package, role: str, identifier: str, shown: str | None
) -> None:
    scope = package["reports.singularity_report"]
    text = hooks.link_roles(f"See {role}.", scope)
    expected = hooks._resolve(scope, identifier)
    assert text == (
        f'See <autoref identifier="{expected}" optional>'
        f"<code>{shown or identifier}</code></autoref>."
    )


def test_no_docstring_keeps_a_role(package) -> None:
    def walk(obj):
        if obj.docstring is not None:
            yield obj.path, obj.docstring.value
        for member in obj.members.values():
            if not member.is_alias:
                yield from walk(member)

    left = [path for path, text in walk(package) if RAW_ROLE.search(text)]
    assert left == []


def test_math_becomes_mathml(hooks) -> None:
    text = "\n".join(
        [
            "A speed :math:`\\dot q_r` and",
            ":math:`J^\\#` at a line start.",
            "",
            "    .. math:: \\dot q = \\arg\\min",
            "              \\|J\\dot q\\|^2,",
            "",
            "after.",
        ]
    )
    out = hooks.render_math(text).split("\n")
    assert out[0].startswith('A speed <span class="math"><math ')
    assert out[1].startswith('<span class="math"><math ')  # inline, not a block
    assert out[3].startswith('    <math xmlns="http://www.w3.org/1998/Math/MathML"')
    assert 'display="block"' in out[3] and "<mo>arg</mo>" in out[3]
    assert out[4:] == ["", "after."]
    assert "\\" not in "".join(out)
    assert hooks.render_math(":math:`\\frac{1}{`") == "<code>\\frac{1}{</code>"


@pytest.mark.subprocess
def test_api_pages_draw_math(site) -> None:
    for page in sorted((site / "api").glob("*/index.html")):
        text = page.read_text("utf-8")
        assert ":math:" not in text and ".. math::" not in text, page
        formulas = re.findall(r"<math .*?</math>", text, flags=re.DOTALL)
        assert all("\\" not in f for f in formulas), page
    page = (site / "api" / "ik" / "index.html").read_text("utf-8")
    assert page.count("<math ") >= 10 and 'display="block"' in page
