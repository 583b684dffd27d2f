"""Motion around obstacles: requests and scenes in the ecosystem's formats.

:mod:`.requests` reads MoveIt motion requests (start and joint goal) as
configurations of a robot; MoveIt planning scenes are read by
:func:`workbench.collision.read_scene`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from workbench._lazy import attach

if TYPE_CHECKING:
    from workbench.motion.requests import MotionRequest, read_request

__all__ = ["MotionRequest", "read_request"]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
