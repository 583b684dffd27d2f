"""``workbench singularities``: singularity analysis at one configuration.

The analysis is :func:`workbench.singularities.analyse_configuration`; its
``as_dict()`` is the ``--json`` output.
"""

from __future__ import annotations

import argparse

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
from workbench.singularities import (
    CONDITION_UNITS,
    SINGULARITY_KINDS,
    SRS_CONDITION_UNITS,
    SRS_SINGULARITY_KINDS,
    analyse_configuration,
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


def run(args: argparse.Namespace) -> int:
    """Print the analysis; returns the exit code."""
    robot = load_robot_from_args(args)
    q = configuration_from_args(robot, args, args.q)
    result = analyse_configuration(robot, q).as_dict()
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
