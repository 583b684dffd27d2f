"""Plots of the normal spline and of pick-and-place trajectories (matplotlib).

Imported lazily by the command line and the demo; the core modules never
import matplotlib. Each function follows matplotlib's convention: it draws into
the ``fig`` it is given (these functions draw several axes) or into a new
:class:`matplotlib.figure.Figure`, returns the Figure, and writes a PNG only
when ``path`` is given. A new Figure is not registered with pyplot (no global
state, nothing to close); in a notebook it shows inline when it is the value
of a cell. Angles are shown in degrees (display only); the data stay SI.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Protocol

import numpy as np
import numpy.typing as npt
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from workbench.atomic_files import atomic_file
from workbench.model.robot import Robot
from workbench.trajectory.cartesian import CartesianSamples
from workbench.trajectory.normal_spline import NormalSpline, UniformCubicSpline

FloatArray = npt.NDArray[np.float64]

_DPI = 110
_SAMPLES = 1001


def _new_or_cleared(fig: Figure | None, figsize: tuple[float, float]) -> Figure:
    """``fig`` emptied for a redraw, or a new constrained-layout Figure."""
    if fig is None:
        return Figure(figsize=figsize, layout="constrained")
    fig.clear()
    return fig


def save_figure(fig: Figure, path: str | Path) -> Path:
    """Write ``fig`` at :data:`_DPI` (folders created), all at once; returns the path.

    The format follows the suffix (``.png``, ``.svg``, ``.pdf``, ...).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if fig.canvas is None or type(fig.canvas).__name__ == "FigureCanvasBase":
        FigureCanvasAgg(fig)
    with atomic_file(path) as tmp:
        fig.savefig(tmp, dpi=_DPI, format=path.suffix.lstrip(".").lower() or None)
    return path


def _finish(fig: Figure, path: str | Path | None) -> Figure:
    if path is not None:
        save_figure(fig, path)
    return fig


def plot_normal_spline(
    spline: NormalSpline,
    path: str | Path | None = None,
    *,
    fig: Figure | None = None,
    literal: UniformCubicSpline | None = None,
    literal_amplitude: float | None = None,
) -> Figure:
    """Fig. 1 of Angeles et al.: s, ṡ (a) and s̈, jerk (b) over t' = t/T.

    Args:
        spline: The normal spline.
        path: PNG file to write; None writes nothing.
        fig: Figure to draw into (cleared first); None makes a new one.
        literal: Optionally Section IV read literally (s odd and 2-periodic,
            on [0, 2]), drawn in a third panel (c) over its own period.
        literal_amplitude: The A used for ``literal``, for the panel title.

    Returns:
        The Figure.
    """
    t = np.linspace(0.0, 1.0, _SAMPLES)
    s, sd, sdd = spline.evaluate(t)
    knots = spline.spline.knots
    rows = 2 if literal is None else 3
    fig = _new_or_cleared(fig, (8, 3.4 * rows))
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
        ax3.axvline(1.0, color="k", lw=0.8, ls=":", label="t = 1, where s must be 1")
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
    return _finish(fig, path)


#: Said in a panel whose limits are not drawn (infinite or unknown).
NO_LIMIT = "no limit known"
_QUANTITIES = ("position [deg]", "speed [deg/s]", "acceleration [deg/s²]")


class _JointTrajectory(Protocol):
    """What the joint plot reads: a robot, a duration and samples."""

    @property
    def robot(self) -> Robot: ...

    @property
    def duration(self) -> float: ...

    def sample(self, t: npt.ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]: ...


def plot_joint_trajectory(
    trajectory: _JointTrajectory,
    path: str | Path | None = None,
    *,
    fig: Figure | None = None,
    joints: Sequence[int] | None = None,
    title: str | None = None,
) -> Figure:
    """Position, speed and acceleration of each joint against its own limits.

    One row of three panels per joint (position, speed, acceleration), so
    that every dashed limit line belongs to exactly one joint and one
    quantity; the limit values are written at the line's right end.

    Args:
        trajectory: A joint trajectory (``robot``, ``duration`` [s] and
            ``sample(t) -> (q, qd, qdd)``), e.g. from
            :func:`workbench.trajectory.pick_and_place`.
        path: PNG file to write; None writes nothing.
        fig: Figure to draw into (cleared first); None makes a new one.
        joints: 0-based joint indices to show (default all).
        title: Figure title.

    Returns:
        The Figure. Infinite limits are not drawn (the panel says so).
    """
    robot = trajectory.robot
    idx = list(range(robot.nq)) if joints is None else list(joints)
    t = np.linspace(0.0, trajectory.duration, _SAMPLES)
    values = [np.rad2deg(x[:, idx]) for x in trajectory.sample(t)]
    lows = [robot.lower, -robot.velocity_limit, -robot.acceleration_limit]
    highs = [robot.upper, robot.velocity_limit, robot.acceleration_limit]
    fig = _new_or_cleared(fig, (11.0, 1.9 * len(idx) + 1.0))
    axes = np.atleast_2d(fig.subplots(len(idx), 3, sharex=True, squeeze=False))
    for row, joint in enumerate(idx):
        color = f"C{joint % 10}"
        name = robot.joint_names[joint]
        for col in range(3):
            ax = axes[row, col]
            ax.plot(t, values[col][:, row], color=color, lw=1.6)
            lo = float(np.rad2deg(np.asarray(lows[col])[joint]))
            hi = float(np.rad2deg(np.asarray(highs[col])[joint]))
            _limit_lines(ax, lo, hi, color)
            ax.grid(alpha=0.3)
            ax.tick_params(labelsize=8)
            if row == 0:
                ax.set_title(_QUANTITIES[col], fontsize=10)
            if col == 0:
                label = (
                    name
                    if name == f"joint{joint + 1}"
                    else f"{name} (joint {joint + 1})"
                )
                ax.set_ylabel(label, fontsize=9)
    for ax in axes[-1]:
        ax.set_xlabel("time t [s]")
    handles = [
        Line2D([], [], color="0.2", lw=1.6),
        Line2D([], [], color="0.2", ls="--", lw=0.9),
    ]
    fig.legend(
        handles,
        ["joint value", "that joint's limit (value at the right end)"],
        loc="outside lower center",
        ncol=2,
        fontsize="small",
    )
    if title:
        fig.suptitle(title)
    return _finish(fig, path)


def _limit_lines(ax: Axes, lower: float, upper: float, color: str) -> None:
    """Dashed lines at the finite limits, labelled with their value."""
    finite = [v for v in (lower, upper) if np.isfinite(v)]
    for value in finite:
        ax.axhline(value, color=color, ls="--", lw=0.9, alpha=0.8)
        ax.annotate(
            f"{value:.4g}",
            xy=(1.0, value),
            xycoords=("axes fraction", "data"),
            xytext=(2, 0),
            textcoords="offset points",
            va="center",
            fontsize=7,
            color=color,
            annotation_clip=False,
        )
    if not finite:  # a legend entry, so that it is placed clear of the curve
        ax.legend(
            [Line2D([], [], ls="none")],
            [NO_LIMIT],
            loc="best",
            handlelength=0.0,
            handletextpad=0.0,
            fontsize=7,
            labelcolor="0.4",
            framealpha=0.8,
        )


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
    path: str | Path | None = None,
    *,
    fig: Figure | None = None,
    which: str = "all",
    title: str | None = None,
) -> Figure:
    """Tool-frame time histories as the paper's Figs. 4 (vect), 5 (cos), 6 (p).

    Args:
        samples: FK along the trajectory.
        path: PNG file to write; None writes nothing.
        fig: Figure to draw into (cleared first); None makes a new one.
        which: ``"vect"``, ``"cos"``, ``"position"``, ``"velocity"`` (speed
            and acceleration norms) or ``"all"`` (the four panels).
        title: Figure title.

    Returns:
        The Figure.

    Raises:
        ValueError: If ``which`` is unknown.
    """
    kinds = [*_PANELS, "velocity"] if which == "all" else [which]
    for kind in kinds:
        if kind not in (*_PANELS, "velocity"):
            raise ValueError(f"unknown panel {kind!r}")
    fig = _new_or_cleared(fig, (8, 2.6 + 2.4 * len(kinds)))
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
    return _finish(fig, path)


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
    ax.set_ylabel("norm [m/s, rad/s, m/s², rad/s²]")
    ax.set_title("J q̇ and J q̈ + J̇ q̇ of the tool frame (zero at both ends)")
    ax.legend(loc="best", fontsize="small")
    ax.grid(alpha=0.3)
