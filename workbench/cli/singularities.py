"""``workbench singularities``: singularity analysis at one configuration."""

from __future__ import annotations

import argparse
import math
from typing import Any

import numpy as np

from workbench.cli._common import (
    add_angle_arguments,
    add_json_flag,
    add_robot_argument,
    configuration_from_args,
    format_vector,
    load_robot_from_args,
    print_json,
)
from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.singularities.conditions import (
    CONDITION_UNITS,
    ELBOW_TOL,
    SHOULDER_TOL,
    SINGULARITY_KINDS,
    WRIST_TOL,
    NotPumaTypeError,
    classify_configuration,
    compute_conditions,
    get_factorisation,
)
from workbench.singularities.directions import compute_degenerate_direction
from workbench.singularities.measures import compute_measures
from workbench.singularities.redundant import (
    SRS_CONDITION_UNITS,
    SRS_SINGULARITY_KINDS,
    NotSRSArmError,
    compute_srs_conditions,
    compute_srs_det_jjt,
)


def register(commands: argparse._SubParsersAction) -> None:
    """Add the ``singularities`` command."""
    parser = commands.add_parser(
        "singularities",
        help="singularity analysis at one configuration",
        description=(
            "det J, singular values, manipulability and condition number of the "
            "tool Jacobian (any robot), and for OPW and UR-type arms the signed "
            "distances to the shoulder [m], elbow [sine] and wrist [sin θ5] loci "
            "(SRS seven-axis arms: to their elbow, shoulder, wrist, "
            "shoulder-wrist and arm-angle loci, and det(J Jᵀ) analytic and "
            "numeric); "
            "where a configuration is within tolerance of a locus, its degenerate "
            "direction u (the twist the arm cannot make, at the wrist point and at "
            "the tool) and the self-motion v. "
            "In JSON an infinite condition number is null."
        ),
    )
    add_robot_argument(parser)
    add_angle_arguments(parser)
    add_json_flag(parser)
    parser.set_defaults(
        run=run, progress_message="singularities: analysing the configuration…"
    )


def analyse_configuration(robot: Robot, q: np.ndarray) -> dict[str, Any]:
    """The JSON payload of the command for a validated ``q`` [rad]."""
    measures = compute_measures(robot, q)
    result: dict[str, Any] = {
        "robot": robot.name,
        "q": q,
        "det_j": None if measures.det_j is None else float(measures.det_j),
        "sigma_min": float(measures.sigma_min),
        "manipulability": float(measures.manipulability),
        "condition_number": _finite_or_none(float(measures.condition_number)),
        "singular_values": measures.singular_values,
        "near": dict.fromkeys(SINGULARITY_KINDS),
        "near_units": CONDITION_UNITS,
        "singular": None,
        "tolerances": {
            "shoulder": SHOULDER_TOL,
            "elbow": ELBOW_TOL,
            "wrist": WRIST_TOL,
        },
        "det_j_constant": None,
        "directions": None,
        "srs": _srs(robot, q, measures.singular_values),
    }
    try:
        conditions = compute_conditions(robot, q).as_dict()
    except NotPumaTypeError:
        return result
    result["near"] = {kind: float(value) for kind, value in conditions.items()}
    result["singular"] = list(classify_configuration(robot, q))
    factorisation = get_factorisation(robot)
    result["det_j_constant"] = factorisation.constant
    result["family"] = factorisation.family
    result["directions"] = {
        kind: _direction(robot, q, kind) for kind in result["singular"]
    }
    return result


def _srs(
    robot: Robot, q: np.ndarray, singular_values: np.ndarray
) -> dict[str, Any] | None:
    """An SRS seven-axis arm's distances to its loci and det(J Jᵀ); else None."""
    try:
        conditions = compute_srs_conditions(robot, q).as_dict()
    except NotSRSArmError:
        return None
    return {
        "near": {kind: float(value) for kind, value in conditions.items()},
        "units": SRS_CONDITION_UNITS,
        "det_jjt": float(compute_srs_det_jjt(robot, q)),
        "det_jjt_pinocchio": float(np.prod(np.square(singular_values))),
    }


def _direction(robot: Robot, q: np.ndarray, kind: str) -> dict[str, Any] | None:
    """JSON of the degenerate direction of ``kind`` at ``q``; None if not unique."""
    try:
        d = compute_degenerate_direction(robot, q, kind)
    except InputError:  # on two loci at once, in a way the formula cannot resolve
        return None
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


def run(args: argparse.Namespace) -> int:
    """Print the analysis; returns the exit code."""
    robot = load_robot_from_args(args)
    q = configuration_from_args(robot, args, args.q)
    result = analyse_configuration(robot, q)
    if args.json:
        print_json(result)
        return 0
    det = result["det_j"]
    condition = result["condition_number"]
    print(f"robot            {robot.name}")
    print(f"q [deg]          {format_vector(np.rad2deg(q), 4)}")
    print(f"det J            {'n/a (J not square)' if det is None else f'{det:.6e}'}")
    print(f"singular values  {format_vector(result['singular_values'], 6)}")
    print(f"sigma_min        {result['sigma_min']:.6e}")
    print(f"manipulability   {result['manipulability']:.6e}")
    print(f"condition number {'inf' if condition is None else f'{condition:.6g}'}")
    if (srs := result["srs"]) is not None:
        for kind in SRS_SINGULARITY_KINDS:
            value, unit = srs["near"][kind], SRS_CONDITION_UNITS[kind]
            print(f"near {kind:<14} {value:+.6f}  [{unit}]")
        print(
            f"family           SRS (det(J Jᵀ) = {srs['det_jjt']:.6e} m⁶ analytic, "
            f"{srs['det_jjt_pinocchio']:.6e} from Pinocchio's J)"
        )
        return 0
    if result["singular"] is None:
        print(
            "near             n/a (no analytic conditions for this arm: numeric only)"
        )
        return 0
    for kind in SINGULARITY_KINDS:
        value, unit = result["near"][kind], CONDITION_UNITS[kind]
        print(f"near {kind:<11} {value:+.6f}  [{unit}]")
    print(f"family           {result['family'].upper()} (det J = K s e w)")
    print(f"singular         {', '.join(result['singular']) or 'none'}")
    for kind, d in result["directions"].items():
        if d is None:
            print(f"u {kind:<15}not unique (on two loci at once)")
            continue
        print(f"u {kind:<15}{format_vector(d['u'], 4)}")
        print(f"  reference      {d['reference']}")
        print(f"  at [m]         {format_vector(d['reference_point'], 4)}")
        print(f"  |u^T J|        {d['residual']:.1e}")
        print(f"  u at the tool  {format_vector(d['u_tool'], 4)}")
        print(f"  self-motion v  {format_vector(d['self_motion'], 4)}")
    return 0
