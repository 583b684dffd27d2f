r"""How far a configuration is from a singularity, as a number in [0, 1] and a colour.

Two methods, chosen per robot by :meth:`SingularityGauge.from_robot`:

* ``"analytic"`` (PUMA-type DH tables, :mod:`workbench.singularities.conditions`): the
  smallest of the three signed distances made dimensionless,
  :math:`\min(|s| / (a_2 + L_3),\ |e|,\ |w|)`, with the shoulder distance
  :math:`s` [m] divided by the arm's reach :math:`a_2 + L_3` and the elbow and
  wrist sines :math:`e, w` as they are.
* ``"jacobian"`` (any arm): the inverse condition number of the tool Jacobian
  with its linear rows divided by a characteristic length :math:`L` (so metres
  and radians weigh alike),

  .. math::
      \mu(q) = \frac{\sigma_{\min}(S J(q))}{\sigma_{\max}(S J(q))}, \qquad
      S = \mathrm{diag}(I_3 / L, I_3),

  divided by its 95th percentile over configurations drawn uniformly within
  the joint limits (clipped to 1).

Both are 0 exactly at a singularity; the colour ramp runs red → amber → green.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.model.robot import Robot
from workbench.singularities.conditions import (
    compute_conditions,
    find_puma_factorisation,
)

FloatArray = npt.NDArray[np.float64]


def _characteristic_length(robot: Robot) -> float:
    """Sum of the distances between successive joint origins and the tool [m]."""
    model = robot.model
    data = model.createData()
    q = np.clip(np.zeros(model.nq), robot.lower, robot.upper)
    pin.forwardKinematics(model, data, q)
    pin.updateFramePlacements(model, data)
    points = [data.oMi[i].translation for i in range(model.njoints)]
    points.append(data.oMf[robot.tool_frame_id].translation)
    length = float(np.sum(np.linalg.norm(np.diff(np.array(points), axis=0), axis=1)))
    return length if length > 0.0 else 1.0


def _inverse_condition(jacobian: FloatArray, length: float) -> float:
    scaled = np.array(jacobian, dtype=np.float64).reshape(6, -1)  # nv = 1 gives (6,)
    scaled[:3] /= length
    sigma = np.linalg.svd(scaled, compute_uv=False)
    return float(sigma[-1] / sigma[0]) if sigma[0] > 0.0 else 0.0


@dataclass(frozen=True, slots=True)
class SingularityGauge:
    """Distance to the nearest singularity of one robot, normalised to [0, 1].

    Build it with :meth:`from_robot`.

    Attributes:
        robot: The robot.
        method: ``"analytic"`` or ``"jacobian"`` (see the module docstring).
        length: Length that makes distances dimensionless [m]: the reach
            :math:`a_2 + L_3` (analytic) or the characteristic length L
            (jacobian).
        reference: Raw value mapped to distance 1 (1 for ``"analytic"``).
    """

    robot: Robot
    method: str
    length: float
    reference: float

    SAMPLES: ClassVar[int] = 256
    """Configurations drawn (seeded, reproducible) to set the Jacobian reference."""

    COLOR_STOPS: ClassVar[tuple[tuple[float, tuple[float, float, float]], ...]] = (
        (0.0, (0.85, 0.1, 0.1)),
        (0.2, (0.95, 0.7, 0.1)),
        (0.5, (0.2, 0.7, 0.3)),
    )
    """(distance, RGB) stops of the colour ramp; beyond the last it stays green."""

    @classmethod
    def from_robot(cls, robot: Robot) -> SingularityGauge:
        """Analytic gauge for PUMA-type arms, Jacobian gauge otherwise."""
        factors = find_puma_factorisation(robot)
        if factors is not None:
            return cls(robot, "analytic", abs(factors.a2) + factors.forearm, 1.0)
        length = _characteristic_length(robot)
        rng = np.random.default_rng(0)
        finite = np.isfinite(robot.lower) & np.isfinite(robot.upper)
        lower = np.where(finite, robot.lower, -np.pi)
        upper = np.where(finite, robot.upper, np.pi)
        samples = rng.uniform(lower, upper, size=(cls.SAMPLES, robot.nq))
        values = [_inverse_condition(robot.jacobian(q), length) for q in samples]
        reference = float(np.percentile(values, 95))
        return cls(robot, "jacobian", length, reference if reference > 0.0 else 1.0)

    def compute_distance(self, q: npt.ArrayLike) -> float:
        """Normalised distance to the nearest singularity.

        Args:
            q: Configuration, shape (nq,) [rad].

        Returns:
            In [0, 1]: 0 at a singularity, 1 far from every one.

        Raises:
            DimensionError: If ``q`` has the wrong size.
            NonFiniteError: If ``q`` has NaN or infinite entries.
        """
        q = self.robot.check_configuration(q)
        if self.method == "analytic":
            c = compute_conditions(self.robot, q)
            raw = min(
                abs(float(c.shoulder)) / self.length,
                abs(float(c.elbow)),
                abs(float(c.wrist)),
            )
        else:
            raw = _inverse_condition(self.robot.jacobian(q), self.length)
        return min(1.0, float(raw) / self.reference)

    def compute_color(self, q: npt.ArrayLike) -> FloatArray:
        """Colour of the arm at ``q`` (nq,) [rad]: RGB, shape (3,), in [0, 1]."""
        return get_singularity_color(self.compute_distance(q))


def get_singularity_color(distance: float) -> FloatArray:
    """Colour ramp red (0) → amber (0.2) → green (0.5 and beyond).

    Args:
        distance: Normalised distance in [0, 1] (clipped).

    Returns:
        RGB, shape (3,), each in [0, 1].
    """
    stops = SingularityGauge.COLOR_STOPS
    x = float(np.clip(distance, 0.0, 1.0))
    positions = [s[0] for s in stops]
    colors = np.array([s[1] for s in stops])
    return np.array([np.interp(x, positions, colors[:, i]) for i in range(3)])
