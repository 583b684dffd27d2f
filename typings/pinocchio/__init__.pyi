# Type stubs for the part of Pinocchio (the `pin` wheel, a Boost.Python extension
# without annotations) that workbench uses: its typed boundary. mypy reads them
# through `mypy_path = "typings"` in pyproject.toml; they are not shipped.
# Arrays are float64 NumPy arrays, as Pinocchio's Eigen bindings return them.

from collections.abc import Iterator, Sequence
from enum import Enum
from typing import Any, overload

import numpy as np
import numpy.typing as npt
from pinocchio import rpy as rpy

_Array = npt.NDArray[np.float64]
_ArrayLike = npt.ArrayLike

class ReferenceFrame(Enum):
    WORLD = 0
    LOCAL = 1
    LOCAL_WORLD_ALIGNED = 2

class FrameType(Enum):
    OP_FRAME = 1
    JOINT = 2
    FIXED_JOINT = 4
    BODY = 8
    SENSOR = 16

class GeometryType(Enum):
    VISUAL = 0
    COLLISION = 1

class SE3:
    rotation: _Array
    translation: _Array
    @overload
    def __init__(self) -> None: ...
    @overload
    def __init__(self, rotation: _ArrayLike, translation: _ArrayLike) -> None: ...
    @overload
    def __init__(self, homogeneous: _ArrayLike) -> None: ...
    @overload
    def __init__(self, other: SE3) -> None: ...
    @property
    def homogeneous(self) -> _Array: ...
    def inverse(self) -> SE3: ...
    @overload
    def act(self, other: SE3) -> SE3: ...
    @overload
    def act(self, point: _ArrayLike) -> _Array: ...
    @overload
    def actInv(self, other: SE3) -> SE3: ...
    @overload
    def actInv(self, point: _ArrayLike) -> _Array: ...
    def isApprox(self, other: SE3, prec: float = ...) -> bool: ...
    def copy(self) -> SE3: ...
    @overload
    def __mul__(self, other: SE3) -> SE3: ...
    @overload
    def __mul__(self, other: _ArrayLike) -> _Array: ...
    @staticmethod
    def Identity() -> SE3: ...

class Quaternion:
    @overload
    def __init__(self, rotation: _ArrayLike) -> None: ...
    @overload
    def __init__(self, w: float, x: float, y: float, z: float) -> None: ...
    def coeffs(self) -> _Array: ...  # [x, y, z, w]
    def toRotationMatrix(self) -> _Array: ...

class Motion:
    linear: _Array
    angular: _Array
    vector: _Array
    def __init__(self, vector: _ArrayLike) -> None: ...

class Frame:
    name: str
    parent: int
    parentJoint: int
    parentFrame: int
    placement: SE3
    type: FrameType

class JointModel:
    idx_q: int
    idx_v: int
    nq: int
    nv: int
    def shortname(self) -> str: ...
    def createData(self) -> Any: ...
    def calc(self, data: Any, q: _ArrayLike) -> None: ...
    def extract(self) -> Any: ...

class _StdVec(Sequence[Any]):
    def __iter__(self) -> Iterator[Any]: ...

class Model:
    @overload
    def __init__(self) -> None: ...
    @overload
    def __init__(self, other: Model) -> None: ...
    name: str
    nq: int
    nv: int
    njoints: int
    nframes: int
    names: Sequence[str]
    frames: Sequence[Frame]
    joints: Sequence[JointModel]
    parents: Sequence[int]
    jointPlacements: Sequence[SE3]
    supports: Sequence[Sequence[int]]
    lowerPositionLimit: _Array
    upperPositionLimit: _Array
    velocityLimit: _Array
    effortLimit: _Array
    def createData(self) -> Data: ...
    def getFrameId(self, name: str, type: FrameType = ...) -> int: ...
    def existFrame(self, name: str, type: FrameType = ...) -> bool: ...
    def getJointId(self, name: str) -> int: ...
    def existJointName(self, name: str) -> bool: ...

class Data:
    oMi: Sequence[SE3]
    oMf: Sequence[SE3]
    J: _Array

class GeometryObject:
    def __init__(
        self,
        name: str,
        parent_joint: int,
        parent_frame: int,
        placement: SE3,
        geometry: Any,  # a coal collision geometry
    ) -> None: ...
    name: str
    parentJoint: int
    parentFrame: int
    placement: SE3
    meshPath: str
    meshScale: _Array
    meshColor: _Array
    overrideMaterial: bool
    meshMaterial: Any
    geometry: Any  # an hpp-fcl collision geometry

class CollisionPair:
    first: int
    second: int
    def __init__(self, first: int, second: int) -> None: ...

class GeometryModel:
    @overload
    def __init__(self) -> None: ...
    @overload
    def __init__(self, other: GeometryModel) -> None: ...
    ngeoms: int
    geometryObjects: Sequence[GeometryObject]
    collisionPairs: Sequence[CollisionPair]
    def addGeometryObject(self, geometry_object: GeometryObject) -> int: ...
    def addCollisionPair(self, pair: CollisionPair) -> None: ...
    def createData(self) -> GeometryData: ...
    def getGeometryId(self, name: str) -> int: ...
    def existGeometryName(self, name: str) -> bool: ...

class DistanceResult:  # coal's, as Pinocchio returns it
    min_distance: float
    def getNearestPoint1(self) -> _Array: ...
    def getNearestPoint2(self) -> _Array: ...

class GeometryData:
    def __init__(self, geometry_model: GeometryModel) -> None: ...
    oMg: Sequence[SE3]
    distanceResults: Sequence[DistanceResult]
    distanceRequests: Sequence[Any]  # coal DistanceRequest
    def activateCollisionPair(self, pair_index: int) -> None: ...
    def deactivateCollisionPair(self, pair_index: int) -> None: ...

def neutral(model: Model) -> _Array: ...
def normalize(model: Model, q: _ArrayLike) -> _Array: ...
def integrate(model: Model, q: _ArrayLike, v: _ArrayLike) -> _Array: ...
def difference(model: Model, q0: _ArrayLike, q1: _ArrayLike) -> _Array: ...
def randomConfiguration(model: Model) -> _Array: ...
def forwardKinematics(
    model: Model, data: Data, q: _ArrayLike, v: _ArrayLike = ..., a: _ArrayLike = ...
) -> None: ...
def framesForwardKinematics(model: Model, data: Data, q: _ArrayLike) -> None: ...
def updateFramePlacements(model: Model, data: Data) -> None: ...
def updateFramePlacement(model: Model, data: Data, frame_id: int) -> SE3: ...
def updateGeometryPlacements(
    model: Model,
    data: Data,
    geometry_model: GeometryModel,
    geometry_data: GeometryData,
    q: _ArrayLike = ...,
) -> None: ...
def computeJointJacobians(model: Model, data: Data, q: _ArrayLike = ...) -> _Array: ...
def computeJointJacobiansTimeVariation(
    model: Model, data: Data, q: _ArrayLike, v: _ArrayLike
) -> _Array: ...
def computeFrameJacobian(
    model: Model,
    data: Data,
    q: _ArrayLike,
    frame_id: int,
    reference_frame: ReferenceFrame = ...,
) -> _Array: ...
def getFrameJacobian(
    model: Model, data: Data, frame_id: int, reference_frame: ReferenceFrame
) -> _Array: ...
def getFrameJacobianTimeVariation(
    model: Model, data: Data, frame_id: int, reference_frame: ReferenceFrame
) -> _Array: ...
def computeDistances(
    model: Model,
    data: Data,
    geometry_model: GeometryModel,
    geometry_data: GeometryData,
    q: _ArrayLike,
) -> int: ...
def computeDistance(
    geometry_model: GeometryModel, geometry_data: GeometryData, pair_index: int
) -> DistanceResult: ...
def log6(transform: SE3 | _ArrayLike) -> Motion: ...
def log3(rotation: _ArrayLike) -> _Array: ...
def exp3(omega: _ArrayLike) -> _Array: ...
def exp6(motion: Motion | _ArrayLike) -> SE3: ...
def buildModelFromXML(xml: str) -> Model: ...
def buildModelFromUrdf(filename: str) -> Model: ...
def buildGeomFromUrdf(
    model: Model,
    filename: str,
    geom_type: GeometryType,
    geometry_model: GeometryModel | None = ...,
    package_dirs: str | Sequence[str] | None = ...,
) -> GeometryModel: ...
def transformJointIntoMimic(
    input_model: Model,
    index_mimicked: int,
    index_mimicking: int,
    scaling: float,
    offset: float,
) -> Model: ...
def buildReducedModel(
    model: Model, joints_to_lock: Sequence[int], reference_configuration: _ArrayLike
) -> Model: ...
