"""Names of the robots the workbench can load without a path.

``puma560`` and ``puma560-kang`` are this project's own URDFs (``urdf/``),
generated from the papers' DH tables. Every other name is a robot of the
``example-robot-data`` data package (6.0.0 or newer), with the names of that
project's Python loaders. The workbench does not use those loaders: the
``example-robot-data-loaders`` 5.0.0 package pins ``example-robot-data==5.0.0``,
so we read the current data files directly and keep the name table here.

Robots that the loaders mount on a free flyer (legged, humanoid, flying) are
loaded with a fixed base: this is a kinematics workbench for arms. The two
joint-less drones (``hector``, ``iris``) are therefore left out.
"""

from __future__ import annotations

import importlib.metadata
from dataclasses import dataclass
from pathlib import Path

from workbench.errors import URDFLoadError

_PACKAGE_ROOT = Path(__file__).resolve().parents[1]  # workbench/


@dataclass(frozen=True, slots=True)
class CatalogEntry:
    """Where a named robot's URDF is and how to cut it to an arm.

    Attributes:
        urdf: Path of the URDF relative to example-robot-data's ``robots/``
            folder, or to this project's ``urdf/`` folder for the PUMAs.
        tool_frame: Default tool frame; None for the last frame of the model.
        locked_joints: Joints fixed at their neutral value (e.g. gripper
            fingers), so that ``q`` holds the arm joints only.
        own: True for this project's URDFs, False for example-robot-data.
    """

    urdf: str
    tool_frame: str | None = None
    locked_joints: tuple[str, ...] = ()
    own: bool = False


_PANDA_FINGERS = ("panda_finger_joint1", "panda_finger_joint2")

# Hands whose <mimic> joints Pinocchio cannot represent (a finger comes before
# the joint it follows, or follows a joint the URDF does not have): the whole
# hand is locked, leader and followers alike, as the panda's fingers are.
_ROMEO_HANDS = tuple(
    f"{side}{joint}"
    for side in "LR"
    for joint in (
        "Hand",
        *(f"Finger{i}{k}" for i in (1, 2, 3) for k in (1, 2, 3) if (i, k) != (1, 1)),
        "Thumb1",
        "Thumb2",
        "Thumb3",
    )
)
_TALOS_GRIPPERS = tuple(
    f"gripper_{side}_{joint}"
    for side in ("left", "right")
    for joint in (
        "joint",
        "inner_double_joint",
        "fingertip_1_joint",
        "fingertip_2_joint",
        "motor_single_joint",
        "inner_single_joint",
        "fingertip_3_joint",
    )
)
_PSYONIC_FINGER_TIPS = tuple(
    f"{side}_{finger}_q2"
    for side in ("Left", "Right")
    for finger in ("index", "middle", "ring", "pinky")
)

CATALOG: dict[str, CatalogEntry] = {
    "puma560": CatalogEntry("puma560.urdf", "wrist_center", own=True),
    "puma560-kang": CatalogEntry("puma560-kang.urdf", "wrist_center", own=True),
    "kuka-kr6-r700": CatalogEntry("kuka-kr6-r700.urdf", "flange", own=True),
    "abb-irb2400": CatalogEntry("abb-irb2400.urdf", "flange", own=True),
    "generic6r": CatalogEntry("generic6r.urdf", "flange", own=True),
    "iiwa14": CatalogEntry("iiwa14.urdf", "flange", own=True),
    "a1": CatalogEntry("a1_description/urdf/a1.urdf"),
    "alex_nub_hands": CatalogEntry("alex_description/urdf/alex_nub_hands.urdf"),
    "alex_psyonic_hands": CatalogEntry(
        "alex_description/urdf/alex_psyonic_hands.urdf",
        locked_joints=_PSYONIC_FINGER_TIPS,
    ),
    "alex_sake_hands": CatalogEntry("alex_description/urdf/alex_sake_hands.urdf"),
    "alexander": CatalogEntry(
        "alexander_description/urdf/alexander_v1.lowerBodyOnly.urdf"
    ),
    "allegro_left_hand": CatalogEntry(
        "allegro_hand_description/urdf/allegro_left_hand.urdf"
    ),
    "allegro_right_hand": CatalogEntry(
        "allegro_hand_description/urdf/allegro_right_hand.urdf"
    ),
    "anymal": CatalogEntry("anymal_b_simple_description/robots/anymal.urdf"),
    "anymal_c": CatalogEntry("anymal_c_simple_description/urdf/anymal.urdf"),
    "anymal_kinova": CatalogEntry(
        "anymal_b_simple_description/robots/anymal-kinova.urdf"
    ),
    "asr_twodof": CatalogEntry("asr_twodof_description/urdf/TwoDofs.urdf"),
    "b1": CatalogEntry("b1_description/urdf/b1.urdf"),
    "b1_z1": CatalogEntry("b1_description/urdf/b1-z1.urdf"),
    "baxter": CatalogEntry("baxter_description/urdf/baxter.urdf"),
    "bolt": CatalogEntry("bolt_description/robots/bolt.urdf"),
    "borinot": CatalogEntry("borinot_description/urdf/borinot_flying_arm_2.urdf"),
    "centauro": CatalogEntry("centauro_description/urdf/centauro.urdf"),
    "double_pendulum": CatalogEntry(
        "double_pendulum_description/urdf/double_pendulum.urdf"
    ),
    "double_pendulum_continuous": CatalogEntry(
        "double_pendulum_description/urdf/double_pendulum_continuous.urdf"
    ),
    "double_pendulum_simple": CatalogEntry(
        "double_pendulum_description/urdf/double_pendulum_simple.urdf"
    ),
    "finger_edu": CatalogEntry("finger_edu_description/robots/finger_edu.urdf"),
    "g1": CatalogEntry("g1_description/urdf/g1_29dof_rev_1_0.urdf"),
    "g1_with_hands": CatalogEntry(
        "g1_description/urdf/g1_29dof_with_hand_rev_1_0.urdf"
    ),
    "go1": CatalogEntry("go1_description/urdf/go1.urdf"),
    "go2": CatalogEntry("go2_description/urdf/go2.urdf"),
    "hextilt": CatalogEntry("hextilt_description/urdf/hextilt_flying_arm_5.urdf"),
    "human": CatalogEntry("human_description/robots/human.urdf"),
    "hyq": CatalogEntry("hyq_description/robots/hyq_no_sensors.urdf"),
    "icub": CatalogEntry("icub_description/robots/icub.urdf"),
    "icub_reduced": CatalogEntry("icub_description/robots/icub_reduced.urdf"),
    "kinova": CatalogEntry("kinova_description/robots/kinova.urdf"),
    "laikago": CatalogEntry("laikago_description/urdf/laikago.urdf"),
    "panda": CatalogEntry(
        "panda_description/urdf/panda.urdf", "panda_hand_tcp", _PANDA_FINGERS
    ),
    "panda_collision": CatalogEntry(
        "panda_description/urdf/panda_collision.urdf", "panda_hand_tcp", _PANDA_FINGERS
    ),
    "pr2": CatalogEntry("pr2_description/urdf/pr2.urdf"),
    "quadruped": CatalogEntry("quadruped_description/urdf/quadruped.urdf"),
    "romeo": CatalogEntry(
        "romeo_description/urdf/romeo.urdf", locked_joints=_ROMEO_HANDS
    ),
    "simple_humanoid": CatalogEntry(
        "simple_humanoid_description/urdf/simple_humanoid.urdf"
    ),
    "simple_humanoid_classical": CatalogEntry(
        "simple_humanoid_description/urdf/simple_humanoid_classical.urdf"
    ),
    "so100": CatalogEntry("so_arm_description/urdf/so100.urdf"),
    "so101": CatalogEntry("so_arm_description/urdf/so101.urdf"),
    "solo8": CatalogEntry("solo_description/robots/solo.urdf"),
    "solo12": CatalogEntry("solo_description/robots/solo12.urdf"),
    "talos": CatalogEntry("talos_data/robots/talos_reduced.urdf"),
    "talos_arm": CatalogEntry("talos_data/robots/talos_left_arm.urdf"),
    "talos_box": CatalogEntry("talos_data/robots/talos_reduced_box.urdf"),
    "talos_full": CatalogEntry(
        "talos_data/robots/talos_full_v2.urdf", locked_joints=_TALOS_GRIPPERS
    ),
    "talos_full_box": CatalogEntry(
        "talos_data/robots/talos_full_v2_box.urdf", locked_joints=_TALOS_GRIPPERS
    ),
    "tiago": CatalogEntry("tiago_description/robots/tiago.urdf"),
    "tiago_dual": CatalogEntry("tiago_description/robots/tiago_dual.urdf"),
    "tiago_no_hand": CatalogEntry("tiago_description/robots/tiago_no_hand.urdf"),
    "tiago_pro": CatalogEntry("tiago_pro_description/robots/tiago_pro.urdf"),
    "ur3": CatalogEntry("ur_description/urdf/ur3_robot.urdf", "tool0"),
    "ur3_gripper": CatalogEntry("ur_description/urdf/ur3_gripper.urdf", "tool0"),
    "ur3_limited": CatalogEntry(
        "ur_description/urdf/ur3_joint_limited_robot.urdf", "tool0"
    ),
    "ur5": CatalogEntry("ur_description/urdf/ur5_robot.urdf", "tool0"),
    "ur5_gripper": CatalogEntry("ur_description/urdf/ur5_gripper.urdf", "tool0"),
    "ur5_limited": CatalogEntry(
        "ur_description/urdf/ur5_joint_limited_robot.urdf", "tool0"
    ),
    "ur10": CatalogEntry("ur_description/urdf/ur10_robot.urdf", "tool0"),
    "ur10_limited": CatalogEntry(
        "ur_description/urdf/ur10_joint_limited_robot.urdf", "tool0"
    ),
    "xarm7": CatalogEntry("xarm_description/urdf/xarm7.urdf", "link_eef"),
    "z1": CatalogEntry(
        "z1_description/urdf/z1.urdf", "gripperStator", ("jointGripper",)
    ),
}


def get_own_urdf_dir() -> Path:
    """Folder of the project's own URDFs and DH tables.

    ``urdf/`` beside the package in a source checkout (editable install), or
    ``workbench/_urdf`` inside an installed wheel.
    """
    for candidate in (_PACKAGE_ROOT.parent / "urdf", _PACKAGE_ROOT / "_urdf"):
        if candidate.is_dir():
            return candidate
    raise URDFLoadError(
        "the workbench's urdf/ folder is missing from this installation"
    )


def get_example_robot_data_dir() -> Path:
    """The ``robots/`` folder of the installed example-robot-data package.

    Raises:
        URDFLoadError: If the package is not installed.
    """
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError as err:
        raise URDFLoadError(
            "example-robot-data is not installed (pip install example-robot-data)"
        ) from err
    path = Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))
    if not path.is_dir():
        raise URDFLoadError(f"example-robot-data has no robots/ folder at {path}")
    return path


def get_catalog_urdf(name: str) -> Path:
    """Absolute URDF path of a catalog robot (no check that the name exists)."""
    entry = CATALOG[name]
    base = get_own_urdf_dir() if entry.own else get_example_robot_data_dir()
    return base / entry.urdf
