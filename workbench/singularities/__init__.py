"""Singularities: analytic conditions, measures, loci, directions, along a path.

Modules, in the order they build on each other:

- ``conditions``: det J of an OPW (PUMA-type) or UR-type arm factorised into its
  shoulder, elbow and wrist conditions (Kang 2007, Section 3 for the PUMA), derived
  from the robot's kinematic structure;
- ``measures``: SVD measures of any Jacobian (a compiled Jacobi SVD), joint-space
  grids, the cross-check of the analytic det J against Pinocchio;
- ``loci``: the elbow-singular θ3, the shoulder-singular θ2 and one configuration on
  each locus, in closed form for any OPW or UR-type arm;
- ``directions``: the Cartesian direction a singular configuration cannot move in (the
  left null vector of J, derived from the joint axes of any OPW or UR-type arm);
- ``along_path``: the closest approaches of a joint trajectory to each singularity;
- ``redundant``: SRS seven-axis arms (KUKA LBR iiwa): det(J Jᵀ) of the 6 × 7
  Jacobian factorised, the elbow, shoulder, wrist and shoulder-wrist loci, the lost
  directions, and the arm angle's algorithmic singularity;
- ``analysis``: all of the above at one configuration, in one result
  (``workbench singularities``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from workbench._lazy import attach

if TYPE_CHECKING:
    from workbench.singularities.along_path import (
        ClosestApproach,
        find_closest_approaches,
    )
    from workbench.singularities.analysis import (
        ConfigurationAnalysis,
        SRSAnalysis,
        analyse_configuration,
    )
    from workbench.singularities.conditions import (
        CONDITION_UNITS,
        ELBOW_TOL,
        SHOULDER_TOL,
        SINGULARITY_KINDS,
        WRIST_TOL,
        NotPumaTypeError,
        PumaFactorisation,
        SingularityConditions,
        URFactorisation,
        classify_configuration,
        compute_conditions,
        compute_det_j_analytic,
        find_factorisation,
        find_puma_factorisation,
        get_factorisation,
        get_puma_factorisation,
    )
    from workbench.singularities.directions import (
        DegenerateDirection,
        compute_degenerate_direction,
        compute_joint_axes,
        compute_wrist_center_jacobian,
        compute_wrist_point,
    )
    from workbench.singularities.loci import (
        compute_example_configurations,
        get_elbow_singular_theta3,
        solve_shoulder_theta2,
    )
    from workbench.singularities.measures import (
        DetCrossCheck,
        JacobianMeasures,
        JointGrid,
        compute_dh_jacobians,
        compute_joint_grid,
        compute_measures,
        compute_measures_from_jacobians,
        compute_singular_values,
        cross_check_det_j,
    )
    from workbench.singularities.redundant import (
        SRS_CONDITION_UNITS,
        SRS_SINGULARITY_KINDS,
        NotSRSArmError,
        SRSConditions,
        SRSDegenerateDirection,
        SRSFactorisation,
        compute_srs_conditions,
        compute_srs_degenerate_direction,
        compute_srs_det_jjt,
        find_srs_factorisation,
        get_srs_factorisation,
    )

__all__ = [
    "CONDITION_UNITS",
    "ELBOW_TOL",
    "SHOULDER_TOL",
    "SINGULARITY_KINDS",
    "SRS_CONDITION_UNITS",
    "SRS_SINGULARITY_KINDS",
    "WRIST_TOL",
    "ClosestApproach",
    "ConfigurationAnalysis",
    "DegenerateDirection",
    "DetCrossCheck",
    "JacobianMeasures",
    "JointGrid",
    "NotPumaTypeError",
    "NotSRSArmError",
    "PumaFactorisation",
    "SRSAnalysis",
    "SRSConditions",
    "SRSDegenerateDirection",
    "SRSFactorisation",
    "SingularityConditions",
    "URFactorisation",
    "analyse_configuration",
    "classify_configuration",
    "compute_conditions",
    "compute_degenerate_direction",
    "compute_det_j_analytic",
    "compute_dh_jacobians",
    "compute_example_configurations",
    "compute_joint_axes",
    "compute_joint_grid",
    "compute_measures",
    "compute_measures_from_jacobians",
    "compute_singular_values",
    "compute_srs_conditions",
    "compute_srs_degenerate_direction",
    "compute_srs_det_jjt",
    "compute_wrist_center_jacobian",
    "compute_wrist_point",
    "cross_check_det_j",
    "find_closest_approaches",
    "find_factorisation",
    "find_puma_factorisation",
    "find_srs_factorisation",
    "get_elbow_singular_theta3",
    "get_factorisation",
    "get_puma_factorisation",
    "get_srs_factorisation",
    "solve_shoulder_theta2",
]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
