"""Tasks built on the online planner: Kang's fish cutting on a simulated fish.

Any OPW or UR-type arm runs it in Kang's cell scaled to its reach
(:func:`get_cell_scale`; 1 for the PUMA models).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from workbench._lazy import attach

if TYPE_CHECKING:
    from workbench.tasks.cuts import HorizontalCut, VerticalDownCut
    from workbench.tasks.fish import SimulatedFish
    from workbench.tasks.fish_cutting import (
        FishCuttingResult,
        FishEvent,
        run_fish_cutting,
    )
    from workbench.tasks.fish_program import (
        FOLD_MARGIN,
        KANG_START_FOLD,
        FishCuttingSetup,
        build_program,
        get_base_placement,
        get_cell_scale,
        get_shortest_fold,
    )
    from workbench.tasks.fish_scene import (
        compute_fish_cutting_clearance,
        get_fish_cutting_scene,
    )

__all__ = [
    "FOLD_MARGIN",
    "KANG_START_FOLD",
    "FishCuttingResult",
    "FishCuttingSetup",
    "FishEvent",
    "HorizontalCut",
    "SimulatedFish",
    "VerticalDownCut",
    "build_program",
    "compute_fish_cutting_clearance",
    "get_base_placement",
    "get_cell_scale",
    "get_fish_cutting_scene",
    "get_shortest_fold",
    "run_fish_cutting",
]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
