"""MotionBenchMaker: the workbench's planner, VAMP and OMPL side by side.

Run: ``python -m benchmarks.bench_motion [--robots panda,ur5]
[--scenarios table_pick,...] [--limit N]
[--planners vamp,ompl,workbench,workbench-ompl]
[--time-limit 1.0] [--verify workbench,vamp] [--sdist PATH] [--cache DIR]
[--json OUT]``.

The problems are MotionBenchMaker's (Chamzas et al., *MotionBenchMaker: A Tool
to Generate and Benchmark Motion Planning Datasets*, RA-L 2022) as the
``vamp-planner`` 0.6.4 sdist ships them: ``resources/{panda,ur5}/
problems.tar.bz2``, 7 scenarios x 100 problems per robot, each a MoveIt
planning scene (boxes and cylinders) and a MoveIt motion request (start joint
state, joint goal), with the robots' URDFs, SRDFs and meshes beside them. The
sdist comes from the package index only: ``--sdist PATH``, else the copy in
``--cache`` (default ``~/.cache/workbench-bench``), else PyPI's simple index
(``https://pypi.org/simple/vamp-planner/``), checked against its SHA-256.

Per robot, scenario and problem, in one run:

* **valid**: start and goal free of collision on the exact meshes
  (:class:`workbench.collision.CollisionChecker`, coal, the robot's SRDF).
  Invalid problems are left out of every planner's statistics and listed in
  the JSON with their closest pair; VAMP's own verdict (its spheres) is
  counted beside it.
* **vamp**: ``vamp.<robot>.rrtc`` with the settings of VAMP's
  ``scripts/evaluate_mbm.py`` (``configure_robot_and_planner_with_kwargs``:
  RRT-Connect range 1.0 (panda) / 1.5 (ur5), 10⁶ iterations, the Halton
  sampler reset per problem, the default simplification), planning and
  simplification times as VAMP measures them.
* **ompl**: OMPL's RRTConnect (same range) with VAMP's checker behind Python
  callbacks: a state validity callback (``vamp.<robot>.validate``) and a
  motion validator that checks a segment in pieces of at most
  ``rake / resolution`` = 8 / 32 rad (each ``validate_motion`` call samples
  its piece at ``rake`` = 8 points on x86-64), so motions are checked at
  VAMP's own planner resolution, 32 samples per unit of joint-space length.
  Planning time (OMPL's), then OMPL's ``PathSimplifier``
  (``simplifySolution``) time. Time limit ``--time-limit`` per problem [s].
* **workbench**: ``workbench.motion.plan(robot, scene, start, goal, seed=s,
  time_limit=...)`` from the joint goal, and again from the goal
  configuration's tool pose (``robot.fk(goal)``, a ``pin.SE3``). Each
  trajectory is then checked on the exact meshes with
  ``workbench.motion.verify_trajectory`` (``check_path`` at joint steps
  <= 0.25°, proven between the samples), its time reported apart. The
  column is skipped (with a line on stderr) where ``workbench.motion.plan``
  is missing. Where the plan carries its own exact-mesh report (``clearance``
  and ``verification_time``, the same check on the same meshes) it is
  counted instead of checking twice. The robots' acceleration limits:
  :data:`ACCELERATION_LIMITS`.
* **workbench-ompl**: ``workbench.motion.plan(..., planner="ompl:RRTConnect")``
  from the joint goal: OMPL's RRTConnect (range 1.0) with the workbench's
  compiled checker behind Python callbacks (state validity and certified
  motions), then the same shortcuts, time scaling and exact check: the
  compiled RRT-Connect and OMPL's beside it with the same checker.
* ``--verify vamp`` checks VAMP's simplified paths on the exact meshes too
  (the polyline at joint steps <= 0.25°, :func:`check_polyline`): VAMP plans
  on spheres, and its paths are judged by the same meshes (slow on the UR5,
  whose gripper and force sensor meshes have ~20,000 vertices each).

Path length: the sum of the joint-space Euclidean lengths of the simplified
path's segments [rad]; its ratio to VAMP's is taken per problem solved by
both, then the median. Times are wall-clock as each planner reports them
(VAMP: its own nanoseconds; OMPL: its plan and simplification clocks; the
workbench: ``planning_time`` and ``smoothing_time``); a reference loop
``sum(range(1000))`` [µs] is printed per robot. Nothing is asserted.

VAMP is an sdist whose build downloads its CMake dependencies, so it is not
in the ``bench`` extra: ``pip install vamp-planner==0.6.4`` with internet, or
offline from its dependencies given as local sources
(``CPM_<name>_SOURCE``; ``docs/motion-benchmark.md`` says how).
OMPL is: ``pip install ompl==2.0.1``.
"""

from __future__ import annotations

import argparse
import functools
import importlib.util
import json
import math
import sys
import timeit
from collections.abc import Callable, Iterator, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks._motion_peers import (
    OmplPeer,
    VampPeer,
    WorkbenchPeer,
    check_polyline,
    get_workbench_plan,
)
from benchmarks._motionbenchmaker import (
    ROBOTS,
    SCENARIOS,
    extract_resources,
    get_sdist,
    load_mbm_robot,
)
from workbench.cli._common import format_time
from workbench.collision import CollisionChecker
from workbench.motion import check_validity, find_problems

PLANNERS = ("vamp", "ompl", "workbench", "workbench-ompl")

# --- the run --------------------------------------------------------------


def run_robot(
    name: str,
    resources: Path,
    args: argparse.Namespace,
    progress: Callable[[int, int], None] | None = None,
) -> dict[str, Any]:
    """Every problem of robot ``name``: validity, then each planner.

    Returns:
        ``robot``, ``reference_us`` (before and after) and ``problems``: one
        record per problem (``scenario``, ``index``, ``valid`` (a
        :class:`workbench.motion.Validity` as a dict), ``vamp_valid``, and
        one :class:`Run` as a dict per planner on valid problems).
    """
    robot = load_mbm_robot(resources, name)
    problems = find_problems(
        resources / name / "problems",
        robot_name=name,
        scenarios=args.scenarios,
        limit=args.limit,
    )
    planners = args.planners
    vamp = VampPeer(name) if {"vamp", "ompl"} & set(planners) else None
    order = (
        None if vamp is None else [robot.joint_names.index(j) for j in vamp.joint_names]
    )
    ompl = OmplPeer(vamp, args.time_limit) if vamp and "ompl" in planners else None
    wanted = {"workbench", "workbench-ompl"} & set(planners)
    plan = get_workbench_plan() if wanted else None
    if wanted and plan is None:
        print("workbench.motion.plan is missing: no workbench column", file=sys.stderr)
    ours = (
        None
        if plan is None or "workbench" not in planners
        else WorkbenchPeer(plan, args.time_limit, "workbench" in args.verify)
    )
    with_ompl = "workbench-ompl" in planners and plan is not None
    if with_ompl and importlib.util.find_spec("ompl") is None:
        print("ompl is not installed: no workbench-ompl column", file=sys.stderr)
        with_ompl = False
    ours_ompl = (
        None
        if not with_ompl
        else WorkbenchPeer(
            functools.partial(plan, planner="ompl:RRTConnect"),
            args.time_limit,
            "workbench" in args.verify,
        )
    )
    if plan is not None and problems:
        _warm_up(plan, robot, problems[0])
        if ours_ompl is not None:
            _warm_up(
                functools.partial(plan, planner="ompl:RRTConnect"), robot, problems[0]
            )
    reference = [_reference_us()]
    records = []
    for done, problem in enumerate(problems):
        scene = problem.scene
        start, goal = problem.read_request(robot)
        checker = CollisionChecker(robot, scene)
        validity = check_validity(robot, problem, checker=checker)
        record: dict[str, Any] = {
            "scenario": problem.scenario,
            "index": problem.index,
            "valid": asdict(validity),
        }
        env = None
        if vamp is not None and order is not None:
            env = vamp.environment(scene, problem.scenario)
            qs, qg = start[order].tolist(), goal[order].tolist()
            record["vamp_valid"] = vamp.valid(qs, env) and vamp.valid(qg, env)
        if validity.valid:
            if vamp is not None and "vamp" in planners:
                run = vamp.run(qs, qg, env)
                if run.solved and "vamp" in args.verify and order is not None:
                    path = np.empty((len(run.extra["path"]), robot.nq))
                    path[:, order] = run.extra["path"]  # VAMP's order to the robot's
                    run.extra.update(check_polyline(checker, path))
                record["vamp"] = asdict(run)
            if ompl is not None:
                record["ompl"] = asdict(ompl.run(qs, qg, env))
            if ours is not None:
                seed = problem.index
                record["workbench"] = asdict(
                    ours.run(robot, scene, checker, start, goal, seed)
                )
                record["workbench_pose"] = asdict(
                    ours.run(robot, scene, checker, start, robot.fk(goal), seed)
                )
            if ours_ompl is not None:
                record["workbench_ompl"] = asdict(
                    ours_ompl.run(robot, scene, checker, start, goal, problem.index)
                )
        records.append(record)
        if progress is not None:
            progress(done + 1, len(problems))
    reference.append(_reference_us())
    return {"robot": name, "reference_us": reference, "problems": records}


def _warm_up(plan: Any, robot: Any, problem: Any) -> None:
    """Untimed plans: the robot's spheres are built and the kernels loaded
    (compiled on a first run) before any problem is timed, as VAMP's are: the
    search's (a short try at the problem) and the shortcuts' (a step of a
    milliradian towards the goal, solved at once)."""
    start, goal = problem.read_request(robot)
    plan(robot, problem.scene, start, goal, seed=0, time_limit=0.05, verify=False)
    near = start + 1e-3 * (goal - start) / max(
        float(np.linalg.norm(goal - start)), 1e-3
    )
    plan(robot, problem.scene, start, near, seed=0, time_limit=0.05, verify=False)


def _reference_us() -> float:
    """The reference loop ``sum(range(1000))``, best of 5 [µs]."""
    return 1e6 * min(timeit.repeat("sum(range(1000))", number=1000, repeat=5)) / 1000


# --- statistics and tables ------------------------------------------------

#: Planner keys of a record, and their names in the tables.
COLUMNS = {
    "vamp": "VAMP",
    "ompl": "OMPL (Python callback)",
    "workbench": "workbench",
    "workbench_pose": "workbench, pose goal",
    "workbench_ompl": "workbench-ompl (OMPL RRTConnect, our checker)",
}


def summarise(records: list[dict[str, Any]], key: str) -> dict[str, Any] | None:
    """Solved count and time/length statistics of planner ``key`` [s, rad].

    Times are over the solved problems; ``length_ratio`` is the median over
    the problems both ``key`` and VAMP solved of the length ratio; the
    exact-mesh counts over every path checked (a plan refused for a contact
    too).
    """
    runs = [(r, r[key]) for r in records if key in r]
    if not runs:
        return None
    solved = [(r, run) for r, run in runs if run["solved"]]
    plan = [run["planning_time"] for _, run in solved]
    simplify = [run["simplification_time"] for _, run in solved]
    total = [p + s for p, s in zip(plan, simplify, strict=True)]
    ratios = [
        run["length"] / r["vamp"]["length"]
        for r, run in solved
        if "vamp" in r and r["vamp"]["solved"] and r["vamp"]["length"] > 0
    ]
    out: dict[str, Any] = {
        "tried": len(runs),
        "solved": len(solved),
        "plan_median": _quantile(plan, 0.5),
        "plan_p95": _quantile(plan, 0.95),
        "plan_max": max(plan, default=math.nan),
        "simplify_median": _quantile(simplify, 0.5),
        "setup_median": _quantile(
            [run["extra"].get("setup_time", math.nan) for _, run in solved], 0.5
        ),
        "total_median": _quantile(total, 0.5),
        "length_ratio": _quantile(ratios, 0.5),
    }
    checked = [run["extra"] for _, run in runs if "contacts" in run["extra"]]
    if checked:
        out["verified"] = len(checked)
        out["with_contacts"] = sum(1 for c in checked if c["contacts"])
        out["contacts"] = sum(c["contacts"] for c in checked)
        out["verify_median"] = _quantile([c["verify_time"] for c in checked], 0.5)
        out["verify_max"] = max(c["verify_time"] for c in checked)
    return out


def _quantile(values: Sequence[float], q: float) -> float:
    if not values:
        return math.nan
    return float(np.quantile(np.asarray(values, dtype=float), q))


def _ratio(a: float, b: float) -> str:
    return "–" if math.isnan(a) or math.isnan(b) or b == 0 else f"{a / b:.2f}"


def scenario_groups(records: list[dict[str, Any]]) -> Iterator[tuple[str, list]]:
    """``(scenario, records)`` per scenario in order, then ``("all", records)``."""
    names = list(dict.fromkeys(r["scenario"] for r in records))
    for name in names:
        yield name, [r for r in records if r["scenario"] == name]
    yield "all", records


def format_tables(result: dict[str, Any], time_limit: float) -> str:
    """The markdown tables of one robot's run."""
    name, records = result["robot"], result["problems"]
    before, after = result["reference_us"]
    lines = [
        f"### {name}",
        "",
        f"Reference loop `sum(range(1000))`: {before:.1f} µs before, "
        f"{after:.1f} µs after. Times over the solved problems; time limit "
        f"{time_limit:g} s per problem (OMPL, workbench).",
        "",
        "| scenario | valid (exact) | valid (VAMP) | planner | solved | plan median "
        "| plan p95 | plan max | simplify median | total median | length / VAMP "
        "| setup median |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    ratios = [
        "| scenario | workbench / VAMP | OMPL / workbench | OMPL / VAMP "
        "| workbench-ompl / workbench |",
        "| --- | --- | --- | --- | --- |",
    ]
    verify = [
        "| scenario | planner | checked | with contacts | contacts | check median "
        "| check max |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    for scenario, group in scenario_groups(records):
        valid = sum(r["valid"]["valid"] for r in group)
        vamp_valid = sum(bool(r.get("vamp_valid")) for r in group)
        vamp_text = str(vamp_valid) if any("vamp_valid" in r for r in group) else "–"
        stats = {key: summarise(group, key) for key in COLUMNS}
        first = True
        for key, label in COLUMNS.items():
            s = stats[key]
            if s is None:
                continue
            head = (
                f"| {scenario} | {valid}/{len(group)} | {vamp_text}/{len(group)}"
                if first
                else "| | |"
            )
            first = False
            lines.append(
                f"{head} | {label} | {s['solved']}/{s['tried']} "
                f"| {format_time(s['plan_median'])} | {format_time(s['plan_p95'])} "
                f"| {format_time(s['plan_max'])} "
                f"| {format_time(s['simplify_median'])} "
                f"| {format_time(s['total_median'])} "
                f"| {'–' if key == 'vamp' else _fmt(s['length_ratio'])} "
                f"| {format_time(s['setup_median'])} |"
            )
            if "verified" in s:
                verify.append(
                    f"| {scenario} | {label} "
                    f"| {s['verified']} | {s['with_contacts']} | {s['contacts']} "
                    f"| {format_time(s['verify_median'])} "
                    f"| {format_time(s['verify_max'])} |"
                )
        if first:
            lines.append(f"| {scenario} | {valid}/{len(group)} | {vamp_text} | – |")
        median = {
            k: math.nan if s is None else s["plan_median"] for k, s in stats.items()
        }
        ratios.append(
            f"| {scenario} | {_ratio(median['workbench'], median['vamp'])} "
            f"| {_ratio(median['ompl'], median['workbench'])} "
            f"| {_ratio(median['ompl'], median['vamp'])} "
            f"| {_ratio(median['workbench_ompl'], median['workbench'])} |"
        )
    lines += ["", "Ratios of the median planning times:", "", *ratios]
    if len(verify) > 2:
        lines += [
            "",
            "Exact-mesh check of the paths (coal, joint steps <= 0.25°, proven "
            "between the samples; VAMP: its simplified polyline, the workbench: its "
            "trajectory):",
            "",
            *verify,
        ]
    invalid = [r for r in records if not r["valid"]["valid"]]
    if invalid:
        lines += [
            "",
            "Invalid on the exact meshes (left out of every planner's statistics):",
            "",
            "| scenario | problem | in collision | closest pair | distance |",
            "| --- | --- | --- | --- | --- |",
        ]
        for r in invalid:
            v = r["valid"]
            lines.append(
                f"| {r['scenario']} | {r['index']} | {v['where']} "
                f"| {v['body_a']} – {v['body_b']} | {1e3 * v['distance']:.2f} mm |"
            )
    lines += _disagreements(records)
    return "\n".join(lines)


def _disagreements(records: list[dict[str, Any]]) -> list[str]:
    """Problems valid on the exact meshes that VAMP's spheres call invalid, and
    the valid problems a planner left unsolved, with why."""
    lines = []
    spheres = [
        r for r in records if r["valid"]["valid"] and r.get("vamp_valid") is False
    ]
    if spheres:
        lines += [
            "",
            "Valid on the exact meshes, invalid for VAMP's spheres (`validate` of the "
            "start or the goal):",
            "",
            "| scenario | problem | exact clearance | closest pair | VAMP solved |",
            "| --- | --- | --- | --- | --- |",
        ]
        for r in spheres:
            v = r["valid"]
            solved = r["vamp"]["solved"] if "vamp" in r else "–"
            lines.append(
                f"| {r['scenario']} | {r['index']} | {1e3 * v['distance']:.2f} mm "
                f"| {v['body_a']} – {v['body_b']} | {solved} |"
            )
    unsolved = []
    for r in records:
        for key, label in COLUMNS.items():
            run = r.get(key)
            if run is None or run["solved"]:
                continue
            if key in ("vamp", "ompl") and r.get("vamp_valid") is False:
                why = "start or goal invalid for VAMP's spheres"
            else:
                why = str(run["extra"].get("status", "no path"))
                why += f" after {format_time(run['planning_time'])}"
            unsolved.append(f"| {label} | {r['scenario']} | {r['index']} | {why} |")
    if unsolved:
        lines += [
            "",
            "Valid problems left unsolved:",
            "",
            "| planner | scenario | problem | why |",
            "| --- | --- | --- | --- |",
            *unsolved,
        ]
    return lines


def _fmt(value: float) -> str:
    return "–" if math.isnan(value) else f"{value:.2f}"


def _parse_list(text: str, allowed: Sequence[str], what: str) -> list[str]:
    items = [s.strip() for s in text.split(",") if s.strip()]
    unknown = [s for s in items if s not in allowed]
    if unknown or not items:
        raise argparse.ArgumentTypeError(
            f"unknown {what} {', '.join(unknown) or '(none)'}; "
            f"choose from {', '.join(allowed)}"
        )
    return items


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--robots",
        type=lambda s: _parse_list(s, ROBOTS, "robot"),
        default=list(ROBOTS),
    )
    parser.add_argument(
        "--scenarios",
        type=lambda s: _parse_list(s, SCENARIOS, "scenario"),
        default=list(SCENARIOS),
    )
    parser.add_argument(
        "--planners",
        type=lambda s: _parse_list(s, PLANNERS, "planner"),
        default=list(PLANNERS),
    )
    parser.add_argument(
        "--verify",
        type=lambda s: _parse_list(s, ("workbench", "vamp", "none"), "planner"),
        default=["workbench"],
        help="whose paths to check on the exact meshes (vamp: slow on the UR5)",
    )
    parser.add_argument("--limit", type=int, default=None, help="problems per scenario")
    parser.add_argument("--time-limit", type=float, default=1.0, help="[s]")
    parser.add_argument("--sdist", type=Path, default=None)
    parser.add_argument(
        "--cache", type=Path, default=Path.home() / ".cache" / "workbench-bench"
    )
    parser.add_argument("--json", type=Path, default=None, help="write the records")
    args = parser.parse_args(argv)
    from workbench.progress import Progress

    resources = extract_resources(get_sdist(args.cache, args.sdist), args.cache)
    results = []
    for name in args.robots:
        with Progress(f"MotionBenchMaker {name}", delay=0.0) as progress:
            results.append(run_robot(name, resources, args, progress.count))
    print(
        f"## MotionBenchMaker ({', '.join(args.robots)}), planners "
        f"{', '.join(args.planners)}"
    )
    for result in results:
        print()
        print(format_tables(result, args.time_limit))
    if args.json is not None:
        summary = {
            r["robot"]: {
                scenario: {k: summarise(group, k) for k in COLUMNS}
                for scenario, group in scenario_groups(r["problems"])
            }
            for r in results
        }
        document = {"arguments": vars(args), "summary": summary, "robots": results}
        args.json.write_text(json.dumps(document, indent=1, default=str) + "\n")


if __name__ == "__main__":
    main()
