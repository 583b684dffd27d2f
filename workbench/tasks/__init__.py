"""Tasks built on the online planner: Kang's fish cutting on a simulated fish."""

from workbench.tasks.cuts import HorizontalCut, VerticalDownCut
from workbench.tasks.fish import SimulatedFish
from workbench.tasks.fish_cutting import (
    FishCuttingResult,
    FishCuttingSetup,
    FishEvent,
    build_program,
    run_fish_cutting,
)

__all__ = [
    "FishCuttingResult",
    "FishCuttingSetup",
    "FishEvent",
    "HorizontalCut",
    "SimulatedFish",
    "VerticalDownCut",
    "build_program",
    "run_fish_cutting",
]
