"""Inverse kinematics: closed form for OPW and UR-type arms, numerical for any arm.

Public entry points (see docs/interface.md): ``analytic``, ``analytic_batch``,
``numeric``, ``numeric_batch``, each robot's ``ClosedFormSolver``
(``get_closed_form``), plus the damped-least-squares tools and the compiled
chain's batch of tool Jacobians (``compute_jacobians_local``) and of tool
poses with their manipulability (``compute_tool_poses``).
"""

from workbench.ik.batch_jacobians import compute_jacobians_local
from workbench.ik.batch_poses import compute_tool_poses
from workbench.ik.closed_form import (
    BRANCHES,
    UR_BRANCHES,
    WRIST_SINGULAR_TOL,
    IKSolution,
    UnreachableError,
    UnsupportedRobotError,
    analytic,
    analytic_batch,
    get_branches,
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
from workbench.ik.numerical import IKResult, numeric
from workbench.ik.numerical_batch import IKBatchResult, numeric_batch
from workbench.ik.qp import QP_DAMPING, DifferentialIKError, qp_step
from workbench.ik.solver import ClosedFormSolver, get_closed_form
from workbench.ik.structure import (
    STRUCTURE_TOL,
    KinematicStructure,
    get_structure,
)

__all__ = [
    "BRANCHES",
    "DLS_EPSILON",
    "DLS_LAMBDA_MAX",
    "QP_DAMPING",
    "STRUCTURE_TOL",
    "UR_BRANCHES",
    "WRIST_SINGULAR_TOL",
    "ClosedFormSolver",
    "DifferentialIKError",
    "IKBatchResult",
    "IKResult",
    "IKSolution",
    "KinematicStructure",
    "UnreachableError",
    "UnsupportedRobotError",
    "analytic",
    "analytic_batch",
    "compute_jacobians_local",
    "compute_tool_poses",
    "dls_inverse",
    "dls_step",
    "get_branches",
    "get_closed_form",
    "get_structure",
    "nearest",
    "numeric",
    "numeric_batch",
    "qp_step",
    "solve_null_space_velocity",
    "solve_velocity",
]
