"""What every report builder returns: the HTML page, its key numbers, its figures."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True, slots=True)
class HtmlReport:
    """A built report.

    Attributes:
        html: The whole HTML document.
        summary: JSON-ready key numbers (what ``--json`` prints).
        figures: PNG images by name, as embedded in ``html``.
    """

    html: str
    summary: dict[str, Any]
    figures: dict[str, bytes]


__all__ = ["HtmlReport"]
