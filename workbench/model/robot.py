"""A robot arm in Pinocchio: model, tool frame, limits, FK and Jacobians."""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
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
from workbench.model.mesh_files import honour_collada_frames
from workbench.model.packages import get_package_lookup, resolve_mesh_uris
from workbench.model.urdf_joints import MimicJoint
from workbench.validation import as_vector

FloatArray = npt.NDArray[np.float64]
IndexArray = npt.NDArray[np.intp]

_LOCAL = pin.ReferenceFrame.LOCAL
_WORLD = pin.ReferenceFrame.WORLD
_LOCAL_WORLD_ALIGNED = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


_FLOAT64 = np.dtype(np.float64)
#: Revisions of the robots' attributes, unique over all robots (``Robot._revision``).
_REVISIONS = itertools.count()

# Module-level names for the per-call paths of fk / jacobian.
_forward_kinematics = pin.forwardKinematics
_update_frame_placement = pin.updateFramePlacement
_compute_frame_jacobian = pin.computeFrameJacobian


def _positive_limits(values: npt.ArrayLike, size: int, name: str) -> FloatArray:
    """Limits of shape (size,) (a scalar holds for every joint), each > 0.

    inf means "no limit"; NaN, 0 and negative values are refused.
    """
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise InputError(f"{name} must be numbers, got {values!r}") from err
    if arr.shape == ():
        arr = np.full(size, float(arr))
    if arr.shape != (size,):
        raise DimensionError(name, (size,), arr.shape)
    if np.any(np.isnan(arr)) or np.any(arr <= 0.0):
        raise InputError(f"{name} must be > 0 (inf for no limit), got {arr.tolist()}")
    return arr


def _given_limits(values: npt.ArrayLike) -> FloatArray:
    """A URDF's rate limits, 0 (how a URDF says "not given") as inf."""
    arr = np.asarray(values, dtype=np.float64)
    return np.where(arr > 0.0, arr, np.inf)


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
        velocity_limit: Speed limits, shape (nv,) [rad/s], > 0; inf where
            not given (a URDF's ``velocity="0"`` or a missing ``<limit>``).
            Every speed check and duration reads this attribute.
        acceleration_limit: Acceleration limits, shape (nv,) [rad/s²], > 0;
            inf where not given (a URDF has none).
        srdf_path: The SRDF whose ``<disable_collisions>`` the self-collision
            check honours (:mod:`workbench.model.srdf_files`), else None.
        disabled_collisions: Its entries, ``(link_a, link_b, reason)``.
    """

    def __init__(
        self,
        name: str,
        model: pin.Model,
        urdf_path: Path,
        tool_frame: str,
        *,
        package_dirs: Sequence[str],
        acceleration_limit: npt.ArrayLike | None = None,
        dh_table: DHTable | None = None,
        description: str | None = None,
        xacro_args: Sequence[tuple[str, str]] = (),
        srdf_path: Path | None = None,
        disabled_collisions: Sequence[tuple[str, str, str]] = (),
    ):
        self._revision: int
        self.name = name
        self.dh_table = dh_table
        self.model = model
        self.data = model.createData()
        self._finite_test = np.full(model.nq, 1e-300)  # see check_configuration
        self.urdf_path = urdf_path
        self._package_dirs = tuple(package_dirs)
        self._description = description
        self._xacro_args = tuple(sorted((str(k), str(v)) for k, v in xacro_args))
        self.srdf_path = srdf_path
        self.disabled_collisions = tuple(disabled_collisions)
        self.tool_frame = tool_frame
        self.tool_frame_id = self.get_frame_id(tool_frame)
        self.lower = _read_only(model.lowerPositionLimit)
        self.upper = _read_only(model.upperPositionLimit)
        self.velocity_limit = _read_only(_given_limits(model.velocityLimit))
        if acceleration_limit is None:
            acceleration_limit = np.full(model.nv, np.inf)
        self.acceleration_limit = _read_only(
            _positive_limits(acceleration_limit, model.nv, "acceleration_limit")
        )

    def __setattr__(self, name: str, value: object) -> None:
        """Set an attribute, and give the robot a new ``_revision``.

        ``_revision`` tells the per-robot caches
        (:func:`~workbench.model.per_robot.per_robot`) in one comparison
        that no attribute was assigned since a value was derived.
        """
        object.__setattr__(self, name, value)
        object.__setattr__(self, "_revision", next(_REVISIONS))

    def with_limits(
        self,
        *,
        velocity_limit: npt.ArrayLike | None = None,
        acceleration_limit: npt.ArrayLike | None = None,
    ) -> Robot:
        """A copy of this robot with other speed and/or acceleration limits.

        Args:
            velocity_limit: Shape (nv,) [rad/s], > 0 or inf (no limit); a
                scalar holds for every joint. None keeps the current one.
            acceleration_limit: Shape (nv,) [rad/s²], > 0 or inf; a scalar
                holds for every joint. None keeps the current one.

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
            description=self._description,
            xacro_args=self._xacro_args,
            srdf_path=self.srdf_path,
            disabled_collisions=self.disabled_collisions,
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
    def package_dirs(self) -> tuple[str, ...]:
        """The package folders (and ``NAME=DIR`` mappings) given, absolute.

        ``load_robot(robot.name, package_dirs=robot.package_dirs)`` finds the
        same meshes again (e.g. in another process of a cluster); see
        :mod:`workbench.model.packages` for the lookup.
        """
        return self._package_dirs

    @property
    def xacro_args(self) -> tuple[tuple[str, str], ...]:
        """The ``(name, value)`` arguments a xacro description was expanded with.

        Sorted by name; empty for a URDF. ``load_robot(robot.urdf_path,
        xacro_args=dict(robot.xacro_args))`` expands it the same way again.
        """
        return self._xacro_args

    @property
    def description(self) -> str:
        """The URDF text of the model, every mesh URI an absolute file path.

        Raises:
            URDFLoadError: If the file cannot be read or a mesh is not found
                (a robot built without the text reads its ``urdf_path``).
        """
        if self._description is None:
            try:
                text = Path(self.urdf_path).read_text(encoding="utf-8")
            except (OSError, UnicodeDecodeError) as err:
                raise URDFLoadError(
                    f"cannot read URDF {self.urdf_path}: {err}"
                ) from err
            lookup = get_package_lookup(self.urdf_path, self._package_dirs)
            object.__setattr__(self, "_description", resolve_mesh_uris(text, lookup))
        return self._description  # type: ignore[return-value]

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
        """Names of the joints with a coordinate of their own, base to tip.

        Pinocchio's "universe" and the mimicking joints (which follow their
        leader, see :attr:`mimic_joints`) are left out: one name per joint
        value, ``n_joints`` names.
        """
        return [self.model.names[j] for j in self._moving_joints()]

    def _moving_joints(self) -> list[int]:
        """Pinocchio indices of the joints with a coordinate of their own."""
        model = self.model
        return [j for j in range(1, model.njoints) if model.joints[j].nv]

    @property
    def n_joints(self) -> int:
        """Number of joints with a coordinate of their own (see :attr:`joint_names`).

        The length of a vector of joint values (one angle per revolute or
        continuous joint, one length per prismatic joint); it differs from
        ``nq`` when a continuous joint stores its angle as (cos, sin).
        """
        return len(self.joint_names)

    @property
    def mimic_joints(self) -> tuple[MimicJoint, ...]:
        """Joints that follow another (URDF ``<mimic>``), without a coordinate.

        ``q_joint = multiplier * q_leader + offset``; FK and Jacobians apply it.
        """
        model = self.model
        leaders = {model.joints[j].idx_q: model.names[j] for j in self._moving_joints()}
        found = []
        for j in range(1, model.njoints):
            joint = model.joints[j]
            if joint.shortname() == "JointModelMimic":
                mimic = joint.extract()
                found.append(
                    MimicJoint(
                        model.names[j],
                        leaders[joint.idx_q],
                        float(mimic.scaling),
                        float(mimic.offset),
                    )
                )
        return tuple(found)

    def _value_slots(self) -> tuple[IndexArray, IndexArray, IndexArray]:
        """Where each joint value goes in q: plain slots and (cos, sin) pairs.

        Returns ``(plain_q, continuous_q, plain_value)``: q indices of the
        one-coordinate joints, the q index of the cosine of each continuous
        joint, and a mask over the joint values, True for the one-coordinate
        joints (in joint order both).

        Raises:
            InputError: If a joint has several degrees of freedom (planar,
                spherical, floating): it has no single joint value.
        """
        model = self.model
        plain, pairs, plain_value = [], [], []
        for j in self._moving_joints():
            joint = model.joints[j]
            plain_value.append(joint.nq == 1)
            if joint.nv == 1 and joint.nq == 1:
                plain.append(joint.idx_q)
            elif joint.nv == 1 and joint.nq == 2:
                pairs.append(joint.idx_q)
            else:
                raise InputError(
                    f"joint {model.names[j]!r} ({joint.shortname()}) has "
                    f"{joint.nv} degrees of freedom and no single joint value; "
                    f"give q with nq = {model.nq} values"
                )
        return (
            np.array(plain, dtype=np.intp),
            np.array(pairs, dtype=np.intp),
            np.array(plain_value, dtype=bool),
        )

    def q_from_joint_values(self, values: npt.ArrayLike) -> FloatArray:
        r"""Configuration ``q`` from one value per joint.

        A continuous joint's angle :math:`\theta` becomes Pinocchio's pair
        :math:`(\cos\theta, \sin\theta)`; every other value is copied.

        Args:
            values: Shape (n_joints,) [rad for revolute and continuous joints,
                m for prismatic ones], in :attr:`joint_names` order.

        Returns:
            ``q``, shape (nq,).

        Raises:
            DimensionError: If ``values`` does not have n_joints entries.
            NonFiniteError: If an entry is NaN or infinite.
            InputError: If a joint has several degrees of freedom.
        """
        plain, pairs, plain_value = self._value_slots()
        values = as_vector(values, plain_value.size, "joint values")
        q = np.empty(self.nq)
        q[plain] = values[plain_value]
        angles = values[~plain_value]
        q[pairs] = np.cos(angles)
        q[pairs + 1] = np.sin(angles)
        return q

    def joint_values_from_q(self, q: npt.ArrayLike) -> FloatArray:
        """One value per joint from ``q``: the inverse of :meth:`q_from_joint_values`.

        A continuous joint's (cos, sin) pair gives its angle in (-π, π].

        Args:
            q: Configuration, shape (nq,).

        Returns:
            Shape (n_joints,) [rad or m], in :attr:`joint_names` order.

        Raises:
            DimensionError: If ``q`` does not have nq entries.
            NonFiniteError: If an entry is NaN or infinite.
            InputError: If a joint has several degrees of freedom.
        """
        q = as_vector(q, self.nq, "q")
        plain, pairs, plain_value = self._value_slots()
        values = np.empty(plain_value.size)
        values[plain_value] = q[plain]
        values[~plain_value] = np.arctan2(q[pairs + 1], q[pairs])
        return values

    def as_configuration(self, values: npt.ArrayLike) -> FloatArray:
        """``q`` from either joint values (n_joints,) or a configuration (nq,).

        The two lengths never clash: they differ when a continuous joint
        stores (cos, sin), and when they are equal every joint has one
        coordinate and joint values *are* q.

        Args:
            values: Shape (n_joints,) [rad or m] or (nq,).

        Returns:
            ``q``, shape (nq,), float64.

        Raises:
            DimensionError: If the length is neither n_joints nor nq (the
                message asks for n_joints values).
            NonFiniteError: If an entry is NaN or infinite.
        """
        arr = np.asarray(values, dtype=np.float64)
        if arr.ndim == 1 and arr.size != self.nq and arr.size == self.n_joints:
            return self.q_from_joint_values(arr)
        if arr.ndim == 1 and arr.size != self.nq:
            followers = ", ".join(map(str, self.mimic_joints))
            name = f"joint values ({followers})" if followers else "joint values"
            raise DimensionError(name, (self.n_joints,), arr.shape)
        return self.check_configuration(arr)

    @property
    def frame_names(self) -> list[str]:
        """Names of every frame of the model, in Pinocchio's order."""
        return [frame.name for frame in self.model.frames]

    @cached_property
    def visual_model(self) -> pin.GeometryModel:
        """Visual geometry, meshes resolved (built on first use).

        Collada meshes carry their file's unit and up axis in ``meshScale``
        and ``placement`` (:mod:`workbench.model.mesh_files`).
        """
        return self._build_geometry(pin.GeometryType.VISUAL)

    @cached_property
    def collision_model(self) -> pin.GeometryModel:
        """Collision geometry, meshes resolved (built on first use; see above)."""
        return self._build_geometry(pin.GeometryType.COLLISION)

    def _build_geometry(self, kind: pin.GeometryType) -> pin.GeometryModel:
        try:
            model = pin.buildGeomFromUrdfString(  # type: ignore[attr-defined]
                self.model, self.description, kind
            )
        except (ValueError, RuntimeError) as err:
            raise URDFLoadError(f"{self.urdf_path}: {err}") from err
        honour_collada_frames(model)  # the files' units and up axes
        return model

    def check_configuration(self, q: npt.ArrayLike) -> FloatArray:
        """Validate ``q``: shape (nq,), finite. Returns it as float64.

        A float64 array is returned as is (not copied), as ``np.asarray``
        would. Its test is cheap and exact: ``q . w`` with every
        ``w_i = 1e-300`` is finite iff every entry is (NaN and inf propagate;
        finite terms are below 2e8, so the sum cannot overflow, and no
        floating-point warning is raised either way).

        Raises:
            DimensionError: If the joint count is wrong.
            NonFiniteError: If an entry is NaN or infinite.
        """
        weights = self._finite_test
        if (
            q.__class__ is np.ndarray
            and q.dtype is _FLOAT64
            and q.shape == weights.shape
            and math.isfinite(q.dot(weights))
            and weights.shape[0] == self.model.nq
        ):
            return q
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

        Raises:
            DimensionError: If ``q`` does not have nq entries.
            NonFiniteError: If an entry of ``q`` is NaN or infinite.
            FrameNotFoundError: If the model has no such frame.
        """
        q = self.check_configuration(q)
        frame_id = self.tool_frame_id if frame is None else self.get_frame_id(frame)
        model, data = self.model, self.data
        _forward_kinematics(model, data, q)
        return _update_frame_placement(model, data, frame_id).copy()

    def _frame_jacobian(
        self, q: npt.ArrayLike, frame: str | None, reference: pin.ReferenceFrame
    ) -> FloatArray:
        q = self.check_configuration(q)
        frame_id = self.tool_frame_id if frame is None else self.get_frame_id(frame)
        return _compute_frame_jacobian(self.model, self.data, q, frame_id, reference)

    def jacobian(self, q: npt.ArrayLike, frame: str | None = None) -> FloatArray:
        """Jacobian of a frame, LOCAL_WORLD_ALIGNED (the default everywhere).

        Args:
            q: Configuration, shape (nq,) [rad].
            frame: Frame name; the tool frame when None.

        Returns:
            Shape (6, nv): rows [linear velocity of the frame origin (m/s);
            angular velocity (rad/s)], both in base axes, per unit joint speed.

        Raises:
            DimensionError: If ``q`` does not have nq entries.
            NonFiniteError: If an entry of ``q`` is NaN or infinite.
            FrameNotFoundError: If the model has no such frame.
        """
        return self._frame_jacobian(q, frame, _LOCAL_WORLD_ALIGNED)

    def jacobian_local(self, q: npt.ArrayLike, frame: str | None = None) -> FloatArray:
        """Jacobian of a frame, LOCAL: body twist in the frame's own axes, (6, nv)."""
        return self._frame_jacobian(q, frame, _LOCAL)

    def jacobian_world(self, q: npt.ArrayLike, frame: str | None = None) -> FloatArray:
        """Jacobian of a frame, WORLD: the spatial twist at the base origin, (6, nv)."""
        return self._frame_jacobian(q, frame, _WORLD)

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

        Raises:
            InputError: If the robot has mimic joints: Pinocchio 4.1's
                ``getFrameJacobianTimeVariation`` is wrong for them
                (``docs/pinocchio-notes.md``), so it is refused, naming them.
        """
        if self.mimic_joints:
            followers = ", ".join(map(str, self.mimic_joints))
            raise InputError(
                f"jacobian_time_derivative does not support mimic joints "
                f"({followers}) of robot {self.name}"
            )
        q = self.check_configuration(q)
        v = as_vector(v, self.nv, "v")
        frame_id = self.get_frame_id(frame)
        pin.computeJointJacobiansTimeVariation(self.model, self.data, q, v)
        pin.updateFramePlacements(self.model, self.data)
        return pin.getFrameJacobianTimeVariation(
            self.model, self.data, frame_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        )
