"""MkDocs hooks: the command-line reference, generated from the parser itself.

``docs/cli.md`` holds the marker ``<!-- workbench-cli-help -->``; it is replaced
by the ``--help`` text of every command and subcommand, so the page cannot drift
from the code.
"""

from __future__ import annotations

import argparse
import os
from typing import Any

MARKER = "<!-- workbench-cli-help -->"


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
