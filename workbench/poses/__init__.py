r"""Pose representations and exact conversions between them.

A rotation ``R`` (3, 3) maps child-frame to parent-frame coordinates, as in
``pin.SE3``; positions are in metres. Modules:

- ``rigid``: checks of rotations and rigid transforms (``as_rotation``, ``as_se3``);
- ``rotations``: axis–angle and quaternions (component order in the name:
  ``quat_wxyz``, ``quat_xyzw``);
- ``angeles7``: the 7-number pose of Angeles et al. (1988),
  ``[e sin(phi), cos(phi), p]``;
- ``targets``: a tool pose typed as numbers (angeles7, matrix, position and
  quaternion), the parser of every command that takes one (``parse_target``).
"""

from workbench.poses.angeles7 import (
    ANGELES7_PRINTED_TOL,
    ANGELES7_TOL,
    angeles4_from_rotation,
    angeles7_from_se3,
    rotation_from_angeles4,
    se3_from_angeles7,
)
from workbench.poses.rigid import (
    RIGIDITY_TOL,
    UNIT_NORM_TOL,
    as_rotation,
    as_se3,
    check_rigid_rows,
    compute_rigidity_errors,
    se3_from_matrix,
)
from workbench.poses.rotations import (
    axis_angle_from_rotation,
    quat_wxyz_from_rotation,
    quat_xyzw_from_rotation,
    rotation_from_axis_angle,
    rotation_from_quat_wxyz,
    rotation_from_quat_xyzw,
)
from workbench.poses.targets import (
    MAX_TARGET_COORDINATE,
    QUAT_TYPED_TOL,
    TARGET_FORMS,
    parse_target,
)

__all__ = [
    "ANGELES7_PRINTED_TOL",
    "ANGELES7_TOL",
    "MAX_TARGET_COORDINATE",
    "QUAT_TYPED_TOL",
    "RIGIDITY_TOL",
    "TARGET_FORMS",
    "UNIT_NORM_TOL",
    "angeles4_from_rotation",
    "angeles7_from_se3",
    "as_rotation",
    "as_se3",
    "axis_angle_from_rotation",
    "check_rigid_rows",
    "compute_rigidity_errors",
    "parse_target",
    "quat_wxyz_from_rotation",
    "quat_xyzw_from_rotation",
    "rotation_from_angeles4",
    "rotation_from_axis_angle",
    "rotation_from_quat_wxyz",
    "rotation_from_quat_xyzw",
    "se3_from_angeles7",
    "se3_from_matrix",
]
