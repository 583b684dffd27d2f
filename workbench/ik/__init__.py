r"""Inverse kinematics: closed form for OPW, UR, SRS and Franka arms, numerical for any.

Public entry points (see docs/interface.md): the closed-form families
(``Family``, ``FAMILIES``, ``get_family``), ``analytic``, ``analytic_batch``,
``numeric``, ``numeric_batch``, each robot's one ``Solver`` (``get_solver``,
every family: six axes and, with ``redundancy=``, seven) returning
``IKSolution``\ s (flags: ``Flag``), the redundancy choice
(``choose_redundancy``), plus the damped-least-squares
tools and the compiled chain's batch of tool Jacobians
(``compute_jacobians_local``) and of tool poses with their manipulability
(``compute_tool_poses``), and the one rule that chooses a configuration
among the branches (``select``, ``pick_place_configurations``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from workbench._lazy import attach

if TYPE_CHECKING:
    from workbench.errors import (
        DifferentialIKError,
        UnreachableError,
        UnsupportedRobotError,
    )
    from workbench.ik._flags import Flag, SolveFlag
    from workbench.ik.batch_jacobians import compute_jacobians_local
    from workbench.ik.batch_poses import compute_tool_poses
    from workbench.ik.closed_form import (
        BRANCHES,
        UR_BRANCHES,
        WRIST_SINGULAR_TOL,
        analytic,
        analytic_batch,
        nearest,
    )
    from workbench.ik.damped import (
        DLS_EPSILON,
        DLS_LAMBDA_MAX,
        dls_inverse,
        dls_step,
        solve_null_space_velocity,
        solve_velocity,
    )
    from workbench.ik.families import (
        FAMILIES,
        Family,
        get_family,
        get_family_refusal,
        require_family,
    )
    from workbench.ik.numerical import TARGET_PARTS, IKResult, numeric
    from workbench.ik.numerical_batch import IKBatchResult, numeric_batch
    from workbench.ik.pick_place import pick_place_configurations
    from workbench.ik.qp import QP_DAMPING, qp_step
    from workbench.ik.redundancy import RedundancyChoice, choose_redundancy
    from workbench.ik.redundant import FRANKA_BRANCHES, SRS_BRANCHES, FeasibleRedundancy
    from workbench.ik.selection import (
        DEFAULT_RULE,
        NUMERIC_BRANCH,
        RULES,
        IKChoice,
        compute_limit_margin,
        select,
    )
    from workbench.ik.solution import IKSolution, Solutions
    from workbench.ik.solver import Solver, get_solver
    from workbench.ik.structure import (
        CALIBRATION_ANGLE_TOL,
        CALIBRATION_DISTANCE_TOL,
        STRUCTURE_TOL,
        KinematicStructure,
        StructureDeviation,
        get_structure,
    )

__all__ = [
    "BRANCHES",
    "CALIBRATION_ANGLE_TOL",
    "CALIBRATION_DISTANCE_TOL",
    "DEFAULT_RULE",
    "DLS_EPSILON",
    "DLS_LAMBDA_MAX",
    "FAMILIES",
    "FRANKA_BRANCHES",
    "NUMERIC_BRANCH",
    "QP_DAMPING",
    "RULES",
    "SRS_BRANCHES",
    "STRUCTURE_TOL",
    "TARGET_PARTS",
    "UR_BRANCHES",
    "WRIST_SINGULAR_TOL",
    "DifferentialIKError",
    "Family",
    "FeasibleRedundancy",
    "Flag",
    "IKBatchResult",
    "IKChoice",
    "IKResult",
    "IKSolution",
    "KinematicStructure",
    "RedundancyChoice",
    "Solutions",
    "SolveFlag",
    "Solver",
    "StructureDeviation",
    "UnreachableError",
    "UnsupportedRobotError",
    "analytic",
    "analytic_batch",
    "choose_redundancy",
    "compute_jacobians_local",
    "compute_limit_margin",
    "compute_tool_poses",
    "dls_inverse",
    "dls_step",
    "get_family",
    "get_family_refusal",
    "get_solver",
    "get_structure",
    "nearest",
    "numeric",
    "numeric_batch",
    "pick_place_configurations",
    "qp_step",
    "require_family",
    "select",
    "solve_null_space_velocity",
    "solve_velocity",
]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
