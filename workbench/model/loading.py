"""``load_robot``: a Robot from a catalog name, a URDF or a xacro file."""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path

import pinocchio as pin

from workbench.errors import JointNotFoundError, RobotNotFoundError, URDFLoadError
from workbench.model.catalog import CATALOG, get_catalog_urdf
from workbench.model.dh import DHTable
from workbench.model.packages import (
    get_package_lookup,
    resolve_mesh_uris,
    split_package_dir,
)
from workbench.model.robot import Robot
from workbench.model.srdf_files import find_srdf, read_disabled_collisions
from workbench.model.urdf_joints import (
    MimicJoint,
    apply_mimic_joints,
    parse_urdf_joints,
)
from workbench.model.xacro_files import expand_xacro, is_xacro


def get_robot_names() -> list[str]:
    """Every name :func:`load_robot` accepts besides a path, sorted."""
    return sorted(CATALOG)


def load_robot(
    name: str | Path,
    *,
    tool_frame: str | None = None,
    package_dirs: Sequence[str | Path] = (),
    xacro_args: Mapping[str, str] | None = None,
    srdf: str | Path | None = None,
) -> Robot:
    r"""Load a robot by catalog name or from a URDF or xacro file.

    The URDF's joints are checked (zero-length axis, lower limit above the
    upper one: refused) and its ``<mimic>`` joints honoured: a mimicking joint
    has no coordinate of its own and follows its leader in FK and Jacobians
    (:attr:`Robot.mimic_joints`). Every mesh URI is resolved here
    (:mod:`workbench.model.packages`): a missing mesh is an error now, not
    when the geometry is first drawn or checked.

    Args:
        name: ``"puma560"``, ``"puma560-kang"``, an example-robot-data name
            (``"ur5"``, ``"panda"``, …; see :func:`get_robot_names`), or a path
            to a ``.urdf`` file or a ``.xacro`` file (expanded by the ROS
            ``xacro`` package, :mod:`workbench.model.xacro_files`).
        tool_frame: Tool frame name. Default: the catalog's tool frame, else
            the last frame of the model.
        package_dirs: Folders that hold ROS packages (at any depth, found by
            the ``<name>`` of their ``package.xml`` or by folder name), or a
            package's own folder, or ``"NAME=DIR"`` for one package; searched
            for ``package://PKG/...`` and ``$(find PKG)`` before the folders
            of ``ROS_PACKAGE_PATH`` and the file's own folders.
        xacro_args: Values of a xacro file's ``<xacro:arg>``\ s.
        srdf: An SRDF whose ``<disable_collisions>`` pairs the self-collision
            check leaves out (instead of the pairs it computes,
            :mod:`workbench.collision.self_filter`). Default: the SRDF beside
            a URDF or xacro file given by path (``arm.srdf`` beside
            ``arm.urdf``), if there is one; none for a catalog name.

    Returns:
        The robot, base fixed (no free flyer).

    Raises:
        RobotNotFoundError: If ``name`` is neither a catalog name nor a path
            to an existing file; the message lists the valid names.
        URDFLoadError: If the URDF is unreadable or malformed, has a joint
            with a zero axis or inverted limits, or a mimic joint Pinocchio
            cannot represent (the message names the joints and values); if
            xacro refuses the file; if the SRDF cannot be read; if a mesh is not found
            (:class:`~workbench.model.packages.MeshNotFoundError`: the
            message names the URI, where it looked and ``--package-dir``);
            if ``xacro_args`` are given for a file that is no xacro.
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
        if not (path.suffix.lower() == ".urdf" or is_xacro(path) or path.exists()):
            raise RobotNotFoundError(key, get_robot_names())
        if not path.is_file():
            kind = "xacro" if is_xacro(path) else "URDF"
            raise URDFLoadError(f"{kind} file not found: {path}")
        locked = ()
    lookup = get_package_lookup(path, package_dirs)
    if is_xacro(path):
        text = expand_xacro(path, lookup, xacro_args)
    elif xacro_args:
        raise URDFLoadError(
            f"{path}: xacro arguments given for a file that is no xacro"
        )
    else:
        text = _read_text(path)
    model, mimics = _build_model(text, path)
    if locked:
        model = _lock_joints(model, locked)
    model = apply_mimic_joints(model, mimics, path)
    if tool_frame is None:
        tool_frame = model.frames[len(model.frames) - 1].name
    srdf_path = _srdf_path(srdf, None if entry is not None else path)
    return Robot(
        key,
        model,
        path,
        tool_frame,
        package_dirs=_absolute(package_dirs),
        dh_table=dh_table,
        description=resolve_mesh_uris(text, lookup),
        xacro_args=tuple((xacro_args or {}).items()),
        srdf_path=srdf_path,
        disabled_collisions=(
            () if srdf_path is None else read_disabled_collisions(srdf_path)
        ),
    )


def _srdf_path(srdf: str | Path | None, description: Path | None) -> Path | None:
    """The SRDF given (absolute), else the one beside ``description``."""
    if srdf is not None:
        path = Path(srdf).expanduser()
        if not path.is_file():
            raise URDFLoadError(f"SRDF file not found: {path}")
        return path.resolve()
    found = None if description is None else find_srdf(description)
    return None if found is None else found.resolve()


def _absolute(package_dirs: Sequence[str | Path]) -> tuple[str, ...]:
    """The given package folders (and ``NAME=DIR`` entries), absolute."""
    out = []
    for entry in package_dirs:
        name, folder = split_package_dir(entry)
        path = str(Path(folder).expanduser().resolve())
        out.append(path if name is None else f"{name}={path}")
    return tuple(out)


def _read_text(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise URDFLoadError(f"cannot read URDF {path}: {err}") from err


def _build_model(text: str, path: Path) -> tuple[pin.Model, list[MimicJoint]]:
    """The kinematic model of the URDF ``text`` (read from ``path``)."""
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
