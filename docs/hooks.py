"""MkDocs hooks: the CLI reference from the parser, Sphinx roles as links.

``docs/cli.md`` holds the marker ``<!-- workbench-cli-help -->``; it is replaced
by the ``--help`` text of every command and subcommand, so the page cannot drift
from the code.

The docstrings keep Sphinx's roles (``:func:`name```, ``:class:`~a.b.C```...),
which read well in an editor; :class:`SphinxRoles`, a Griffe extension that
``mkdocs.yml`` hands to mkdocstrings, turns each into a cross-reference before
the docstring is rendered. The name is resolved as Python would from where the
docstring sits (the object, then its parents, following imports); mkdocs-autorefs
links it to the page that documents the target, and shows plain code when no
page does (a private module, numpy, Pinocchio). ``:math:`...``` roles and
``.. math::`` blocks become MathML (latex2mathml), which browsers draw with no
script, offline.
"""

from __future__ import annotations

import argparse
import html
import os
import re
from typing import Any

import griffe
from latex2mathml.converter import convert as latex_to_mathml

MARKER = "<!-- workbench-cli-help -->"
#: A cross-reference role: ``:kind:`target```, ``:kind:`~target``` (show the
#: last part only) or ``:kind:`title <target>```.
ROLE = re.compile(
    r":(?:py:)?(?P<kind>func|class|meth|mod|data|attr|exc|obj|const):"
    r"`(?P<tilde>~?)(?P<text>[^`<]+?)(?:\s*<(?P<target>[^`>]+)>)?`"
)
#: An inline formula: ``:math:`LaTeX```.
MATH_ROLE = re.compile(r":math:`(?P<latex>[^`]+)`")
#: A displayed formula: ``.. math::``, LaTeX on that line or the indented ones.
MATH_DIRECTIVE = re.compile(r"^(?P<indent>\s*)\.\. math::\s*(?P<latex>.*)$")
#: LaTeX operators latex2mathml does not know, as ``\operatorname``.
UNKNOWN_OPERATORS = re.compile(r"\\(arg)(?![A-Za-z])")
#: The package whose docstrings are rewritten.
PACKAGE = "workbench"


def _subcommands(
    parser: argparse.ArgumentParser,
) -> list[tuple[str, argparse.ArgumentParser]]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return list(action.choices.items())
    return []


def _walk(
    parser: argparse.ArgumentParser, words: tuple[str, ...]
) -> list[tuple[str, str]]:
    pages = [(" ".join(words), parser.format_help())]
    for name, sub in _subcommands(parser):
        pages += _walk(sub, (*words, name))
    return pages


def render_cli_reference() -> str:
    """Markdown: one section per command, its help in a code block."""
    os.environ["COLUMNS"] = "88"  # argparse wraps help to the terminal width
    from workbench.cli import build_parser

    parts = []
    for command, text in _walk(build_parser(), ("workbench",)):
        level = "##" if command.count(" ") <= 1 else "###"
        parts.append(f"{level} `{command}`\n\n```text\n{text.rstrip()}\n```\n")
    return "\n".join(parts)


def on_page_markdown(markdown: str, page: Any, config: Any, files: Any) -> str:
    """Fill the CLI reference page."""
    if MARKER in markdown:
        return markdown.replace(MARKER, render_cli_reference())
    return markdown


def _resolve(scope: griffe.Object, name: str) -> str:
    """Full path of ``name`` seen from ``scope``: its members, then its parents'."""
    name = name.lstrip(".")
    if name == PACKAGE or name.startswith(PACKAGE + "."):
        return name
    first, _, rest = name.partition(".")
    current: griffe.Object | None = scope
    while current is not None:
        has_members = current.is_module or current.is_class
        member = current.members.get(first) if has_members else None
        if member is not None:
            path = member.target_path if member.is_alias else member.path
            return f"{path}.{rest}" if rest else path
        current = current.parent
    return name  # outside the package (numpy, pinocchio...): left to autorefs


def link_roles(text: str, scope: griffe.Object) -> str:
    """``text`` with every Sphinx role turned into an optional autorefs link."""

    def replace(match: re.Match[str]) -> str:
        target = (match["target"] or match["text"]).strip()
        shown = match["text"].strip()
        if match["tilde"]:
            shown = shown.rsplit(".", 1)[-1]
        identifier = html.escape(_resolve(scope, target), quote=True)
        return (
            f'<autoref identifier="{identifier}" optional>'
            f"<code>{html.escape(shown)}</code></autoref>"
        )

    return ROLE.sub(replace, text)


def _mathml(latex: str, *, block: bool) -> str:
    """MathML of a LaTeX formula; the LaTeX as code if it cannot be converted."""
    latex = UNKNOWN_OPERATORS.sub(r"\\operatorname{\1}", " ".join(latex.split()))
    try:
        mathml = latex_to_mathml(latex, display="block" if block else "inline")
    except Exception:  # latex2mathml raises its own and plain exceptions
        return f"<code>{html.escape(latex)}</code>"
    # Markdown takes a line that starts with <math> for an HTML block: a span
    # keeps an inline formula inside its paragraph.
    return mathml if block else f'<span class="math">{mathml}</span>'


def render_math(text: str) -> str:
    """``text`` with its ``.. math::`` blocks and ``:math:`` roles as MathML."""
    lines, out, i = text.split("\n"), [], 0
    while i < len(lines):
        directive = MATH_DIRECTIVE.match(lines[i])
        i += 1
        if directive is None:
            out.append(lines[i - 1])
            continue
        indent = directive["indent"]
        body = [directive["latex"]] if directive["latex"].strip() else []
        while i < len(lines):
            line = lines[i]
            if not line.strip():
                if body:
                    break  # a blank line after the formula ends it
            elif len(line) - len(line.lstrip()) <= len(indent):
                break  # back to the text
            else:
                body.append(line.strip())
            i += 1
        out.append(indent + _mathml(" ".join(body), block=True))
    return MATH_ROLE.sub(lambda m: _mathml(m["latex"], block=False), "\n".join(out))


class SphinxRoles(griffe.Extension):
    """Griffe extension: the package's Sphinx roles become links and MathML."""

    def on_package(self, *, pkg: griffe.Module, **kwargs: Any) -> None:
        """Rewrite every docstring of the package once it is loaded."""
        if pkg.name == PACKAGE:
            _rewrite(pkg)


def _rewrite(obj: griffe.Object) -> None:
    if obj.docstring is not None:
        scope = obj if obj.is_module or obj.is_class else obj.parent or obj
        obj.docstring.value = link_roles(render_math(obj.docstring.value), scope)
    for member in obj.members.values():
        if not member.is_alias:
            _rewrite(member)
