"""``load_robot``: a Robot from a catalog name or a URDF path."""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path

import pinocchio as pin

from workbench.errors import JointNotFoundError, RobotNotFoundError, URDFLoadError
from workbench.model.catalog import CATALOG, get_catalog_urdf
from workbench.model.dh import DHTable
from workbench.model.robot import Robot
from workbench.model.urdf_joints import (
    MimicJoint,
    apply_mimic_joints,
    parse_urdf_joints,
)

_ROS_PACKAGE_PATH = (
    "ROS_PACKAGE_PATH"  # folders holding ROS packages, os.pathsep-separated
)


def get_robot_names() -> list[str]:
    """Every name :func:`load_robot` accepts besides a path, sorted."""
    return sorted(CATALOG)


def load_robot(
    name: str | Path,
    *,
    tool_frame: str | None = None,
    package_dirs: Sequence[str | Path] = (),
) -> Robot:
    """Load a robot by catalog name or from a URDF file.

    The URDF's joints are checked (zero-length axis, lower limit above the
    upper one: refused) and its ``<mimic>`` joints honoured: a mimicking joint
    has no coordinate of its own and follows its leader in FK and Jacobians
    (:attr:`Robot.mimic_joints`).

    Args:
        name: ``"puma560"``, ``"puma560-kang"``, an example-robot-data name
            (``"ur5"``, ``"panda"``, …; see :func:`get_robot_names`), or a path
            to a ``.urdf`` file.
        tool_frame: Tool frame name. Default: the catalog's tool frame, else
            the last frame of the model.
        package_dirs: Folders that hold ROS packages, searched first for a
            ``package://PKG/...`` mesh URI (as ``DIR/PKG/...``); a package's
            own folder may be given too. Then come the folders of the
            ``ROS_PACKAGE_PATH`` environment variable, then the URDF's folder
            and each of its parents.

    Returns:
        The robot, base fixed (no free flyer).

    Raises:
        RobotNotFoundError: If ``name`` is neither a catalog name nor a path
            to an existing file; the message lists the valid names.
        URDFLoadError: If the URDF is unreadable or malformed, has a joint
            with a zero axis or inverted limits, or a mimic joint Pinocchio
            cannot represent (the message names the joints and values).
        FrameNotFoundError: If ``tool_frame`` is not in the model.
    """
    key = str(name)
    entry = CATALOG.get(key)
    dh_table = None
    if entry is not None:
        path = get_catalog_urdf(key)
        locked = entry.locked_joints
        tool_frame = tool_frame or entry.tool_frame
        if entry.own:
            dh_table = DHTable.from_json(path.with_name(f"{key}.dh.json"))
    else:
        path = Path(key).expanduser()
        if not (path.suffix.lower() == ".urdf" or path.exists()):
            raise RobotNotFoundError(key, get_robot_names())
        if not path.is_file():
            raise URDFLoadError(f"URDF file not found: {path}")
        locked = ()
    model, mimics = _build_model(path)
    if locked:
        model = _lock_joints(model, locked)
    model = apply_mimic_joints(model, mimics, path)
    if tool_frame is None:
        tool_frame = model.frames[len(model.frames) - 1].name
    return Robot(
        key,
        model,
        path,
        tool_frame,
        package_dirs=_get_package_dirs(path, package_dirs),
        dh_table=dh_table,
    )


def _get_package_dirs(urdf: Path, given: Sequence[str | Path] = ()) -> list[str]:
    """Folders searched for ``package://`` URIs, in order, without repeats.

    Each folder of ``given`` (and its parent, so that a package's own folder
    works too), then each of ``ROS_PACKAGE_PATH`` (likewise), then the URDF's
    folder and its parents.

    Raises:
        URDFLoadError: If a folder of ``given`` does not exist.
    """
    found: list[Path] = []
    for folder in given:
        folder = Path(folder).expanduser()
        if not folder.is_dir():
            raise URDFLoadError(f"package folder not found: {folder}")
        found += [folder.resolve(), folder.resolve().parent]
    for entry in os.environ.get(_ROS_PACKAGE_PATH, "").split(os.pathsep):
        if entry and Path(entry).is_dir():
            found += [Path(entry).resolve(), Path(entry).resolve().parent]
    found += [urdf.resolve().parent, *urdf.resolve().parents]
    return [str(p) for p in dict.fromkeys(found)]


def _build_model(path: Path) -> tuple[pin.Model, list[MimicJoint]]:
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise URDFLoadError(f"cannot read URDF {path}: {err}") from err
    if "<robot" not in text:
        raise URDFLoadError(f"{path}: not a URDF (no <robot> element)")
    try:
        with _stderr_captured() as captured:
            model = pin.buildModelFromXML(text)
    except (ValueError, RuntimeError) as err:
        details = [
            line.strip() for line in captured if line.strip().startswith("Error:")
        ]
        reason = details[0].removeprefix("Error:").strip() if details else str(err)
        raise URDFLoadError(f"{path}: malformed URDF: {reason}") from err
    if model.nq == 0:
        raise URDFLoadError(f"{path}: the URDF has no moving joint")
    return model, parse_urdf_joints(text, path)


@contextlib.contextmanager
def _stderr_captured() -> Iterator[list[str]]:
    """Capture what C++ code writes to file descriptor 2 (urdfdom's messages).

    Yields a list that holds the captured lines once the block has ended,
    whether it ended normally or with an exception.
    """
    lines: list[str] = []
    with tempfile.TemporaryFile(mode="w+b") as sink:
        saved = os.dup(2)
        os.dup2(sink.fileno(), 2)
        try:
            yield lines
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            lines.extend(sink.read().decode(errors="replace").splitlines())


def _lock_joints(model: pin.Model, names: tuple[str, ...]) -> pin.Model:
    ids = []
    for joint in names:
        if not model.existJointName(joint):
            raise JointNotFoundError(joint, list(model.names)[1:])
        ids.append(model.getJointId(joint))
    return pin.buildReducedModel(model, ids, pin.neutral(model))


__all__ = ["get_robot_names", "load_robot"]
