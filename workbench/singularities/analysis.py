"""Everything the package says about one configuration, in one result.

:func:`analyse_configuration` gathers, at one ``q``: the SVD measures of the
tool Jacobian (any robot, :func:`~workbench.singularities.compute_measures`);
for an OPW or UR-type arm the signed distances to its shoulder, elbow and
wrist loci, the kinds within tolerance, det J's constant and the degenerate
direction of each such kind (:mod:`~workbench.singularities.conditions`,
:mod:`~workbench.singularities.directions`); for an SRS seven-axis arm the
distances to its loci and det(J Jᵀ), analytic and from Pinocchio's J
(:mod:`~workbench.singularities.redundant`). ``workbench singularities``
prints it; :meth:`ConfigurationAnalysis.as_dict` is that command's JSON.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.singularities.conditions import (
    CONDITION_UNITS,
    ELBOW_TOL,
    SHOULDER_TOL,
    SINGULARITY_KINDS,
    WRIST_TOL,
    classify_configuration,
    compute_conditions,
    find_factorisation,
)
from workbench.singularities.directions import (
    DegenerateDirection,
    compute_degenerate_direction,
)
from workbench.singularities.measures import JacobianMeasures, compute_measures
from workbench.singularities.redundant import (
    SRS_CONDITION_UNITS,
    compute_srs_conditions,
    compute_srs_det_jjt,
    find_srs_factorisation,
)

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class SRSAnalysis:
    """An SRS seven-axis arm's loci at one configuration.

    Attributes:
        near: Signed distance to each locus (``elbow``, ``shoulder``,
            ``wrist``, ``shoulder_wrist``, ``arm_angle``), units in
            :data:`~workbench.singularities.SRS_CONDITION_UNITS`.
        det_jjt: det(J Jᵀ) of the 6 × 7 tool Jacobian, analytic [m⁶].
        det_jjt_pinocchio: The same as Π σᵢ² of Pinocchio's J [m⁶].
    """

    near: dict[str, float]
    det_jjt: float
    det_jjt_pinocchio: float


@dataclass(frozen=True, slots=True)
class ConfigurationAnalysis:
    """The singularity analysis of one configuration (:func:`analyse_configuration`).

    Attributes:
        robot: The robot's name.
        q: The configuration, shape (nq,) [rad], a read-only copy.
        measures: SVD measures of Pinocchio's tool Jacobian (unbatched).
        near: OPW or UR-type arm: signed distance to each locus
            (``shoulder`` [m], ``elbow`` [sine], ``wrist`` [sin θ5],
            :data:`~workbench.singularities.CONDITION_UNITS`); None otherwise.
        singular: The kinds within tolerance (``SHOULDER_TOL``, ``ELBOW_TOL``,
            ``WRIST_TOL``); None for an arm of neither family.
        family: ``"opw"`` or ``"ur"``, None for an arm of neither.
        det_j_constant: K of det J = K · shoulder · elbow · wrist, or None.
        directions: For each kind in ``singular``, its degenerate direction,
            None where it is not unique (on two loci at once); None for an
            arm of neither family.
        srs: An SRS seven-axis arm's loci, None for any other arm.
    """

    robot: str
    q: FloatArray
    measures: JacobianMeasures
    near: dict[str, float] | None
    singular: tuple[str, ...] | None
    family: str | None
    det_j_constant: float | None
    directions: dict[str, DegenerateDirection | None] | None
    srs: SRSAnalysis | None

    def as_dict(self) -> dict[str, Any]:
        """JSON form: the output of ``workbench singularities --json``.

        Keys ``robot, q, det_j, sigma_min, manipulability, condition_number``
        (null when infinite), ``singular_values, near, near_units, singular,
        tolerances, det_j_constant, directions, srs`` and, for an OPW or
        UR-type arm, ``family``.
        """
        m = self.measures
        near = dict.fromkeys(SINGULARITY_KINDS) if self.near is None else self.near
        result: dict[str, Any] = {
            "robot": self.robot,
            "q": self.q,
            "det_j": None if m.det_j is None else float(m.det_j),
            "sigma_min": float(m.sigma_min),
            "manipulability": float(m.manipulability),
            "condition_number": _finite_or_none(float(m.condition_number)),
            "singular_values": m.singular_values,
            "near": near,
            "near_units": CONDITION_UNITS,
            "singular": None if self.singular is None else list(self.singular),
            "tolerances": {
                "shoulder": SHOULDER_TOL,
                "elbow": ELBOW_TOL,
                "wrist": WRIST_TOL,
            },
            "det_j_constant": self.det_j_constant,
            "directions": None,
            "srs": None,
        }
        if self.srs is not None:
            result["srs"] = {
                "near": self.srs.near,
                "units": SRS_CONDITION_UNITS,
                "det_jjt": self.srs.det_jjt,
                "det_jjt_pinocchio": self.srs.det_jjt_pinocchio,
            }
        if self.family is not None:
            result["family"] = self.family
        if self.directions is not None:
            result["directions"] = {
                kind: None if d is None else _direction_dict(d)
                for kind, d in self.directions.items()
            }
        return result


def analyse_configuration(robot: Robot, q: npt.ArrayLike) -> ConfigurationAnalysis:
    """The singularity analysis of ``robot`` at ``q`` (see the module docstring).

    Args:
        robot: Any robot; OPW and UR-type arms get their analytic conditions,
            SRS seven-axis arms theirs.
        q: Configuration, shape (nq,) [rad].

    Returns:
        The measures, distances, singular kinds and degenerate directions.

    Raises:
        DimensionError: If ``q`` does not have nq values.
        NonFiniteError: If ``q`` holds NaN or infinity.
    """
    q = robot.check_configuration(q).copy()
    q.setflags(write=False)
    measures = compute_measures(robot, q)
    srs = _srs(robot, q, measures.singular_values)
    factorisation = find_factorisation(robot)
    if factorisation is None:
        return ConfigurationAnalysis(
            robot.name, q, measures, None, None, None, None, None, srs
        )
    conditions = compute_conditions(robot, q).as_dict()
    singular = tuple(classify_configuration(robot, q))
    return ConfigurationAnalysis(
        robot.name,
        q,
        measures,
        {kind: float(value) for kind, value in conditions.items()},
        singular,
        factorisation.family,
        factorisation.constant,
        {kind: _direction(robot, q, kind) for kind in singular},
        srs,
    )


def _srs(
    robot: Robot, q: FloatArray, singular_values: FloatArray
) -> SRSAnalysis | None:
    """An SRS seven-axis arm's distances to its loci and det(J Jᵀ); else None."""
    if find_srs_factorisation(robot) is None:
        return None
    conditions = compute_srs_conditions(robot, q).as_dict()
    return SRSAnalysis(
        {kind: float(value) for kind, value in conditions.items()},
        float(compute_srs_det_jjt(robot, q)),
        float(np.prod(np.square(singular_values))),
    )


def _direction(robot: Robot, q: FloatArray, kind: str) -> DegenerateDirection | None:
    """The degenerate direction of ``kind`` at ``q``; None if not unique."""
    try:
        return compute_degenerate_direction(robot, q, kind)
    except InputError:  # on two loci at once, in a way the formula cannot resolve
        return None


def _direction_dict(d: DegenerateDirection) -> dict[str, Any]:
    """JSON of a degenerate direction, as ``workbench singularities`` prints it."""
    return {
        "reference": d.reference,
        "reference_point": d.reference_point,
        "u": d.direction,
        "residual": d.residual,
        "u_tool": d.tool_direction,
        "residual_tool": d.tool_residual,
        "self_motion": d.self_motion,
    }


def _finite_or_none(value: float) -> float | None:
    return value if math.isfinite(value) else None


__all__ = ["ConfigurationAnalysis", "SRSAnalysis", "analyse_configuration"]
