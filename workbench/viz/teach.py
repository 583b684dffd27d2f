"""Teach panel for notebooks: joint sliders driving the 3D view, with a readout.

Needs ``ipywidgets``. The panel builds without a display (a headless notebook
run only creates the widgets). The view is the viewer's live server shown in
an ``iframe`` (``live=True``, the browser must reach 127.0.0.1 of the kernel's
machine) or the static page re-rendered when a slider is released
(``live=False``, for remote kernels).
"""

from __future__ import annotations

import html
from typing import Any

import numpy as np
import numpy.typing as npt

from workbench.errors import WorkbenchError
from workbench.model.robot import Robot
from workbench.poses import angeles7_from_se3
from workbench.singularities.conditions import (
    compute_conditions,
    find_factorisation,
)
from workbench.viz.singularity_gauge import SingularityGauge
from workbench.viz.viewer import Viewer

FloatArray = npt.NDArray[np.float64]


def _ik_branch(robot: Robot, q: FloatArray) -> str | None:
    """Closed-form IK branch label of ``q``, or None where there is none."""
    try:
        from workbench.ik import analytic, nearest
    except ImportError:  # the closed-form IK is not part of this installation
        return None
    try:
        solutions = analytic(robot, robot.fk(q), q_previous=q)
    except WorkbenchError:  # not a PUMA-type arm, or out of reach
        return None
    return nearest(solutions, q).branch  # q's own, within the limits or not


def _format(values: npt.ArrayLike, digits: int = 4) -> str:
    return "[" + " ".join(f"{x: .{digits}f}" for x in np.ravel(values)) + "]"


def compute_readout(
    robot: Robot, q: npt.ArrayLike, gauge: SingularityGauge | None = None
) -> list[str]:
    """Text lines describing configuration ``q`` (nq,) [rad], as the panel shows.

    Lines: the tool pose (Angeles' seven numbers, SI), det J (6-joint arms;
    else the manipulability), the normalised singularity distance, the signed
    shoulder/elbow/wrist distances (PUMA-type arms) and the closed-form IK
    branch (when the IK module supports the arm). Lines that do not apply are
    left out.
    """
    q = robot.check_configuration(q)
    a7 = angeles7_from_se3(robot.fk(q))
    jac = robot.jacobian(q)
    lines = [
        f"tool pose: e·sinφ = {_format(a7[:3])}  cosφ = {a7[3]: .4f}",
        f"           p = {_format(a7[4:])} m",
    ]
    if jac.shape[0] == jac.shape[1]:
        lines.append(f"det J = {np.linalg.det(jac): .4e}")
    else:
        lines.append(
            f"manipulability √det(J Jᵀ) = {np.sqrt(np.linalg.det(jac @ jac.T)): .4e}"
        )
    gauge = gauge or SingularityGauge.from_robot(robot)
    lines.append(
        f"singularity distance ({gauge.method}) = {gauge.compute_distance(q):.3f}"
    )
    if find_factorisation(robot) is not None:
        c = compute_conditions(robot, q)
        lines.append(
            f"shoulder = {float(c.shoulder): .4f} m  elbow = {float(c.elbow): .4f}"
            f"  wrist = {float(c.wrist): .4f}"
        )
    branch = _ik_branch(robot, q)
    if branch is not None:
        lines.append(f"IK branch: {branch}")
    return lines


class TeachPanel:
    """Joint sliders (degrees) driving a Meshcat view of the robot, with a readout.

    Display it as the last expression of a notebook cell.

    Args:
        robot: The robot.
        q: Start configuration, shape (nq,) [rad]; default zeros within limits.
        live: Serve the view live on 127.0.0.1 (updates while dragging);
            False re-renders the static page when a slider is released.
        port: Live server port (0: any free one).
        height: Height of the 3D view [px].

    Raises:
        ImportError: If ``ipywidgets`` is not installed.
    """

    def __init__(
        self,
        robot: Robot,
        q: npt.ArrayLike | None = None,
        *,
        live: bool = True,
        port: int = 0,
        height: int = 480,
    ):
        import ipywidgets as widgets

        self.robot = robot
        self.viewer = Viewer(robot, q, color_by_singularity=True)
        self.viewer.show_frames()
        self._gauge = self.viewer.gauge or SingularityGauge.from_robot(robot)
        self._lines: list[str] = []
        self._live = live
        self._height = height
        self._muted = False
        finite = np.isfinite(robot.lower) & np.isfinite(robot.upper)
        lower = np.rad2deg(np.where(finite, robot.lower, -np.pi))  # ±180° if unlimited
        upper = np.rad2deg(np.where(finite, robot.upper, np.pi))
        self.sliders = [
            widgets.FloatSlider(
                value=float(np.clip(np.rad2deg(v), lo, hi)),
                min=float(lo),
                max=float(hi),
                step=0.5,
                description=f"{name} [°]",
                continuous_update=live,
                readout_format=".1f",
                style={"description_width": "initial"},
            )
            for name, v, lo, hi in zip(
                robot.joint_names, self.viewer.q, lower, upper, strict=True
            )
        ]
        for slider in self.sliders:
            slider.observe(self._on_slider, names="value")
        self.readout = widgets.HTML()
        self.view = widgets.HTML(layout=widgets.Layout(width="100%"))
        if live:
            url = self.viewer.start_server(port=port)
            self.view.value = (
                f'<iframe src="{html.escape(url)}" style="width: 100%; '
                f'height: {int(height)}px; border: none"></iframe>'
            )
        controls = widgets.VBox([*self.sliders, self.readout])
        self.widget = widgets.VBox([controls, self.view])
        self._refresh()

    @property
    def q(self) -> FloatArray:
        """Current configuration, shape (nq,) [rad]."""
        return np.deg2rad([s.value for s in self.sliders])

    def set_configuration(self, q: npt.ArrayLike) -> None:
        """Move the sliders (and the view) to ``q``, shape (nq,) [rad]."""
        q = self.robot.check_configuration(q)
        self._muted = True
        try:
            for slider, value in zip(self.sliders, np.rad2deg(q), strict=True):
                slider.value = float(np.clip(value, slider.min, slider.max))
        finally:
            self._muted = False
        self._refresh()

    def get_readout(self) -> list[str]:
        """The readout lines currently shown."""
        return list(self._lines)

    def _on_slider(self, change: dict[str, Any]) -> None:
        if not self._muted:
            self._refresh()

    def _refresh(self) -> None:
        q = self.q
        self.viewer.display(q)
        self._lines = compute_readout(self.robot, q, self._gauge)
        self.readout.value = (
            '<pre style="font-size: 12px; line-height: 1.3">'
            + html.escape("\n".join(self._lines))
            + "</pre>"
        )
        if not self._live:
            self.view.value = self.viewer.render_inline(height=self._height)

    def close(self) -> None:
        """Stop the live server and close the widgets."""
        self.viewer.stop_server()
        self.widget.close()

    def _repr_mimebundle_(self, **kwargs: Any) -> Any:
        return self.widget._repr_mimebundle_(**kwargs)
