"""PNG plots of the normal spline and of pick-and-place trajectories (matplotlib).

Imported lazily by the command line and the demo; the core modules never
import matplotlib. Figures are built with :class:`matplotlib.figure.Figure`
and written by the Agg canvas, so no pyplot state and no display is involved.
Angles are shown in degrees (display only); the data stay SI.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import numpy.typing as npt
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from workbench.trajectory.cartesian import CartesianSamples
from workbench.trajectory.normal_spline import NormalSpline, UniformCubicSpline

FloatArray = npt.NDArray[np.float64]

_DPI = 110
_SAMPLES = 1001


def _save(fig: Figure, path: str | Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    FigureCanvasAgg(fig)
    fig.savefig(path, dpi=_DPI)
    return path


def _colors(n: int) -> list[str]:
    return [f"C{i % 10}" for i in range(n)]


def plot_normal_spline(
    spline: NormalSpline,
    path: str | Path,
    *,
    literal: UniformCubicSpline | None = None,
    literal_amplitude: float | None = None,
) -> Path:
    """Fig. 1 of Angeles et al.: s, ṡ (a) and s̈, jerk (b) over t' = t/T.

    Args:
        spline: The normal spline.
        path: PNG file to write.
        literal: Optionally Section IV read literally (s odd and 2-periodic,
            on [0, 2]), drawn in a third panel (c) over its own period.
        literal_amplitude: The A used for ``literal``, for the panel title.

    Returns:
        ``path``.
    """
    t = np.linspace(0.0, 1.0, _SAMPLES)
    s, sd, sdd = spline.evaluate(t)
    knots = spline.spline.knots
    rows = 2 if literal is None else 3
    fig = Figure(figsize=(8, 3.4 * rows), layout="constrained")
    axes = fig.subplots(rows, 1)
    ax1, ax2 = axes[0], axes[1]
    ax1.plot(t, s, color="C0", label="s(t')")
    ax1.plot(t, sd, color="C1", label="ds/dt'")
    ax1.plot(knots, spline.evaluate(knots)[0], "o", ms=3, color="C0", label="knots")
    ax1.set_ylabel("s [-], ds/dt' [-]")
    ax1.set_title(
        f"(a) Normal spline and first derivative, N = {spline.n_points}, "
        f"A = {spline.amplitude:.4f}"
    )
    ax1.legend(loc="upper left", fontsize="small")
    ax1.grid(alpha=0.3)
    ax2.plot(t, sdd, color="C2", label="d²s/dt'²")
    ax2.set_ylabel("d²s/dt'² [-]", color="C2")
    ax2.grid(alpha=0.3)
    ax2b = ax2.twinx()
    edges = np.append(knots[:-1], 1.0)
    ax2b.stairs(spline.jerk(knots[:-1]), edges, baseline=None, color="C3", lw=0.9)
    ax2b.set_ylabel("d³s/dt'³ [-] (piecewise constant)", color="C3")
    lim = 1.1 * max(np.abs(sdd).max(), 1e-12)
    ax2.set_ylim(-lim, lim)
    jlim = 1.1 * np.abs(spline.jerk(knots[:-1])).max()
    ax2b.set_ylim(-jlim, jlim)
    ax2.set_title("(b) Second derivative (left axis) and jerk (right axis)")
    for ax in (ax1, ax2):
        ax.set_xlabel("normalised time t' = t/T [-]")
    if literal is not None:
        ax3 = axes[2]
        tl = np.linspace(literal.start, literal.end, _SAMPLES)
        ls, lsd, _ = literal.evaluate(tl)
        ax3.plot(tl, ls, color="C0", label="s")
        ax3.plot(tl, lsd, color="C1", label="ds/dt")
        ax3.axvline(1.0, color="k", lw=0.8, ls=":")
        ax3.plot([0.0, 1.0], [0.0, 1.0], "kx", label="required s(0) = 0, s(1) = 1")
        amp = "" if literal_amplitude is None else f", A = {literal_amplitude:g}"
        ax3.set_title(
            "(c) Section IV read literally: s odd, 2-periodic, "
            f"s̈_i = A sin(πt_i){amp}: a sine"
        )
        ax3.set_xlabel("t [-] (the literal spline's own period [0, 2])")
        ax3.set_ylabel("s [-], ds/dt [-]")
        ax3.legend(loc="upper right", fontsize="small")
        ax3.grid(alpha=0.3)
    return _save(fig, path)


def _limit_lines(
    ax: Axes, lower: FloatArray, upper: FloatArray, colors: Sequence[str]
) -> bool:
    drawn = False
    for lo, hi, color in zip(lower, upper, colors, strict=True):
        for value in (lo, hi):
            if np.isfinite(value):
                ax.axhline(value, color=color, ls="--", lw=0.9, alpha=0.7)
                drawn = True
    return drawn


def plot_joint_trajectory(
    trajectory,
    path: str | Path,
    *,
    joints: Sequence[int] | None = None,
    title: str | None = None,
) -> Path:
    """Positions, speeds and accelerations of some joints, with their limits.

    Args:
        trajectory: A joint trajectory (``robot``, ``duration``, ``sample``).
        path: PNG file to write.
        joints: 0-based joint indices to show (default all).
        title: Figure title.

    Returns:
        ``path``. Limits are dashed lines in each joint's colour; infinite
        limits are not drawn (noted in the panel title).
    """
    robot = trajectory.robot
    idx = list(range(robot.nq)) if joints is None else list(joints)
    names = [robot.joint_names[i] for i in idx]
    colors = _colors(len(idx))
    t = np.linspace(0.0, trajectory.duration, _SAMPLES)
    values = [np.rad2deg(x[:, idx]) for x in trajectory.sample(t)]
    lows = [robot.lower, -robot.velocity_limit, -robot.acceleration_limit]
    highs = [robot.upper, robot.velocity_limit, robot.acceleration_limit]
    labels = ["position [deg]", "speed [deg/s]", "acceleration [deg/s²]"]
    fig = Figure(figsize=(9, 8.5), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    for ax, data, lo, hi, label in zip(axes, values, lows, highs, labels, strict=True):
        for k, (name, color) in enumerate(zip(names, colors, strict=True)):
            ax.plot(t, data[:, k], color=color, label=name)
        drawn = _limit_lines(
            ax, np.rad2deg(np.asarray(lo)[idx]), np.rad2deg(np.asarray(hi)[idx]), colors
        )
        ax.set_ylabel(label)
        ax.set_title(
            f"joint {label.split(' ')[0]}: limits dashed"
            if drawn
            else f"joint {label.split(' ')[0]}: no limit known"
        )
        ax.grid(alpha=0.3)
    handles, texts = axes[0].get_legend_handles_labels()
    handles.append(Line2D([], [], color="0.3", ls="--", lw=0.9))
    texts.append("limit (joint's colour)")
    axes[0].legend(
        handles, texts, loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize="small"
    )
    axes[-1].set_xlabel("time t [s]")
    if title:
        fig.suptitle(title)
    return _save(fig, path)


_PANELS = {
    "vect": (
        slice(0, 3),
        ("e_x sinφ", "e_y sinφ", "e_z sinφ"),
        1.0,
        "vect(Q) [-]",
        "vect(Q) = e sinφ of the tool orientation (Angeles Fig. 4)",
    ),
    "cos": (slice(3, 4), ("cosφ",), 1.0, "cosφ [-]", "cosφ (Angeles Fig. 5)"),
    "position": (
        slice(4, 7),
        ("p_x", "p_y", "p_z"),
        1e3,
        "position [mm]",
        "position of the tool point P, base frame (Angeles Fig. 6)",
    ),
}


def plot_cartesian(
    samples: CartesianSamples,
    path: str | Path,
    *,
    which: str = "all",
    title: str | None = None,
) -> Path:
    """Tool-frame time histories as the paper's Figs. 4 (vect), 5 (cos), 6 (p).

    Args:
        samples: FK along the trajectory.
        path: PNG file to write.
        which: ``"vect"``, ``"cos"``, ``"position"``, ``"velocity"`` (speed
            and acceleration norms) or ``"all"`` (the four panels).
        title: Figure title.

    Returns:
        ``path``.

    Raises:
        ValueError: If ``which`` is unknown.
    """
    kinds = [*_PANELS, "velocity"] if which == "all" else [which]
    for kind in kinds:
        if kind not in (*_PANELS, "velocity"):
            raise ValueError(f"unknown panel {kind!r}")
    fig = Figure(figsize=(8, 2.6 + 2.4 * len(kinds)), layout="constrained")
    axes = np.atleast_1d(fig.subplots(len(kinds), 1, sharex=True))
    t = samples.t
    for ax, kind in zip(axes, kinds, strict=True):
        if kind == "velocity":
            _velocity_panel(ax, samples)
            continue
        cols, names, scale, label, panel_title = _PANELS[kind]
        data = samples.angeles7[:, cols] * scale
        for k, name in enumerate(names):
            ax.plot(t, data[:, k], color=f"C{k}", label=name)
        ax.set_ylabel(label)
        ax.set_title(panel_title)
        ax.legend(loc="best", fontsize="small")
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time t [s]")
    if title:
        fig.suptitle(title)
    return _save(fig, path)


def _velocity_panel(ax: Axes, samples: CartesianSamples) -> None:
    t = samples.t
    ax.plot(t, np.linalg.norm(samples.velocity[:, :3], axis=1), label="|v| [m/s]")
    ax.plot(t, np.linalg.norm(samples.velocity[:, 3:], axis=1), label="|ω| [rad/s]")
    ax.plot(t, np.linalg.norm(samples.acceleration[:, :3], axis=1), label="|a| [m/s²]")
    ax.plot(
        t,
        np.linalg.norm(samples.acceleration[:, 3:], axis=1),
        label="|dω/dt| [rad/s²]",
    )
    ax.set_ylabel("tool speed, acceleration")
    ax.set_title("J q̇ and J q̈ + J̇ q̇ of the tool frame (zero at both ends)")
    ax.legend(loc="best", fontsize="small")
    ax.grid(alpha=0.3)
