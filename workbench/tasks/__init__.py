"""Tasks built on the online planner: Kang's fish cutting on a simulated fish."""

from workbench.tasks.cuts import HorizontalCut, VerticalDownCut
from workbench.tasks.fish import SimulatedFish
from workbench.tasks.fish_cutting import FishCuttingResult, FishEvent, run_fish_cutting
from workbench.tasks.fish_program import FishCuttingSetup, build_program

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
