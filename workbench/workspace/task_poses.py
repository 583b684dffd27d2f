"""Task poses of a base placement: a pose CSV, or a joint trajectory and its robot.

Two sources give the poses of the tool frame that a base placement must reach
(:func:`workbench.workspace.placement.place_base`):

* a CSV file with the header ``x,y,z,qx,qy,qz,qw``: one pose per row, the
  position [m] and the unit quaternion (``quat_xyzw``, Pinocchio's order) of the
  tool frame in the world frame (:func:`read_task_poses`); a set of poses with
  no order;
* a joint trajectory CSV (:func:`workbench.trajectory.csv_io.read_trajectory_csv`)
  with the robot that recorded it: the poses are the forward kinematics of its
  tool frame, in the world frame taken to be the robot's base frame at the
  recording (:func:`task_poses_from_trajectory`); a path, whose order counts
  (the placement then needs one branch along the whole path, without a flip).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.trajectory.csv_io import JointTrajectorySamples, read_trajectory_csv
from workbench.validation import iter_data_rows, parse_float, read_csv_file
from workbench.workspace.orientations import rotations_from_quat_xyzw

FloatArray = npt.NDArray[np.float64]

#: Header of a task-pose CSV file.
TASK_POSE_HEADER = ("x", "y", "z", "qx", "qy", "qz", "qw")
#: Largest | |q| − 1 | of a quaternion in a task-pose file (then normalised):
#: seven typed decimals, as ``workbench.poses.RIGIDITY_TOL`` allows for matrices.
TASK_QUAT_NORM_TOL = 1e-6
#: Most task poses of one file (a placement checks each against every candidate).
MAX_TASK_POSES = 100_000


class TaskPoseFileError(InputError):
    """A task-pose CSV file is missing or malformed (the message names the row)."""


@dataclass(frozen=True, slots=True)
class TaskPoses:
    """Poses of the tool frame that a base placement must reach.

    Attributes:
        poses: Shape (N, 4, 4), homogeneous poses of the tool frame in the
            world frame [m], read-only.
        ordered: True for a path (from a trajectory): the samples are visited
            in order, so one IK branch must follow all of them without a flip.
        source: Where the poses come from (file name), for messages.
    """

    poses: FloatArray
    ordered: bool = False
    source: str = ""

    def __len__(self) -> int:
        """Number of poses N."""
        return int(self.poses.shape[0])


def matrices_from_xyz_quat_xyzw(rows: npt.ArrayLike) -> FloatArray:
    """Homogeneous poses from rows ``x, y, z, qx, qy, qz, qw``.

    Args:
        rows: Shape (N, 7): position [m] and unit quaternion (xyzw, any sign).

    Returns:
        Shape (N, 4, 4) [m]; the quaternions are normalised first.
    """
    values = np.asarray(rows, dtype=np.float64).reshape(-1, 7)
    quat = values[:, 3:] / np.linalg.norm(values[:, 3:], axis=1, keepdims=True)
    out = np.zeros((len(values), 4, 4))
    out[:, :3, :3] = rotations_from_quat_xyzw(quat)
    out[:, :3, 3] = values[:, :3]
    out[:, 3, 3] = 1.0
    return out


def read_task_poses(path: str | Path) -> TaskPoses:
    """Read a task-pose CSV file (header ``x,y,z,qx,qy,qz,qw``, world frame).

    Blank lines and lines starting with ``#`` are skipped.

    Args:
        path: The file: one pose per row, position [m] and unit quaternion
            ``quat_xyzw`` (norm within :data:`TASK_QUAT_NORM_TOL` of 1).

    Returns:
        The poses, unordered (a set of poses, not a path).

    Raises:
        TaskPoseFileError: If the file cannot be read, the header differs, a
            row has another number of fields, a value is not a finite number, a
            quaternion is not of unit norm, there is no pose or more than
            :data:`MAX_TASK_POSES`; the message names the line.
    """
    path = Path(path)
    rows = read_csv_file(path, TaskPoseFileError, "task poses")
    if not rows:
        raise TaskPoseFileError(
            f"{path}: empty file (expected the header x,y,z,qx,qy,qz,qw)"
        )
    columns = tuple(c.strip() for c in rows[0])
    if columns != TASK_POSE_HEADER:
        raise TaskPoseFileError(
            f"{path}, line 1: header must be {','.join(TASK_POSE_HEADER)}, "
            f"got {','.join(columns)[:80]}"
        )
    values = []
    for line, row in iter_data_rows(rows):
        values.append(_parse_row(row, line, path))
        if len(values) > MAX_TASK_POSES:
            raise TaskPoseFileError(f"{path}: more than {MAX_TASK_POSES} task poses")
    if not values:
        raise TaskPoseFileError(f"{path}: no task pose after the header")
    return TaskPoses(_read_only(matrices_from_xyz_quat_xyzw(values)), False, str(path))


def _parse_row(row: list[str], line: int, path: Path) -> list[float]:
    """The seven numbers of one row, checked (finite, unit quaternion)."""
    if len(row) != len(TASK_POSE_HEADER):
        raise TaskPoseFileError(
            f"{path}, line {line}: {len(row)} fields, expected {len(TASK_POSE_HEADER)}"
        )
    try:
        numbers = [parse_float(field.strip()) for field in row]
    except ValueError:
        raise TaskPoseFileError(f"{path}, line {line}: not a number in {row}") from None
    if not all(math.isfinite(x) for x in numbers):
        raise TaskPoseFileError(f"{path}, line {line}: NaN or infinite value")
    norm = math.hypot(*numbers[3:])
    if abs(norm - 1.0) > TASK_QUAT_NORM_TOL:
        raise TaskPoseFileError(
            f"{path}, line {line}: quaternion qx,qy,qz,qw must have unit norm "
            f"(within {TASK_QUAT_NORM_TOL:g}), got {norm:.9g}"
        )
    return numbers


def task_poses_from_trajectory(
    robot: Robot, samples: JointTrajectorySamples, source: str = ""
) -> TaskPoses:
    """The tool-frame path of a joint trajectory, in its robot's base frame.

    Args:
        robot: The robot that ran the trajectory; its base frame at the
            recording is the world frame of the returned poses.
        samples: The trajectory, ``samples.q`` of shape (K, robot.nq) [rad].
        source: Where the samples come from, for messages.

    Returns:
        K ordered poses (a path).

    Raises:
        InputError: If the trajectory has another joint count than the robot.
    """
    if samples.nq != robot.nq:
        raise InputError(
            f"{source or 'trajectory'}: {samples.nq} joints, robot {robot.name} "
            f"has {robot.nq}"
        )
    poses = np.empty((len(samples.t), 4, 4))
    for k, q in enumerate(samples.q):
        poses[k] = robot.fk(robot.check_configuration(q)).homogeneous
    return TaskPoses(_read_only(poses), True, source)


def read_trajectory_task_poses(robot: Robot, path: str | Path) -> TaskPoses:
    """The tool-frame path of a trajectory CSV file.

    See :func:`task_poses_from_trajectory`.

    Raises:
        TrajectoryFileError: If the file is missing or malformed.
        InputError: If its joints do not match the robot.
    """
    samples = read_trajectory_csv(path, robot.nq)
    return task_poses_from_trajectory(robot, samples, str(path))


def _read_only(values: FloatArray) -> FloatArray:
    values.setflags(write=False)
    return values


__all__ = [
    "MAX_TASK_POSES",
    "TASK_POSE_HEADER",
    "TASK_QUAT_NORM_TOL",
    "TaskPoseFileError",
    "TaskPoses",
    "matrices_from_xyz_quat_xyzw",
    "read_task_poses",
    "read_trajectory_task_poses",
    "task_poses_from_trajectory",
]
