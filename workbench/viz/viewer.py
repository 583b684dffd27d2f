"""Meshcat viewer of one robot: poses, animations, tool paths, triads and ghosts.

The scene lives in memory (no Meshcat server process): :meth:`Viewer.render_html`
gives a self-contained page that works offline, :meth:`Viewer.start_server`
serves it live on 127.0.0.1. Geometry is Pinocchio's: every visual geometry
object is drawn by ``pinocchio.visualize.MeshcatVisualizer`` and placed from
``pin.updateGeometryPlacements``.
"""

from __future__ import annotations

import html
import time
from pathlib import Path
from typing import TYPE_CHECKING

import meshcat
import meshcat.animation
import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.atomic_files import write_text_atomic
from workbench.collision import CollisionChecker
from workbench.errors import DimensionError, InputError, NonFiniteError
from workbench.model.robot import Robot
from workbench.poses import as_se3
from workbench.viz import _legend, _shapes
from workbench.viz._arm import (
    Arm,
    as_configurations,
    get_colorable_geometry,
    to_node_name,
)
from workbench.viz._camera import CameraView, frame_points
from workbench.viz._scene import SceneRecorder, render_page
from workbench.viz._server import LiveServer
from workbench.viz.singularity_gauge import SingularityGauge, _characteristic_length

if TYPE_CHECKING:
    from workbench.viz.collision_overlay import CollisionOverlay

FloatArray = npt.NDArray[np.float64]

#: Ghost colours (RGB in [0, 1]), one per IK branch, cycled.
GHOST_COLORS = (
    (0.12, 0.47, 0.71),
    (1.0, 0.5, 0.05),
    (0.17, 0.63, 0.17),
    (0.84, 0.15, 0.16),
    (0.58, 0.4, 0.74),
    (0.55, 0.34, 0.29),
    (0.89, 0.47, 0.76),
    (0.09, 0.75, 0.81),
)
TOOL_PATH_COLOR = (0.1, 0.2, 0.9)
PATH_START_COLOR = (0.1, 0.8, 0.2)
PATH_END_COLOR = (0.9, 0.1, 0.1)


def _translation(p: npt.ArrayLike) -> FloatArray:
    return pin.SE3(np.eye(3), np.asarray(p, dtype=np.float64)).homogeneous


class Viewer:
    """A Meshcat scene of one robot, as an offline page or served live.

    A script that serves must keep running for a browser to render anything:
    end it with :meth:`serve_forever` (or :meth:`wait_for_browser`).

    Args:
        robot: The robot to draw (its visual geometry, meshes resolved).
        q: Configuration shown first, shape (nq,) [rad]; default zeros clipped
            to the joint limits.
        color_by_singularity: Colour the moving links red (singular) to green
            (far), see :class:`~workbench.viz.SingularityGauge`.
        title: Page title.

    Raises:
        URDFLoadError: If a mesh is missing or cannot be drawn.
        DimensionError: If ``q`` has the wrong size.
    """

    def __init__(
        self,
        robot: Robot,
        q: npt.ArrayLike | None = None,
        *,
        color_by_singularity: bool = False,
        title: str | None = None,
    ):
        self.robot = robot
        self.title = title or f"workbench viewer: {robot.name}"
        self._recorder = SceneRecorder()
        self._scene = meshcat.Visualizer(window=self._recorder)
        self._arm = Arm(robot, self._scene, "robot")
        self._gauge = (
            SingularityGauge.from_robot(robot) if color_by_singularity else None
        )
        self._size = _characteristic_length(robot)
        self._frames: dict[str, int] = {}
        self._extra_points: dict[str, FloatArray] = {}
        self._motion: FloatArray | None = None
        self._camera: CameraView | None = None
        self._server: LiveServer | None = None
        self._legend: dict[str, str] = {}  # section -> HTML, drawn over the page
        if self._gauge is not None:
            self._legend["singularity"] = _legend.singularity_scale(self._gauge)
        self._overlay: CollisionOverlay | None = None
        self.q = np.clip(np.zeros(robot.nq), robot.lower, robot.upper)
        self.display(self.q if q is None else q)
        self._draw_floor()

    @property
    def gauge(self) -> SingularityGauge | None:
        """The singularity gauge colouring the arm, or None."""
        return self._gauge

    def _draw_floor(self) -> None:
        """Replace Meshcat's 20 m grid by one under the arm's reach, at its base."""
        floor = float(self._arm.compute_points(self.q, base_only=True)[:, 2].min())
        steps = np.array([0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0])
        step = float(steps[np.argmin(np.abs(np.log(steps / (self._size / 10.0))))])
        half = step * np.ceil(1.2 * self._size / step)
        self._scene["/Grid"].set_property("visible", False)
        _shapes.draw_floor_grid(self._scene["floor"], half, step, floor)
        self._arm.place(self.q)

    # -- what is drawn ----------------------------------------------------------

    def display(self, q: npt.ArrayLike) -> None:
        """Show the arm at ``q``, shape (nq,) [rad], with its frame triads.

        Raises:
            DimensionError: If ``q`` has the wrong size.
            NonFiniteError: If ``q`` has NaN or infinite entries.
        """
        q = self.robot.check_configuration(q)
        self.q = q.copy()
        self._arm.draw(self._scene, q)
        for name, frame_id in self._frames.items():
            self._scene[f"frames/{name}"].set_transform(
                self._arm.get_frame_pose(frame_id)
            )
        if self._gauge is not None:
            rgb = [float(c) for c in self._gauge.compute_color(q)]
            for node in self._arm.moving_nodes:
                self._scene[node].set_property("color", [*rgb, 1.0])
        if self._overlay is not None:
            colors, markers = self._overlay.compute_state(q)
            for node, rgb in colors.items():
                self._scene[node].set_property("color", [*rgb, 1.0])
            for node, pose in markers.items():
                self._scene[node].set_transform(pose)

    def show_frames(
        self, frames: list[str] | None = None, *, scale: float | None = None
    ) -> None:
        """Draw triads (x red, y green, z blue) that follow frames of the robot.

        Args:
            frames: Frame names; default the tool frame.
            scale: Axis length [m]; default a tenth of the arm's length.

        Raises:
            FrameNotFoundError: If a frame is not in the model.
        """
        for name in frames or [self.robot.tool_frame]:
            self._frames[name] = self.robot.get_frame_id(name)
            _shapes.draw_triad(self._scene[f"frames/{name}"], scale or 0.1 * self._size)
        self._legend["frames"] = _legend.triads("frame " + ", ".join(self._frames))
        self.display(self.q)

    def add_target(
        self, name: str, pose: pin.SE3 | npt.ArrayLike, *, scale: float | None = None
    ) -> None:
        """Draw a fixed triad at ``pose`` (``pin.SE3`` or 4×4, base frame, m).

        Raises:
            InputError: If ``pose`` is not a rigid transform.
        """
        pose = as_se3(pose)
        node = self._scene[f"targets/{to_node_name(name)}"]
        _shapes.draw_triad(node, scale or 0.12 * self._size, opacity=0.8)
        node.set_transform(pose.homogeneous)
        self._extra_points[f"target:{name}"] = pose.translation[None, :].copy()
        names = [key[7:] for key in self._extra_points if key.startswith("target:")]
        self._legend["targets"] = _legend.triads("targets " + ", ".join(names))

    def show_tool_path(
        self,
        q: npt.ArrayLike,
        *,
        name: str = "tool_path",
        color: npt.ArrayLike = TOOL_PATH_COLOR,
    ) -> FloatArray:
        """Draw the line the tool origin traces through configurations ``q``.

        Args:
            q: Configurations, shape (K, nq) [rad].
            name: Scene node name (another name adds another path).
            color: RGB in [0, 1] of the line. The legend's tool-path entry
                is for :data:`TOOL_PATH_COLOR`; a line of another colour gets
                none (add one with :meth:`add_legend`).

        Returns:
            The tool positions, shape (K, 3) [m], base frame.
        """
        q = as_configurations(self.robot, q, "q")
        rgb = tuple(float(c) for c in np.asarray(color, dtype=np.float64))
        points = np.array([self.robot.fk(qk).translation for qk in q])
        node = self._scene[to_node_name(name)]
        _shapes.draw_polyline(node["line"], points, rgb)
        radius = 0.012 * self._size
        _shapes.draw_marker(node["start"], radius, PATH_START_COLOR)
        node["start"].set_transform(_translation(points[0]))
        _shapes.draw_marker(node["end"], radius, PATH_END_COLOR)
        node["end"].set_transform(_translation(points[-1]))
        if rgb == tuple(TOOL_PATH_COLOR):
            self._legend["tool_path"] = _legend.tool_path(
                TOOL_PATH_COLOR, PATH_START_COLOR, PATH_END_COLOR
            )
        self._extra_points[f"path:{name}"] = points
        return points

    def show_ghosts(
        self,
        configurations: npt.ArrayLike,
        *,
        labels: list[str] | None = None,
        opacity: float = 0.3,
        colors: npt.ArrayLike | None = None,
        legend: str | None = None,
        collision: bool = False,
    ) -> None:
        """Draw translucent copies of the arm, e.g. every IK branch of one pose.

        Replaces earlier ghosts. Each is a node ``ghosts/<label>`` that the
        page's control panel can hide. An arm whose visual meshes are Collada
        files (they keep their own colours) gets ghosts of its collision
        geometry, which take the ghost's colour.

        Args:
            configurations: Shape (M, nq) [rad], e.g. the ``q`` of each
                solution of ``ik.analytic(robot, pose)``.
            labels: One name per ghost (e.g. the IK branch); default
                ``ghost0``, ``ghost1``, ….
            opacity: In (0, 1].
            colors: RGB in [0, 1] per ghost, shape (M, 3) (e.g. a colour
                scale of a value); default :data:`GHOST_COLORS`, cycled.
            legend: HTML of the legend's ghost section (e.g. the colour
                scale); default one row per label.
            collision: Draw them with the collision geometry (what a
                collision check sees, and far lighter in the page than
                detailed visual meshes) rather than the visual one.

        Raises:
            DimensionError: If the configurations are not (M, nq), or the
                colours not (M, 3).
            InputError: If the labels do not match them one to one.
        """
        qs = as_configurations(self.robot, configurations, "configurations")
        labels = labels or [f"ghost{i}" for i in range(len(qs))]
        if len(labels) != len(qs):
            raise InputError(f"{len(labels)} labels for {len(qs)} ghost configurations")
        if colors is None:
            rgb = np.array(
                [GHOST_COLORS[i % len(GHOST_COLORS)] for i in range(len(qs))]
            )
        else:
            rgb = np.clip(np.asarray(colors, dtype=np.float64), 0.0, 1.0)
            if rgb.shape != (len(qs), 3):
                raise DimensionError("colors", (len(qs), 3), rgb.shape)
        self._scene["ghosts"].delete()
        if collision and self.robot.collision_model.ngeoms:
            geometry, visual = self.robot.collision_model, False
        else:
            geometry, visual = get_colorable_geometry(self.robot)
        points = [np.zeros((0, 3))]
        for i, (qk, label) in enumerate(zip(qs, labels, strict=True)):
            rgba = [*(float(c) for c in rgb[i]), float(opacity)]
            root = f"ghosts/{to_node_name(label)}"
            ghost = Arm(
                self.robot,
                self._scene,
                root,
                rgba,
                with_base=False,
                geometry_model=geometry,
            )
            ghost.draw(self._scene, qk)
            points.append(ghost.compute_points(qk))
        self._extra_points["ghosts"] = np.vstack(points)
        entry = legend or _legend.ghosts(labels, rgb.tolist())
        if not visual:
            entry += (
                "<div>ghosts drawn with the collision geometry</div>"
                if collision
                else "<div>ghosts drawn with the collision geometry (the visual "
                "meshes keep their own colours)</div>"
            )
        self._legend["ghosts"] = entry

    def show_collisions(self, checker: CollisionChecker) -> None:
        """Draw the checker's scene; colour contacts and the closest pair from now on.

        Links and obstacles in contact turn red and the closest pair orange
        (instead of the singularity colours), with two markers on the closest
        points (see :class:`~workbench.viz.collision_overlay.CollisionOverlay`).

        Args:
            checker: A :class:`~workbench.collision.CollisionChecker` of this
                viewer's robot.
        """
        from workbench.viz.collision_overlay import CollisionOverlay

        self._overlay = CollisionOverlay(self._scene, self._arm, checker)
        self._gauge = None
        self._legend.pop("singularity", None)  # the links now show contacts
        self._legend["collisions"] = _legend.collisions(
            [o.name for o in checker.scene.obstacles]
        )
        self.display(self.q)
        corners = [o.placement.translation for o in checker.scene.obstacles]
        if corners:
            self._extra_points["scene"] = np.array(corners)

    def show_points(
        self, name: str, points: npt.ArrayLike, rgb: npt.ArrayLike, *, size: float
    ) -> None:
        """Draw a cloud of coloured points, e.g. the voxels of a workspace map.

        The points are unlit squares facing the camera, ``size`` wide [m] at
        their own depth, so they show their colours exactly.

        Args:
            name: Scene node (``/`` separates nodes; the control panel can
                hide each node and everything under it).
            points: Shape (N, 3) [m], base frame.
            rgb: Colours, shape (N, 3), in [0, 1].
            size: Width of each point [m].

        Raises:
            DimensionError: If the shapes do not match.
            NonFiniteError: If a point is NaN or infinite.
        """
        xyz = np.asarray(points, dtype=np.float64)
        colors = np.asarray(rgb, dtype=np.float64)
        if xyz.ndim != 2 or xyz.shape[1] != 3:
            raise DimensionError(
                "points", (xyz.shape[0] if xyz.ndim else 1, 3), xyz.shape
            )
        if colors.shape != xyz.shape:
            raise DimensionError("rgb", xyz.shape, colors.shape)
        if not np.all(np.isfinite(xyz)):
            raise NonFiniteError(f"points of {name} contain NaN or infinite values")
        _shapes.draw_points(self._scene[name], xyz, colors, size)
        if len(xyz):
            self._extra_points[f"points:{name}"] = xyz.copy()

    def add_legend(self, section: str, entry: str) -> None:
        """Add (or replace) a section of the legend drawn over the page.

        Args:
            section: Key of the section (a later call with it replaces it).
            entry: HTML fragment, e.g. from ``workbench.viz._legend``.
        """
        self._legend[section] = entry

    def set_visible(self, name: str, visible: bool) -> None:
        """Show or hide a part of the scene (a node and everything under it).

        Args:
            name: Node name, e.g. ``"robot"``, ``"ghosts"``, ``"frames"``,
                ``"targets"``, ``"tool_path"``, ``"floor"``.
            visible: Whether to draw it.
        """
        self._scene[name].set_property("visible", bool(visible))

    def play_trajectory(
        self,
        t: npt.ArrayLike,
        q: npt.ArrayLike,
        *,
        trace_tool: bool = True,
        max_frame_rate: float = 30.0,
        repetitions: int = 1,
    ) -> None:
        """Animate a joint trajectory (play, pause and scrub in the page).

        Every geometry object gets one key per kept sample, placed by
        Pinocchio; with ``color_by_singularity`` the links' colour is animated
        too (primitive, STL and OBJ geometry; Collada meshes keep theirs).

        Args:
            t: Times, shape (K,) [s], strictly increasing.
            q: Configurations, shape (K, nq) [rad].
            trace_tool: Also draw the tool path (:meth:`show_tool_path`).
            max_frame_rate: Keep at most about this many samples per second [Hz].
            repetitions: How many times the animation plays.

        Raises:
            DimensionError: If the shapes do not match.
            InputError: If ``t`` is not finite and strictly increasing.
        """
        q = as_configurations(self.robot, q, "q")
        t = np.asarray(t, dtype=np.float64)
        if t.shape != (q.shape[0],):
            raise DimensionError("t", (q.shape[0],), t.shape)
        if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0.0):
            raise InputError("t must be finite and strictly increasing")
        _, keep = np.unique(np.floor((t - t[0]) * max_frame_rate), return_index=True)
        keep = np.union1d(keep, [len(t) - 1])
        animation = meshcat.animation.Animation(default_framerate=1)  # keys in s
        for k in keep:
            frame = animation.at_frame(self._scene, float(t[k] - t[0]))
            for node, pose in zip(self._arm.nodes, self._arm.place(q[k]), strict=True):
                frame[node].set_transform(pose)
            for name, frame_id in self._frames.items():
                frame[f"frames/{name}"].set_transform(
                    self._arm.get_frame_pose(frame_id)
                )
            if self._gauge is not None:
                rgb = [float(c) for c in self._gauge.compute_color(q[k])]
                for node in self._arm.keyed_color_nodes:
                    frame[f"{node}/<object>"].set_property(
                        "material.color", "color", rgb
                    )
            if self._overlay is not None:
                colors, markers = self._overlay.compute_state(q[k])
                for node, rgb in colors.items():
                    frame[f"{node}/<object>"].set_property(
                        "material.color", "color", rgb
                    )
                for node, pose in markers.items():
                    frame[node].set_transform(pose)
        self.display(q[0])
        self._scene.set_animation(animation, play=True, repetitions=repetitions)
        self._motion = q[keep[:: max(1, len(keep) // 40)]]
        if trace_tool:
            self.show_tool_path(q)

    # -- camera and pages -------------------------------------------------------

    def set_camera(
        self, position: npt.ArrayLike, target: npt.ArrayLike, *, fov_deg: float = 45.0
    ) -> None:
        """Fix the page's initial camera (base frame, m); default: frame the scene."""
        p = np.asarray(position, dtype=np.float64)
        c = np.asarray(target, dtype=np.float64)
        if p.shape != (3,) or c.shape != (3,):
            raise DimensionError("camera position and target", (3,), (p.size, c.size))
        self._camera = CameraView(tuple(p.tolist()), tuple(c.tolist()), fov_deg)

    def get_camera(self) -> CameraView:
        """The page's initial camera: the one set, else one framing everything shown."""
        if self._camera is not None:
            return self._camera
        clouds = [self._arm.compute_points(self.q), *self._extra_points.values()]
        if self._motion is not None:
            clouds += [self._arm.compute_points(qk) for qk in self._motion]
        self._arm.place(self.q)
        return frame_points(np.vstack(clouds))

    def render_html(self, *, legend: bool = True) -> str:
        """Self-contained HTML page of the scene (works offline, about 1 MB).

        Args:
            legend: Draw the title and the legend (what the arm's colours, the
                path markers, triads and ghosts mean) over the scene.
        """
        commands = self._recorder.get_commands()
        return render_page(
            commands,
            camera=self.get_camera(),
            title=self.title,
            overlay=self._render_legend() if legend else "",
        )

    def _render_legend(self) -> str:
        return _legend.render_overlay(self.title, self._legend.values())

    def save_html(self, path: str | Path) -> Path:
        """Write :meth:`render_html` to ``path``; returns it.

        Raises:
            InputError: If the file cannot be written.
        """
        return write_text_atomic(path, self.render_html())

    def render_inline(self, *, height: int = 480) -> str:
        """HTML for a notebook cell: the offline page in an ``iframe``."""
        page = html.escape(self.render_html(), quote=True)
        box = f"height: {int(height)}px; width: 100%; resize: both; overflow: hidden"
        frame = "width: 100%; height: 100%; border: none"
        inner = f'<iframe srcdoc="{page}" style="{frame}"></iframe>'
        return f'<div style="{box}">{inner}</div>'

    def _repr_html_(self) -> str:
        return self.render_inline()

    # -- live server ------------------------------------------------------------

    def start_server(self, *, port: int = 0) -> str:
        """Serve the scene live at ``http://127.0.0.1:PORT/``; returns the URL.

        Returns at once: the server runs in a daemon thread and pushes later
        changes to open pages. Binds the loopback interface only.

        Raises:
            InputError: If the port cannot be bound.
        """
        if self._server is None:
            server = LiveServer(self._recorder, self._render_live, port=port)
            server.start()
            self._server = server
        return self._server.url

    def _render_live(self) -> str:
        return render_page(
            [],
            camera=self.get_camera(),
            title=self.title,
            live=True,
            overlay=self._render_legend(),
        )

    def wait_for_browser(self, timeout: float | None = None) -> bool:
        """Block until a page has loaded the scene; False on timeout.

        Raises:
            InputError: If the viewer is not being served.
        """
        if self._server is None:
            raise InputError("the viewer is not served: call start_server() first")
        return self._server.wait_for_client(timeout)

    def serve_forever(self, *, port: int = 0) -> None:
        """Serve (starting if needed) until interrupted (Ctrl-C), then stop."""
        self.start_server(port=port)
        try:
            while True:
                time.sleep(0.5)
        finally:
            self.stop_server()

    def stop_server(self) -> None:
        """Stop the live server, if any (idempotent)."""
        if self._server is not None:
            self._server.stop()
            self._server = None
