"""The papers' examples end to end (``workbench demo``)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from workbench._lazy import attach

if TYPE_CHECKING:
    from workbench.demo.avoid import format_avoid, run_avoid_demo
    from workbench.demo.base_placement import (
        format_base_placement,
        run_base_placement_demo,
    )
    from workbench.demo.pick_and_place import (
        format_pick_and_place,
        run_pick_and_place_demo,
    )
    from workbench.demo.run import (
        Table2Comparison,
        compare_table2,
        format_fish_cutting,
        format_table2,
        run_demo,
    )

__all__ = [
    "Table2Comparison",
    "compare_table2",
    "format_avoid",
    "format_base_placement",
    "format_fish_cutting",
    "format_pick_and_place",
    "format_table2",
    "run_avoid_demo",
    "run_base_placement_demo",
    "run_demo",
    "run_pick_and_place_demo",
]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
