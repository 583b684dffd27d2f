"""A workspace map in Meshcat: coloured voxels in layers, a slice slider, the arm.

Every voxel with a value is a point of the colour of its reachability (fraction
of the map's orientations reached with a usable branch) or of its best
dexterity (Yoshikawa manipulability of the best branch over the orientations,
m³), on matplotlib's viridis scale (perceptually uniform); voxels that no
orientation reaches are not drawn. Each z layer is its own scene node,
``voxels/z+0.350`` (z of the layer's voxel centres in metres), so Meshcat's
control panel ("Open Controls" → Scene → meshcat → voxels) shows or hides layers one by
one. A slider in the legend box cuts the map from above: it shows the layers up
to a height, or, with "only this layer", that layer alone; "cut away y > 0"
hides the half of every layer in front of the base axis (nodes
``voxels/<layer>/y>0``), so the inside of the map and the arm show. The arm
stands in a reference configuration, in its own colours; a map built with a
scene shows its obstacles too (contacts of the arm in red, as in
:meth:`~workbench.viz.Viewer.show_collisions`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, ClassVar, Literal

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError, RobotNotFoundError
from workbench.model.robot import Robot
from workbench.viz import _legend
from workbench.viz.viewer import Viewer

if TYPE_CHECKING:
    from workbench.workspace.store import WorkspaceMap

FloatArray = npt.NDArray[np.float64]
Measure = Literal["reachability", "dexterity"]

#: Measures the page can colour by.
MEASURES: tuple[str, ...] = ("reachability", "dexterity")
#: Colour map of the voxels (perceptually uniform).
COLOR_MAP = "viridis"
#: Width of a voxel's point on screen, as a fraction of the voxel spacing there.
POINT_FILL = 0.55
#: Colour stops written into the legend's ramp.
RAMP_STOPS = 11


class _Scale:
    """What the page colours by: array name, colour scale, legend words."""

    ARRAYS: ClassVar[dict[str, str]] = {
        "reachability": "reachability",
        "dexterity": "dexterity_best",
    }

    def __init__(self, measure: str, values: FloatArray):
        self.measure = measure
        if measure == "reachability":
            self.shown = np.isfinite(values) & (values > 0.0)
            self.vmax = 1.0
            self.what = "fraction of the orientations reached [1]"
            self.ticks = [(x, f"{x:g}") for x in (0.0, 0.25, 0.5, 0.75, 1.0)]
        else:
            self.shown = np.isfinite(values)
            from matplotlib.ticker import MaxNLocator

            top = float(values[self.shown].max()) if self.shown.any() else 0.0
            top = top if top > 0.0 else 1.0
            # The scale ends on the first round tick at or above the largest value.
            steps = MaxNLocator(5, steps=[1, 2, 2.5, 5, 10]).tick_values(0.0, top)
            self.vmax = float(steps[int(np.searchsorted(steps, top))])
            self.what = "best manipulability √det(J Jᵀ) over the orientations [m³]"
            self.ticks = [
                (float(t / self.vmax), f"{t:g}") for t in steps if t <= self.vmax
            ]

    def colors(self, values: FloatArray) -> FloatArray:
        """RGB in [0, 1] of ``values`` (N,), shape (N, 3)."""
        from matplotlib import colormaps

        cmap = colormaps[COLOR_MAP]
        return np.asarray(cmap(np.clip(values / self.vmax, 0.0, 1.0)))[:, :3]

    def legend(self) -> str:
        from matplotlib import colormaps

        cmap = colormaps[COLOR_MAP]
        stops = [
            (x, tuple(float(c) for c in cmap(x)[:3]))
            for x in np.linspace(0.0, 1.0, RAMP_STOPS)
        ]
        title = f"Voxel colour: {self.measure}"
        return _legend.color_scale(title, self.what, stops, self.ticks)


def _layer_name(z: float) -> str:
    """``z+0.350``: the layer's height [m] to the millimetre (never ``z-0.000``)."""
    return f"z{round(z, 3) + 0.0:+.3f}"


def _slice_controls(layers: list[str], heights: list[float], cut_away: bool) -> str:
    """The slider, its two check boxes and the script that sets node visibility."""
    top = len(layers) - 1
    data = json.dumps({"layers": layers, "heights": heights})
    checked = " checked" if cut_away else ""
    return f"""<div class="wb-slice" style="pointer-events: auto; margin-top: 6px">
<b>Slice</b>: layers up to z = <span id="wb-slice-z">{heights[top]:+.3f}</span> m
<input id="wb-slice" type="range" min="0" max="{top}" step="1" value="{top}"
 style="width: 100%; margin: 4px 0">
<label><input id="wb-slice-only" type="checkbox"> only this layer</label>
<label style="margin-left: 10px"><input id="wb-slice-cut" type="checkbox"{checked}>
cut away y &gt; 0</label></div>
<script>
(function (data) {{
  var slider = document.getElementById("wb-slice");
  var only = document.getElementById("wb-slice-only");
  var cut = document.getElementById("wb-slice-cut");
  var label = document.getElementById("wb-slice-z");
  function update() {{
    var k = Number(slider.value);
    var z = Math.round(1000 * data.heights[k]) / 1000 + 0;  /* no "-0.000" */
    label.textContent = (z >= 0 ? "+" : "") + z.toFixed(3);
    data.layers.forEach(function (name, i) {{
      var node = ["meshcat", "voxels", name];
      viewer.set_property(node, "visible", only.checked ? i === k : i <= k);
      viewer.set_property(node.concat(["y>0"]), "visible", !cut.checked);
    }});
    viewer.set_dirty();  /* Meshcat redraws only when told */
  }}
  slider.addEventListener("input", update);
  only.addEventListener("change", update);
  cut.addEventListener("change", update);
}})({data});
</script>"""


def _voxel_counts(scale: _Scale, total: int) -> str:
    shown = int(scale.shown.sum())
    return (
        f"<div>{shown} of {total} voxels drawn; the others are reached in no "
        "orientation.</div>"
    )


def get_map_robot(workspace_map: WorkspaceMap, robot: Robot | None = None) -> Robot:
    """The robot a map was built for, checked against the map's URDF digest.

    Args:
        workspace_map: A :class:`~workbench.workspace.WorkspaceMap`.
        robot: The robot, when its name is no catalog name (a URDF file);
            default loaded from the map's ``robot`` and ``tool_frame``.

    Raises:
        InputError: If the map's robot is no catalog name and no robot is
            given, or the robot's URDF is not the one the map was built from
            (another SHA-256).
    """
    from workbench.model.loading import load_robot
    from workbench.workspace.robot_spec import compute_file_sha256

    attrs = workspace_map.attrs
    name = str(attrs.get("robot"))
    if robot is None:
        try:
            robot = load_robot(name, tool_frame=attrs.get("tool_frame"))
        except RobotNotFoundError as err:
            raise InputError(
                f"the map's robot {name!r} is no catalog name: give its URDF "
                "(robot=..., --robot FILE.urdf)"
            ) from err
    expected = attrs.get("urdf_sha256")
    if expected is not None and compute_file_sha256(robot.urdf_path) != expected:
        raise InputError(
            f"{robot.urdf_path} is not the URDF the map was built from "
            f"(sha256 {str(expected)[:12]}…)"
        )
    return robot


def make_workspace_viewer(
    workspace_map: WorkspaceMap,
    *,
    measure: Measure = "reachability",
    robot: Robot | None = None,
    q: npt.ArrayLike | None = None,
    cut_away: bool = True,
    title: str | None = None,
) -> Viewer:
    """A :class:`~workbench.viz.Viewer` of the map's voxels, layers and arm.

    Args:
        workspace_map: A :class:`~workbench.workspace.WorkspaceMap`
            (``open_map(path)``).
        measure: ``"reachability"`` (per voxel: fraction of orientations
            reached, [1]) or ``"dexterity"`` (per voxel: best manipulability
            over the orientations, [m³]).
        robot: The map's robot; default loaded from the map's ``robot`` and
            ``tool_frame`` attributes (:func:`get_map_robot`).
        q: The arm's reference configuration, shape (nq,) [rad]; default
            zeros clipped to the joint limits.
        cut_away: Start with the voxels at y > 0 hidden (the page's "cut away
            y > 0" box), so the section through the base axis and the arm show.
        title: Page title; default names the robot, measure and grid.

    Returns:
        The viewer: :meth:`~workbench.viz.Viewer.save_html` writes the page,
        :meth:`~workbench.viz.Viewer.start_server` serves it.

    Raises:
        InputError: If ``measure`` is not one of :data:`MEASURES`.
        InputError: If the map's robot cannot be loaded or is not the one
            the map was built for.
        DimensionError: If ``q`` has the wrong size.
    """
    if measure not in MEASURES:
        raise InputError(
            f"unknown measure {measure!r}; choose one of {', '.join(MEASURES)}"
        )
    robot = get_map_robot(workspace_map, robot)
    grid = workspace_map.grid
    values = np.asarray(workspace_map[_Scale.ARRAYS[measure]], dtype=np.float64)
    scale = _Scale(measure, values)
    resolution = float(grid.resolution)
    default_title = (
        f"{robot.name}: workspace {measure}, {resolution * 100:g} cm voxels, "
        f"{len(grid.orientations)} orientations"
    )
    viewer = Viewer(robot, q, title=title or default_title)
    scene = workspace_map.attrs.get("scene")
    if scene:  # the obstacles the map's branches had to miss
        from workbench.collision import CollisionChecker, parse_scene

        checker = CollisionChecker(robot, parse_scene(scene, source="the map's scene"))
        viewer.show_collisions(checker)
    positions = np.asarray(grid.positions, dtype=np.float64)
    # On screen, three.js draws a point of size s at depth d s·H/(2d) pixels wide
    # (H: view height), and voxels res·H/(2d·tan(fov/2)) pixels apart.
    fov = np.radians(viewer.get_camera().fov_deg)
    point_size = POINT_FILL * resolution / np.tan(fov / 2.0)
    # The cut keeps the voxel layer through the base axis (centres at y = 0).
    in_front = positions[:, 1] > 0.5 * resolution
    nz = int(grid.shape[2])
    iz = np.arange(positions.shape[0]) % nz
    layers: list[str] = []
    heights: list[float] = []
    for k in range(nz):
        chosen = scale.shown & (iz == k)
        if not chosen.any():
            continue
        z = float(positions[chosen, 2][0])
        name = _layer_name(z)
        for half, side in (
            ("y<=0", ~in_front),
            ("y>0", in_front),
        ):
            part = chosen & side
            if not part.any():
                continue
            viewer.show_points(
                f"voxels/{name}/{half}",
                positions[part],
                scale.colors(values[part]),
                size=point_size,
            )
            if half == "y>0":
                viewer.set_visible(f"voxels/{name}/{half}", not cut_away)
        layers.append(name)
        heights.append(z)
    entries = [scale.legend(), _voxel_counts(scale, positions.shape[0])]
    if layers:
        entries.append(_slice_controls(layers, heights, cut_away))
    else:
        entries.append("<div>No voxel is reached: nothing to slice.</div>")
    viewer.add_legend("workspace", "".join(entries))
    return viewer


def write_workspace_view(
    workspace_map: WorkspaceMap,
    path: str | Path,
    *,
    measure: Measure = "reachability",
    robot: Robot | None = None,
    q: npt.ArrayLike | None = None,
    cut_away: bool = True,
    title: str | None = None,
) -> Path:
    """Write the self-contained page of :func:`make_workspace_viewer` (offline).

    Args:
        workspace_map: A :class:`~workbench.workspace.WorkspaceMap`.
        path: Output file (``.html``), written whole or not at all.
        measure: ``"reachability"`` or ``"dexterity"``.
        robot: The map's robot; default loaded from the map's attributes.
        q: Reference configuration of the arm, shape (nq,) [rad].
        cut_away: Start with the voxels at y > 0 hidden.
        title: Page title.

    Returns:
        ``path`` as a Path.

    Raises:
        InputError: If ``measure`` is unknown or the file cannot be written.
    """
    viewer = make_workspace_viewer(
        workspace_map, measure=measure, robot=robot, q=q, cut_away=cut_away, title=title
    )
    return viewer.save_html(path)


__all__ = [
    "COLOR_MAP",
    "MEASURES",
    "get_map_robot",
    "make_workspace_viewer",
    "write_workspace_view",
]
