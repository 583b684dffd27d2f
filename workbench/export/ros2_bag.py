"""Joint trajectories as ROS 2 bags (MCAP) of ``trajectory_msgs/msg/JointTrajectory``.

Written and read with the `rosbags <https://gitlab.com/ternaris/rosbags>`_
library, so no ROS installation is needed
(``pip install "kinematics-workbench[export]"``).
The bag holds one message on :data:`DEFAULT_TOPIC`: the whole trajectory, as a
``joint_trajectory_controller`` takes it, with the joint names, and per point
the positions [rad], velocities [rad/s], accelerations [rad/s²] and
``time_from_start``. ROS durations count whole nanoseconds, so times are
rounded to the nearest nanosecond and read back as the integer count over 1e9
in one correctly rounded division: a time that is the double nearest a whole
number of nanoseconds (``k / 100`` s, ``k / 1000`` s: the workbench's 100 Hz and
1 kHz samples) comes back to the bit.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from workbench.atomic_files import atomic_folder
from workbench.errors import DimensionError, InputError
from workbench.trajectory.csv_io import JointTrajectorySamples

FloatArray = npt.NDArray[np.float64]

DEFAULT_TOPIC = "/joint_trajectory"
MSGTYPE = "trajectory_msgs/msg/JointTrajectory"
_NS = 1_000_000_000
#: ROS 2 topic names: slash-separated tokens of letters, digits and _, each
#: starting with a letter.
_TOPIC = re.compile(r"/?[A-Za-z][A-Za-z0-9_]*(/[A-Za-z][A-Za-z0-9_]*)*")


def _rosbags() -> tuple[Any, Any, Any]:
    """The rosbags writer, reader and typestore (ROS 2 Humble message set).

    Raises:
        InputError: If rosbags is not installed.
    """
    try:
        from rosbags.rosbag2 import Reader, StoragePlugin, Writer
        from rosbags.typesys import Stores, get_typestore
    except ImportError as err:
        raise InputError(
            "ROS 2 bag export needs the rosbags library: "
            'pip install "kinematics-workbench[export]"'
        ) from err
    return (Writer, StoragePlugin), Reader, get_typestore(Stores.ROS2_HUMBLE)


@dataclass(frozen=True, slots=True)
class BagTrajectory:
    """A trajectory read back from a bag.

    Attributes:
        joint_names: Joint names, in column order.
        samples: Times (K,) [s] and q, qd, qdd (K, n).
        frame_id: ``header.frame_id`` of the message.
    """

    joint_names: tuple[str, ...]
    samples: JointTrajectorySamples
    frame_id: str


def _check(samples: JointTrajectorySamples, joint_names: list[str], topic: str) -> None:
    if not _TOPIC.fullmatch(topic):
        raise InputError(
            f"topic {topic!r} is not a ROS 2 topic name (e.g. /joint_trajectory)"
        )
    if len(joint_names) != samples.nq:
        raise DimensionError("joint_names", (samples.nq,), (len(joint_names),))
    if len(set(joint_names)) != len(joint_names):
        raise InputError(f"joint names must be unique, got {joint_names}")
    if samples.t[0] < 0.0:
        raise InputError(f"times must be >= 0 s, got {samples.t[0]:g}")


def write_ros2_bag(
    path: str | Path,
    samples: JointTrajectorySamples,
    joint_names: list[str],
    *,
    topic: str = DEFAULT_TOPIC,
    frame_id: str = "base",
) -> Path:
    """Write the trajectory as one JointTrajectory message in a new MCAP bag.

    Args:
        path: Bag folder to create (must not exist).
        samples: Times (K,) [s] from the start, q, qd, qdd (K, n) [rad, rad/s,
            rad/s²].
        joint_names: n names (e.g. ``robot.joint_names``).
        topic: Topic name.
        frame_id: ``header.frame_id``.

    Returns:
        The bag folder; nothing is left behind on failure.

    Raises:
        InputError: If the folder exists, its parent is missing, the names do
            not match the columns, the topic is not a ROS 2 name, or rosbags
            is missing.
    """
    _check(samples, list(joint_names), topic)
    (writer_class, plugin), _, store = _rosbags()
    types = store.types
    duration, header = (
        types["builtin_interfaces/msg/Duration"],
        types["std_msgs/msg/Header"],
    )
    point_type = types["trajectory_msgs/msg/JointTrajectoryPoint"]
    points = []
    for k, t in enumerate(samples.t):
        ns = round(float(t) * _NS)
        points.append(
            point_type(
                positions=np.array(samples.q[k], dtype=np.float64),
                velocities=np.array(samples.qd[k], dtype=np.float64),
                accelerations=np.array(samples.qdd[k], dtype=np.float64),
                effort=np.zeros(0, dtype=np.float64),
                time_from_start=duration(sec=ns // _NS, nanosec=ns % _NS),
            )
        )
    stamp = types["builtin_interfaces/msg/Time"](sec=0, nanosec=0)
    message = types[MSGTYPE](
        header=header(stamp=stamp, frame_id=frame_id),
        joint_names=list(joint_names),
        points=points,
    )
    data = store.serialize_cdr(message, MSGTYPE)
    with atomic_folder(path) as tmp:
        with writer_class(tmp, version=8, storage_plugin=plugin.MCAP) as writer:
            connection = writer.add_connection(topic, MSGTYPE, typestore=store)
            writer.write(connection, 0, data)
    return Path(path)


def read_ros2_bag(path: str | Path, *, topic: str = DEFAULT_TOPIC) -> BagTrajectory:
    """Read the first JointTrajectory message of ``topic`` from a bag.

    Raises:
        InputError: If the bag cannot be read or has no such message.
    """
    _, reader_class, store = _rosbags()
    try:
        with reader_class(Path(path)) as reader:
            connections = [
                c
                for c in reader.connections
                if c.topic == topic and c.msgtype == MSGTYPE
            ]
            for connection, _, raw in reader.messages(connections=connections):
                message = store.deserialize_cdr(raw, connection.msgtype)
                break
            else:
                raise InputError(f"{path}: no {MSGTYPE} message on {topic}")
    except (OSError, ValueError, KeyError) as err:
        raise InputError(f"cannot read bag {path}: {err}") from err
    except Exception as err:  # rosbags' own errors (ReaderError, ...)
        if isinstance(err, InputError):
            raise
        raise InputError(f"cannot read bag {path}: {err}") from err
    points = message.points
    # Whole nanoseconds over 1e9 in one correctly rounded division (not
    # sec + nanosec / 1e9, which rounds twice: 4.56 came back 4.5600000000000005).
    t = np.array(
        [
            (p.time_from_start.sec * _NS + p.time_from_start.nanosec) / _NS
            for p in points
        ]
    )
    samples = JointTrajectorySamples(
        t=t,
        q=np.array([p.positions for p in points], dtype=np.float64),
        qd=np.array([p.velocities for p in points], dtype=np.float64),
        qdd=np.array([p.accelerations for p in points], dtype=np.float64),
    )
    return BagTrajectory(tuple(message.joint_names), samples, message.header.frame_id)


__all__ = ["DEFAULT_TOPIC", "BagTrajectory", "read_ros2_bag", "write_ros2_bag"]
