"""Inverse kinematics: closed form for OPW, UR, SRS and Franka arms, numerical for any.

Public entry points (see docs/interface.md): the closed-form families
(``Family``, ``FAMILIES``, ``get_family``), ``analytic``, ``analytic_batch``,
``numeric``, ``numeric_batch``, each robot's ``ClosedFormSolver``
(``get_closed_form``) or, for seven-axis arms, ``RedundantSolver``
(``get_redundant_solver``) with the redundancy tools (``redundancy_parameter``,
``feasible_redundancy``, ``choose_redundancy``), plus the damped-least-squares
tools and the compiled chain's batch of tool Jacobians
(``compute_jacobians_local``) and of tool poses with their manipulability
(``compute_tool_poses``), and the one rule that chooses a configuration
among the branches (``select``, ``pick_place_configurations``).
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
from workbench.ik.families import (
    FAMILIES,
    Family,
    get_family,
    get_family_refusal,
    require_family,
)
from workbench.ik.numerical import IKResult, numeric
from workbench.ik.numerical_batch import IKBatchResult, numeric_batch
from workbench.ik.pick_place import pick_place_configurations
from workbench.ik.qp import QP_DAMPING, DifferentialIKError, qp_step
from workbench.ik.redundancy import (
    RedundancyChoice,
    choose_redundancy,
    feasible_redundancy,
    redundancy_parameter,
)
from workbench.ik.redundant import (
    FRANKA_BRANCHES,
    SRS_BRANCHES,
    FeasibleRedundancy,
    RedundantIKSolution,
    RedundantSolver,
    get_redundant_solver,
)
from workbench.ik.selection import (
    DEFAULT_RULE,
    NUMERIC_BRANCH,
    RULES,
    IKChoice,
    compute_limit_margin,
    select,
)
from workbench.ik.solver import ClosedFormSolver, get_closed_form
from workbench.ik.structure import (
    STRUCTURE_TOL,
    KinematicStructure,
    get_structure,
)

__all__ = [
    "BRANCHES",
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
    "UR_BRANCHES",
    "WRIST_SINGULAR_TOL",
    "ClosedFormSolver",
    "DifferentialIKError",
    "Family",
    "FeasibleRedundancy",
    "IKBatchResult",
    "IKChoice",
    "IKResult",
    "IKSolution",
    "KinematicStructure",
    "RedundancyChoice",
    "RedundantIKSolution",
    "RedundantSolver",
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
    "feasible_redundancy",
    "get_branches",
    "get_closed_form",
    "get_family",
    "get_family_refusal",
    "get_redundant_solver",
    "get_structure",
    "nearest",
    "numeric",
    "numeric_batch",
    "pick_place_configurations",
    "qp_step",
    "redundancy_parameter",
    "require_family",
    "select",
    "solve_null_space_velocity",
    "solve_velocity",
]
