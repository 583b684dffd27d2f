"""Multi-rate commands: joint commands interpolated from planning to servo rate.

Kang (2007, §5): "the motion commands are generated at longer sampling times
... Then they are interpolated in the joint space to obtain the fine motion
commands at the joint servo control level."
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.trajectory.csv_io import JointTrajectorySamples


def interpolate_servo(
    t: npt.ArrayLike, q: npt.ArrayLike, qd: npt.ArrayLike, samples_per_cycle: int
) -> JointTrajectorySamples:
    r"""Cubic Hermite interpolation of planning-rate commands at the servo rate.

    On each planning interval :math:`[t_k, t_{k+1}]` the cubic matches
    :math:`q_k, \dot q_k, q_{k+1}, \dot q_{k+1}`, so position and velocity are
    continuous across intervals (acceleration is piecewise linear).

    Args:
        t: Planning instants (K,) [s], equally spaced, K >= 1.
        q: Joint positions (K, n) [rad].
        qd: Joint velocities (K, n) [rad/s].
        samples_per_cycle: Servo samples per planning interval, >= 1.

    Returns:
        Servo samples at :math:`t_0 + i\,\Delta t / m`, i = 0 .. m (K - 1).
    """
    t = np.asarray(t, dtype=np.float64)
    q = np.asarray(q, dtype=np.float64)
    qd = np.asarray(qd, dtype=np.float64)
    m = int(samples_per_cycle)
    if m < 1 or t.ndim != 1 or q.shape != qd.shape or q.shape[:1] != t.shape:
        raise InputError("interpolate_servo needs t (K,), q and qd (K, n), m >= 1")
    if t.size == 1:
        return JointTrajectorySamples(t.copy(), q.copy(), qd.copy(), np.zeros_like(q))
    h = np.diff(t)[:, None, None]  # (K-1, 1, 1)
    s = (np.arange(m) / m)[None, :, None]  # (1, m, 1)
    q0, q1 = q[:-1, None, :], q[1:, None, :]
    v0, v1 = qd[:-1, None, :] * h, qd[1:, None, :] * h  # tangents scaled to [0, 1]
    dq = q1 - q0
    c2 = 3.0 * dq - 2.0 * v0 - v1
    c3 = -2.0 * dq + v0 + v1
    pos = q0 + s * (v0 + s * (c2 + s * c3))
    vel = (v0 + s * (2.0 * c2 + 3.0 * s * c3)) / h
    acc = (2.0 * c2 + 6.0 * s * c3) / (h * h)
    n = q.shape[1]
    times = (t[:-1, None] + np.diff(t)[:, None] * (np.arange(m) / m)[None, :]).ravel()
    last_acc = ((2.0 * c2 + 6.0 * c3) / (h * h))[-1]
    return JointTrajectorySamples(
        t=np.append(times, t[-1]),
        q=np.vstack([pos.reshape(-1, n), q[-1]]),
        qd=np.vstack([vel.reshape(-1, n), qd[-1]]),
        qdd=np.vstack([acc.reshape(-1, n), last_acc]),
    )


__all__ = ["interpolate_servo"]
