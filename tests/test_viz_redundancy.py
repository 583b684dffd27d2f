"""Seven-axis arms in the viewer: branches at one value, one branch over the value.

The sweep's configurations are checked against forward kinematics (the pose),
the parameter of each configuration (``ik.redundancy_parameter``) and the
joint limits; the page's ghost nodes, colours and animation are read back
from its Meshcat commands; the page renders in headless Chromium without
console errors, with the ghost arms' pixels where they stand.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tests.conftest import run_cli
from tests.test_cli_seven_axis import Q0, ROBOTS
from tests.test_viz import by_path, page_commands
from tests.test_viz_browser import HEIGHT, WIDTH, changed, screenshot, seek
from workbench import InputError, ik, load_robot
from workbench.cli import EXIT_BAD_INPUT
from workbench.viz import Viewer
from workbench.viz.redundancy_sweep import (
    MAX_SWEEP,
    compute_redundancy_sweep,
    find_branch,
    show_redundancy_sweep,
    spread_over_intervals,
    sweep_colors,
)

#: FK of a closed-form configuration against its target [m, rad].
ATOL_POSE = 1e-9
#: A parameter value recovered from its configuration [rad].
ATOL_PARAMETER = 1e-9
#: Largest |dq/dψ| along the test pose's sweep through ±π [1]: a jump between
#: branches or intervals would be a step of order 1 rad per sample.
MAX_JOINT_RATE = 8.0
#: Arithmetic on interval ends [rad].
ATOL_SPREAD = 1e-12


@st.composite
def _intervals(draw: st.DrawFn) -> tuple[tuple[float, float], ...]:
    edges = sorted(
        draw(
            st.lists(
                st.floats(-4.0, 4.0, allow_nan=False),
                min_size=2,
                max_size=8,
                unique=True,
            ).filter(lambda e: len(e) % 2 == 0)
        )
    )
    pairs = tuple((edges[i], edges[i + 1]) for i in range(0, len(edges), 2))
    return pairs


@given(intervals=_intervals(), count=st.integers(1, 40))
def test_spread_values_lie_inside_and_evenly_over_the_joined_length(
    intervals, count
) -> None:
    values = spread_over_intervals(intervals, count)
    assert values.shape == (count,)
    assert np.all(np.diff(values) > 0.0)
    inside = [any(lo <= v <= hi for lo, hi in intervals) for v in values]
    assert all(inside)
    # position of each value along the joined intervals: (k + 1/2) L / count
    total = sum(hi - lo for lo, hi in intervals)
    along = [
        sum(min(max(v - lo, 0.0), hi - lo) for lo, hi in intervals) for v in values
    ]
    np.testing.assert_allclose(
        along, (np.arange(count) + 0.5) * total / count, rtol=0, atol=ATOL_SPREAD
    )


def test_spread_refuses_no_length_and_no_count() -> None:
    with pytest.raises(InputError, match="no length"):
        spread_over_intervals(((1.0, 1.0),), 3)
    with pytest.raises(InputError, match="at least 1"):
        spread_over_intervals(((0.0, 1.0),), 0)


@pytest.mark.parametrize("name", ROBOTS)
def test_sweep_configurations_reach_the_pose_at_their_values(name) -> None:
    robot = load_robot(name)
    q0 = Q0[name]
    value, branch = find_branch(robot, q0)
    assert abs(value - float(ik.get_solver(robot).parameter_of(q0))) < ATOL_PARAMETER
    target = robot.fk(q0)
    sweep = compute_redundancy_sweep(robot, target, 9, branch)
    feasible = ik.get_solver(robot).feasible(target)
    assert sweep.intervals == feasible.intervals[feasible.branches.index(branch)]
    assert sweep.branch == branch and sweep.q.shape == (9, 7)
    for qk, vk in zip(sweep.q, sweep.values, strict=True):
        error = target.actInv(robot.fk(qk))
        assert np.linalg.norm(error.translation) < ATOL_POSE
        assert np.linalg.norm(pin.log3(error.rotation)) < ATOL_POSE
        assert np.all((qk >= robot.lower) & (qk <= robot.upper))
        assert abs(float(ik.get_solver(robot).parameter_of(qk)) - vk) < ATOL_PARAMETER
        assert any(lo <= vk <= hi for lo, hi in sweep.intervals)
    assert np.all(np.diff(sweep.unwrapped) > 0.0)
    wrapped = np.where(
        sweep.unwrapped < -np.pi, sweep.unwrapped + 2 * np.pi, sweep.unwrapped
    )
    np.testing.assert_array_equal(sweep.values, wrapped)


def test_branch_of_q_reproduces_q() -> None:
    robot = load_robot("iiwa14")
    value, branch = find_branch(robot, Q0["iiwa14"])
    (found,) = [
        s
        for s in ik.analytic(robot, robot.fk(Q0["iiwa14"]), redundancy=value)
        if s.branch == branch
    ]
    wrapped = np.angle(np.exp(1j * (found.q - Q0["iiwa14"])))
    assert np.max(np.abs(wrapped)) < ATOL_POSE


def test_sweep_refuses_bad_counts_and_labels() -> None:
    robot = load_robot("iiwa14")
    target = robot.fk(Q0["iiwa14"])
    with pytest.raises(InputError, match=f"1..{MAX_SWEEP}"):
        compute_redundancy_sweep(robot, target, MAX_SWEEP + 1, "x")
    with pytest.raises(InputError, match="unknown branch 'x'"):
        compute_redundancy_sweep(robot, target, 3, "x")


def test_page_has_one_coloured_ghost_per_value_and_an_animation() -> None:
    robot = load_robot("iiwa14")
    _, branch = find_branch(robot, Q0["iiwa14"])
    sweep = compute_redundancy_sweep(robot, robot.fk(Q0["iiwa14"]), 5, branch)
    viewer = Viewer(robot, Q0["iiwa14"])
    show_redundancy_sweep(viewer, sweep, degrees=True)
    page = viewer.render_html()
    commands = page_commands(page)
    objects = by_path(commands, "set_object")
    ghosts = sorted(
        {p.split("/")[3] for p in objects if p.startswith("/meshcat/ghosts/")}
    )
    assert len(ghosts) == 5
    by_ghost: dict[str, set[int]] = {}
    for path, command in objects.items():
        if path.startswith("/meshcat/ghosts/") and "materials" in command["object"]:
            color = int(command["object"]["materials"][0]["color"])
            by_ghost.setdefault(path.split("/")[3], set()).add(color)
    assert all(len(colors) == 1 for colors in by_ghost.values())  # one per ghost
    rgb = (255 * sweep_colors(sweep.unwrapped)).astype(int)  # truncated, as Meshcat
    expected = {(r << 16) | (g << 8) | b for r, g, b in rgb}
    assert {c for colors in by_ghost.values() for c in colors} == expected
    assert "set_animation" in {c["type"] for c in commands}
    assert "Ghost colour" in page and f"branch {branch}" in page


def test_cli_sweep_and_branches_pages(tmp_path, capsys) -> None:
    q_deg = [repr(float(v)) for v in np.degrees(Q0["iiwa14"])]
    base = ["view", "--robot", "iiwa14", "--deg", *q_deg]
    sweep = tmp_path / "sweep.html"
    code, out, err = run_cli(
        capsys, *base, "--redundancy-sweep", "4", "--html", str(sweep)
    )
    assert (code, err) == (0, ""), err
    assert "wrote" in out
    objects = by_path(page_commands(sweep.read_text()), "set_object")
    assert len({p.split("/")[3] for p in objects if "/ghosts/" in p}) == 4
    branches = tmp_path / "branches.html"
    code, _, err = run_cli(
        capsys,
        *base,
        "--ik-branches",
        "--redundancy",
        "120",
        "--html",
        str(branches),
    )
    assert (code, err) == (0, "")
    page = branches.read_text()
    assert "arm angle = 120.000° (given)" in page


@pytest.mark.parametrize(
    ("robot", "args", "message"),
    [
        ("ur5", ["--redundancy-sweep", "3"], "six-axis arm has no redundancy"),
        ("ur5", ["--ik-branches", "--redundancy", "1"], "no redundancy"),
        ("iiwa14", ["--ik-branches", "--redundancy-sweep", "3"], "not both"),
        ("iiwa14", ["--redundancy", "1"], "add it"),
        ("iiwa14", ["--branch", "x"], "add it"),
        ("iiwa14", ["--redundancy-sweep", "3", "--branch", "x"], "unknown branch"),
        ("iiwa14", ["--redundancy-sweep", "0"], "must be 1..64"),
    ],
)
def test_cli_sweep_input_errors_exit_2(tmp_path, capsys, robot, args, message) -> None:
    q = ["0"] * 6 if robot == "ur5" else [repr(float(v)) for v in np.degrees(Q0[robot])]
    out = str(tmp_path / "x.html")
    code, _, err = run_cli(
        capsys, "view", "--robot", robot, "--deg", *q, *args, "--html", out
    )
    assert code == EXIT_BAD_INPUT
    assert message in err and len(err.strip().splitlines()) == 1


def test_cli_sweep_needs_q(capsys, tmp_path) -> None:
    out = str(tmp_path / "x.html")
    code, _, err = run_cli(
        capsys, "view", "--robot", "iiwa14", "--redundancy-sweep", "3", "--html", out
    )
    assert code == EXIT_BAD_INPUT and "needs joint values" in err


@pytest.mark.parametrize("name", ROBOTS)
def test_sweep_page_renders_the_ghosts(chromium, tmp_path, name) -> None:
    """No console errors; hiding the ghosts removes pixels where they stand."""
    from tests._chromium import take_screenshot

    robot = load_robot(name)
    _, branch = find_branch(robot, Q0[name])
    sweep = compute_redundancy_sweep(robot, robot.fk(Q0[name]), 8, branch)
    viewer = Viewer(robot, Q0[name], color_by_singularity=True)
    show_redundancy_sweep(viewer, sweep)
    viewer.set_camera([1.6, 1.6, 1.2], [0.0, 0.0, 0.4])
    page = tmp_path / "page.html"
    page.write_text(viewer.render_html(), encoding="utf-8")
    errors = take_screenshot(
        chromium,
        page,
        tmp_path / "page.png",
        width=WIDTH,
        height=HEIGHT,
        script=seek(0),
    )
    assert errors == []
    shown = screenshot(
        chromium, viewer.render_html(legend=False), tmp_path / "g.png", seek(0.0)
    )
    viewer.set_visible("ghosts", False)
    bare = screenshot(
        chromium, viewer.render_html(legend=False), tmp_path / "n.png", seek(0.0)
    )
    assert changed(shown, bare).mean() > 0.01  # the ghosts cover part of the view


def test_ghosts_of_collada_arms_take_their_colour_from_the_collision_geometry() -> None:
    from workbench.viz._arm import get_colorable_geometry

    panda = load_robot("panda")
    geometry, visual = get_colorable_geometry(panda)
    assert geometry is panda.collision_model and not visual
    for name in ("iiwa14", "puma560"):  # primitives, STL: their visual geometry
        robot = load_robot(name)
        assert get_colorable_geometry(robot) == (robot.visual_model, True)
    viewer = Viewer(panda, Q0["panda"])
    viewer.show_ghosts([Q0["panda"]], labels=["g"], colors=[[1.0, 0.0, 0.0]])
    page = viewer.render_html()
    objects = by_path(page_commands(page), "set_object")
    ghosts = [c for p, c in objects.items() if p.startswith("/meshcat/ghosts/g/")]
    assert ghosts and all(
        c["object"]["materials"][0]["color"] == 0xFF0000 for c in ghosts
    )
    assert "collision geometry" in page


def test_an_arm_angle_sweep_runs_through_pi_without_a_jump() -> None:
    """A branch feasible across ψ = ±π is swept across it, continuously."""
    robot = load_robot("iiwa14")
    target = robot.fk(Q0["iiwa14"])
    feasible = ik.get_solver(robot).feasible(target)
    through = [
        label
        for label, intervals in zip(feasible.branches, feasible.intervals, strict=True)
        if len(intervals) > 1
        and intervals[0][0] == -np.pi
        and intervals[-1][1] == np.pi
    ]
    assert through, "no branch of the test pose is feasible through ±π"
    sweep = compute_redundancy_sweep(robot, target, 24, through[0])
    first, last = sweep.intervals[0], sweep.intervals[-1]
    inside = (sweep.unwrapped >= last[0] - 2 * np.pi) & (sweep.unwrapped <= first[1])
    assert sweep.unwrapped[0] < -np.pi and inside.sum() >= 2  # the joined interval
    steps = np.abs(np.angle(np.exp(1j * np.diff(sweep.q[inside], axis=0))))
    spacing = np.diff(sweep.unwrapped[inside]).max()
    assert steps.max() < MAX_JOINT_RATE * spacing  # no jump: joints follow ψ
    viewer = Viewer(robot, Q0["iiwa14"])
    show_redundancy_sweep(viewer, sweep, degrees=True)
    assert ">±180<" in viewer.render_html()  # the scale marks where it passes ±π


def test_cli_branches_at_a_value_that_reaches_nothing_exit_3(capsys, tmp_path) -> None:
    """Panda at q7 = 160°: no branch reaches FK(Q); the feasible q7 are said."""
    q = [repr(float(v)) for v in np.degrees(Q0["panda"])]
    out = tmp_path / "x.html"
    argv = ["view", "--robot", "panda", "--deg", *q, "--ik-branches"]
    code, stdout, err = run_cli(
        capsys, *argv, "--redundancy", "160", "--html", str(out)
    )
    assert code == 3 and stdout == "" and not out.exists()
    assert len(err.strip().splitlines()) == 1 and "feasible q7" in err


def test_the_command_line_bound_is_the_viewer_s() -> None:
    from workbench.cli import view

    assert view.MAX_SWEEP == MAX_SWEEP


@pytest.mark.parametrize("name", ROBOTS)
def test_branches_page_renders_the_arm_and_its_ghosts(chromium, tmp_path, name) -> None:
    """The --ik-branches page of a seven-axis arm: no console error, arm and ghosts."""
    from tests._chromium import take_screenshot

    robot = load_robot(name)
    value = float(ik.get_solver(robot).parameter_of(Q0[name]))
    solutions = ik.analytic(robot, robot.fk(Q0[name]), redundancy=value)
    viewer = Viewer(robot, Q0[name], color_by_singularity=True)
    viewer.show_ghosts([s.q for s in solutions], labels=[s.branch for s in solutions])
    viewer.set_camera([1.6, 1.6, 1.2], [0.0, 0.0, 0.4])
    page = tmp_path / "page.html"
    page.write_text(viewer.render_html(), encoding="utf-8")
    errors = take_screenshot(
        chromium, page, tmp_path / "page.png", width=WIDTH, height=HEIGHT
    )
    assert errors == []
    whole = screenshot(chromium, viewer.render_html(legend=False), tmp_path / "w.png")
    viewer.set_visible("ghosts", False)
    arm = screenshot(chromium, viewer.render_html(legend=False), tmp_path / "a.png")
    viewer.set_visible("robot", False)
    bare = screenshot(chromium, viewer.render_html(legend=False), tmp_path / "b.png")
    assert changed(arm, bare).mean() > 0.01  # the arm's pixels
    assert changed(whole, arm).mean() > 0.002  # the ghosts' (tinting the arm)
