# Stub of pinocchio.rpy: roll-pitch-yaw angles [rad] <-> rotation matrices.

from typing import overload

import numpy as np
import numpy.typing as npt

@overload
def rpyToMatrix(rpy: npt.ArrayLike) -> npt.NDArray[np.float64]: ...
@overload
def rpyToMatrix(roll: float, pitch: float, yaw: float) -> npt.NDArray[np.float64]: ...
def matrixToRpy(rotation: npt.ArrayLike) -> npt.NDArray[np.float64]: ...
