"""A robot arm in Pinocchio: model, tool frame, limits, FK and Jacobians."""

from __future__ import annotations

from functools import cached_property
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import (
    DimensionError,
    FrameNotFoundError,
    InputError,
    URDFLoadError,
)
from workbench.model.dh import DHTable
from workbench.validation import as_vector

FloatArray = npt.NDArray[np.float64]

_REFERENCE_FRAMES = {
    "local": pin.ReferenceFrame.LOCAL,
    "world": pin.ReferenceFrame.WORLD,
    "local_world_aligned": pin.ReferenceFrame.LOCAL_WORLD_ALIGNED,
}


def _positive_limits(values: npt.ArrayLike, size: int, name: str) -> FloatArray:
    """Limits of shape (size,), each > 0 (inf allowed, NaN not)."""
    arr = np.asarray(values, dtype=np.float64)
    if arr.shape != (size,):
        raise DimensionError(name, (size,), arr.shape)
    if np.any(np.isnan(arr)) or np.any(arr <= 0.0):
        raise InputError(f"{name} must be > 0 (inf allowed), got {arr.tolist()}")
    return arr


def _read_only(values: npt.ArrayLike) -> FloatArray:
    arr = np.array(values, dtype=np.float64)
    arr.setflags(write=False)
    return arr


class Robot:
    """A kinematic model with a tool frame and joint limits.

    Build one with :func:`workbench.load_robot`. All quantities are SI: rad,
    m, s. ``q`` has shape (nq,), ``v`` shape (nv,); for the revolute arms of
    this project nq == nv.

    Attributes:
        name: Robot name, or the URDF path it was loaded from.
        model: Pinocchio model.
        data: Pinocchio data of ``model`` (scratch space, not thread-safe).
        urdf_path: URDF file the model was built from.
        tool_frame: Name of the tool frame.
        tool_frame_id: Pinocchio frame index of the tool frame.
        dh_table: The DH table the URDF was generated from (the PUMA models),
            else None.
        lower, upper: Position limits, shape (nq,) [rad].
        velocity_limit: Speed limits, shape (nv,) [rad/s].
        acceleration_limit: Acceleration limits, shape (nv,) [rad/s²], inf
            where unknown.
    """

    def __init__(
        self,
        name: str,
        model: pin.Model,
        urdf_path: Path,
        tool_frame: str,
        *,
        package_dirs: list[str],
        acceleration_limit: npt.ArrayLike | None = None,
        dh_table: DHTable | None = None,
    ):
        self.name = name
        self.dh_table = dh_table
        self.model = model
        self.data = model.createData()
        self.urdf_path = urdf_path
        self._package_dirs = package_dirs
        self.tool_frame = tool_frame
        self.tool_frame_id = self.get_frame_id(tool_frame)
        self.lower = _read_only(model.lowerPositionLimit)
        self.upper = _read_only(model.upperPositionLimit)
        self.velocity_limit = _read_only(model.velocityLimit)
        if acceleration_limit is None:
            acceleration_limit = np.full(model.nv, np.inf)
        self.acceleration_limit = _read_only(
            _positive_limits(acceleration_limit, model.nv, "acceleration_limit")
        )

    def with_limits(
        self,
        *,
        velocity_limit: npt.ArrayLike | None = None,
        acceleration_limit: npt.ArrayLike | None = None,
    ) -> Robot:
        """A copy of this robot with other speed and/or acceleration limits.

        Args:
            velocity_limit: Shape (nv,) [rad/s], > 0; None keeps the current one.
            acceleration_limit: Shape (nv,) [rad/s²], > 0 or inf; None keeps it.

        Raises:
            DimensionError: If a shape is wrong.
            InputError: If a limit is not > 0.
        """
        model = pin.Model(self.model)
        if velocity_limit is not None:
            model.velocityLimit = _positive_limits(
                velocity_limit, self.nv, "velocity_limit"
            )
        return Robot(
            self.name,
            model,
            self.urdf_path,
            self.tool_frame,
            package_dirs=self._package_dirs,
            acceleration_limit=(
                self.acceleration_limit
                if acceleration_limit is None
                else acceleration_limit
            ),
            dh_table=self.dh_table,
        )

    def __repr__(self) -> str:
        return f"Robot({self.name!r}, nq={self.nq}, tool_frame={self.tool_frame!r})"

    @property
    def nq(self) -> int:
        """Size of a configuration ``q``."""
        return int(self.model.nq)

    @property
    def nv(self) -> int:
        """Size of a velocity ``v``."""
        return int(self.model.nv)

    @property
    def joint_names(self) -> list[str]:
        """Names of the moving joints, base to tip (Pinocchio's "universe" left out)."""
        return list(self.model.names)[1:]

    @property
    def frame_names(self) -> list[str]:
        """Names of every frame of the model, in Pinocchio's order."""
        return [frame.name for frame in self.model.frames]

    @cached_property
    def visual_model(self) -> pin.GeometryModel:
        """Visual geometry, meshes resolved (built on first use)."""
        return self._build_geometry(pin.GeometryType.VISUAL)

    @cached_property
    def collision_model(self) -> pin.GeometryModel:
        """Collision geometry, meshes resolved (built on first use)."""
        return self._build_geometry(pin.GeometryType.COLLISION)

    def _build_geometry(self, kind: pin.GeometryType) -> pin.GeometryModel:
        try:
            return pin.buildGeomFromUrdf(
                self.model, str(self.urdf_path), kind, package_dirs=self._package_dirs
            )
        except (ValueError, RuntimeError) as err:
            raise URDFLoadError(f"{self.urdf_path}: {err}") from err

    def check_configuration(self, q: npt.ArrayLike) -> FloatArray:
        """Validate ``q``: shape (nq,), finite. Returns it as float64.

        Raises:
            DimensionError: If the joint count is wrong.
            NonFiniteError: If an entry is NaN or infinite.
        """
        return as_vector(q, self.nq, "q")

    def get_frame_id(self, frame: str | None) -> int:
        """Pinocchio index of ``frame``; the tool frame when None.

        Raises:
            FrameNotFoundError: If the model has no such frame.
        """
        if frame is None:
            return self.tool_frame_id
        matches = [i for i, f in enumerate(self.model.frames) if f.name == frame]
        if not matches:
            raise FrameNotFoundError(frame, self.frame_names)
        # A link and a joint may share a name (z1's gripperStator): prefer the link.
        bodies = [i for i in matches if self.model.frames[i].type == pin.FrameType.BODY]
        return (bodies or matches)[-1]

    def fk(self, q: npt.ArrayLike, frame: str | None = None) -> pin.SE3:
        """Forward kinematics: pose of a frame in the base frame.

        Args:
            q: Configuration, shape (nq,) [rad].
            frame: Frame name; the tool frame when None.

        Returns:
            ``transform_frame_to_base`` (Pinocchio's ``oMf``), a copy.
        """
        q = self.check_configuration(q)
        frame_id = self.get_frame_id(frame)
        pin.forwardKinematics(self.model, self.data, q)
        return pin.updateFramePlacement(self.model, self.data, frame_id).copy()

    def _frame_jacobian(
        self, q: npt.ArrayLike, frame: str | None, reference: str
    ) -> FloatArray:
        q = self.check_configuration(q)
        frame_id = self.get_frame_id(frame)
        return pin.computeFrameJacobian(
            self.model, self.data, q, frame_id, _REFERENCE_FRAMES[reference]
        )

    def jacobian(self, q: npt.ArrayLike, frame: str | None = None) -> FloatArray:
        """Jacobian of a frame, LOCAL_WORLD_ALIGNED (the default everywhere).

        Args:
            q: Configuration, shape (nq,) [rad].
            frame: Frame name; the tool frame when None.

        Returns:
            Shape (6, nv): rows [linear velocity of the frame origin (m/s);
            angular velocity (rad/s)], both in base axes, per unit joint speed.
        """
        return self._frame_jacobian(q, frame, "local_world_aligned")

    def jacobian_local(self, q: npt.ArrayLike, frame: str | None = None) -> FloatArray:
        """Jacobian of a frame, LOCAL: body twist in the frame's own axes, (6, nv)."""
        return self._frame_jacobian(q, frame, "local")

    def jacobian_world(self, q: npt.ArrayLike, frame: str | None = None) -> FloatArray:
        """Jacobian of a frame, WORLD: the spatial twist at the base origin, (6, nv)."""
        return self._frame_jacobian(q, frame, "world")

    def jacobian_time_derivative(
        self, q: npt.ArrayLike, v: npt.ArrayLike, frame: str | None = None
    ) -> FloatArray:
        r"""Time derivative :math:`\dot J` of :meth:`jacobian` along velocity ``v``.

        With it the frame's classical acceleration (linear acceleration of its
        origin and angular acceleration, base axes) is :math:`J \dot v + \dot J v`.

        Args:
            q: Configuration, shape (nq,) [rad].
            v: Joint velocity, shape (nv,) [rad/s].
            frame: Frame name; the tool frame when None.

        Returns:
            Shape (6, nv), LOCAL_WORLD_ALIGNED, per unit joint speed, per second.
        """
        q = self.check_configuration(q)
        v = as_vector(v, self.nv, "v")
        frame_id = self.get_frame_id(frame)
        pin.computeJointJacobiansTimeVariation(self.model, self.data, q, v)
        pin.updateFramePlacements(self.model, self.data)
        return pin.getFrameJacobianTimeVariation(
            self.model, self.data, frame_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        )
