r"""Joint trajectories as URScript programs (``servoj`` at the servo rate).

A Universal Robots controller runs ``servoj(q, t=dt, lookahead_time, gain)``
once per control cycle :math:`dt` (500 Hz on e-Series, 125 Hz on CB3). The
program moves to the first sample with ``movej`` (the only motion not on the
trajectory), then sends one ``servoj`` per cycle with the trajectory
resampled at the servo rate by cubic Hermite interpolation of the samples'
positions and velocities, and ends with ``stopj``.

Only UR arms are accepted: the joints must be the six UR joints, in order
(:data:`UR_JOINTS`), so a PUMA program can never be sent to a UR.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import numpy.typing as npt

from workbench.atomic_files import write_text_atomic
from workbench.errors import InputError
from workbench.trajectory.csv_io import JointTrajectorySamples, check_sample_count

FloatArray = npt.NDArray[np.float64]

UR_JOINTS = (
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
)
#: e-Series control rate [Hz] (CB3: 125 Hz).
DEFAULT_SERVO_RATE = 500.0
#: Largest servo rate [Hz] accepted.
MAX_SERVO_RATE = 10_000.0
#: A servo rate is at least the trajectory's own sample rate or this, the
#: slowest control cycle of a UR controller (CB3) [Hz], whichever is lower:
#: fewer servo commands than samples would drop the trajectory's shape.
MIN_SERVO_RATE = 125.0
LOOKAHEAD_TIME = 0.1  # [s], URScript's range 0.03 .. 0.2
GAIN = 300  # URScript's range 100 .. 2000
MOVEJ_SPEED = 0.5  # [rad/s] to the first sample
MOVEJ_ACCELERATION = 1.0  # [rad/s²]


def check_ur_joints(joint_names: list[str], robot_name: str = "robot") -> None:
    """Refuse a robot whose joints are not the six UR joints.

    Raises:
        InputError: Naming the robot's joints and the ones expected.
    """
    if tuple(joint_names) != UR_JOINTS:
        raise InputError(
            f"URScript export is for Universal Robots arms only (joints "
            f"{', '.join(UR_JOINTS)}); {robot_name} has joints "
            f"{', '.join(joint_names)}"
        )


def resample_hermite(samples: JointTrajectorySamples, rate: float) -> FloatArray:
    """Positions (M, n) [rad] every ``1 / rate`` s from the first to the last time.

    Cubic Hermite interpolation of the samples' positions and velocities, so
    it passes through every sample with its velocity.
    """
    t = samples.t
    times = t[0] + np.arange(int(np.floor((t[-1] - t[0]) * rate + 1e-9)) + 1) / rate
    times[-1] = min(times[-1], t[-1])
    k = np.clip(np.searchsorted(t, times, side="right") - 1, 0, len(t) - 2)
    if len(t) == 1:
        return samples.q[:1].copy()
    h = (t[k + 1] - t[k])[:, None]
    s = ((times - t[k]) / (t[k + 1] - t[k]))[:, None]
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    q, qd = samples.q, samples.qd
    return h00 * q[k] + h10 * h * qd[k] + h01 * q[k + 1] + h11 * h * qd[k + 1]


def _pose(q: FloatArray) -> str:
    return "[" + ", ".join(f"{x:.9f}" for x in q) + "]"


def _min_servo_rate(t: FloatArray) -> float:
    """The least servo rate [Hz] for samples at times ``t`` (K,) [s].

    The trajectory's own sample rate, (K − 1) / (t_last − t_first), or
    :data:`MIN_SERVO_RATE`, whichever is lower.
    """
    duration = float(t[-1] - t[0]) if len(t) > 1 else 0.0
    if duration <= 0.0:
        return MIN_SERVO_RATE
    return min((len(t) - 1) / duration, MIN_SERVO_RATE)


def generate_urscript(
    samples: JointTrajectorySamples,
    joint_names: list[str],
    *,
    servo_rate: float = DEFAULT_SERVO_RATE,
    robot_name: str = "robot",
) -> str:
    """URScript text of the trajectory.

    Args:
        samples: Times (K,) [s], q and qd (K, 6) [rad, rad/s].
        joint_names: The robot's joint names (must be the UR joints).
        servo_rate: Control rate [Hz], at least :func:`_min_servo_rate`
            of the samples and at most :data:`MAX_SERVO_RATE`.
        robot_name: For the comment and the error message.

    Raises:
        InputError: If the robot is not a UR arm or the rate is out of range.
    """
    check_ur_joints(list(joint_names), robot_name)
    if not (np.isfinite(servo_rate) and 0.0 < servo_rate <= MAX_SERVO_RATE):
        raise InputError(
            f"servo rate must be > 0 and at most {MAX_SERVO_RATE:g} Hz, got "
            f"{servo_rate}"
        )
    floor = _min_servo_rate(samples.t)
    if servo_rate < floor:
        raise InputError(
            f"servo rate {servo_rate:g} Hz is below {floor:g} Hz, the lower of the "
            f"trajectory's own sample rate and {MIN_SERVO_RATE:g} Hz (fewer servo "
            "commands than samples would lose the trajectory)"
        )
    check_sample_count(
        int((samples.t[-1] - samples.t[0]) * servo_rate) + 1,
        f"URScript at {servo_rate:g} Hz",
    )
    q = resample_hermite(samples, servo_rate)
    dt = 1.0 / servo_rate
    lines = [
        "def workbench_trajectory():",
        f"  # {robot_name}: {len(q)} servo commands at {servo_rate:g} Hz, "
        f"{samples.t[-1] - samples.t[0]:.6g} s; written by workbench export",
        f"  movej({_pose(q[0])}, a={MOVEJ_ACCELERATION:g}, v={MOVEJ_SPEED:g})",
    ]
    lines += [
        f"  servoj({_pose(qk)}, t={dt:.9g}, lookahead_time={LOOKAHEAD_TIME:g}, "
        f"gain={GAIN})"
        for qk in q
    ]
    lines += ["  stopj(2.0)", "end", "workbench_trajectory()", ""]
    return "\n".join(lines)


def write_urscript(
    path: str | Path,
    samples: JointTrajectorySamples,
    joint_names: list[str],
    *,
    servo_rate: float = DEFAULT_SERVO_RATE,
    robot_name: str = "robot",
) -> Path:
    """Write :func:`generate_urscript` to ``path`` (all at once)."""
    text = generate_urscript(
        samples, joint_names, servo_rate=servo_rate, robot_name=robot_name
    )
    return write_text_atomic(path, text)


__all__ = [
    "DEFAULT_SERVO_RATE",
    "MAX_SERVO_RATE",
    "UR_JOINTS",
    "check_ur_joints",
    "generate_urscript",
    "resample_hermite",
    "write_urscript",
]
