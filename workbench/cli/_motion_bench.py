"""``workbench motion bench``: a MotionBenchMaker problem set, planned and verified.

Finds the problems (:func:`workbench.motion.find_problems`: a
``problems.tar.bz2``, its folder or the ``vamp-planner`` sdist), judges each
one's validity on the exact meshes, plans the valid ones
(:func:`workbench.motion.run_problems`, here or on a Dask cluster) and prints
the table per scenario (:func:`workbench.motion.summarise`). Exit 0 when every
valid problem is solved, 3 when some valid problem is not.
"""

from __future__ import annotations

import argparse
import functools
import math
import sys
from dataclasses import asdict
from pathlib import Path
from typing import Any

from workbench.cli._common import (
    EXIT_INFEASIBLE,
    add_json_flag,
    add_limit_arguments,
    add_robot_argument,
    add_search_arguments,
    bounded_int,
    format_time,
    load_robot_from_args,
    print_json,
)
from workbench.errors import InputError


def register(subcommands: argparse._SubParsersAction) -> None:
    """Add ``motion bench`` to the ``motion`` group."""
    bench = subcommands.add_parser(
        "bench",
        help="plan a MotionBenchMaker problem set and print the table per scenario",
        description="Plan the problems of a MotionBenchMaker set (a problems.tar.bz2, "
        "the folder it unpacks to, or the vamp-planner sdist): each one's start and "
        "goal judged on the exact meshes (valid), the valid ones planned, "
        "time-scaled and checked on the exact meshes, and the table per scenario "
        "printed (valid, solved, planning time median / p95 / max, time scaling, "
        "total, exact-check contacts). Exit 3 when some valid problem is unsolved.",
    )
    bench.add_argument(
        "source",
        type=Path,
        metavar="SOURCE",
        help="problems.tar.bz2, its folder, or the vamp-planner sdist (.tar.gz)",
    )
    add_robot_argument(bench)
    add_limit_arguments(bench)
    bench.add_argument(
        "--robot-name",
        metavar="NAME",
        help="whose problems to take (default: the URDF file's name, e.g. panda)",
    )
    bench.add_argument(
        "--scenario",
        action="append",
        metavar="NAME",
        help="a scenario to run (repeatable; default: every one)",
    )
    bench.add_argument(
        "--limit",
        type=bounded_int(1, 10**9),
        metavar="N",
        help="at most N problems per scenario (the first ones)",
    )
    add_search_arguments(bench, scope="per problem: ", planner=True)
    bench.add_argument(
        "--iteration-limit",
        type=bounded_int(1, 10**9),
        default=100_000,
        metavar="N",
        help="RRT-Connect iterations per problem at most (default: 100000)",
    )
    bench.add_argument(
        "--pose-goal",
        action="store_true",
        help="plan to the goal configuration's tool pose instead",
    )
    bench.add_argument(
        "--no-verify",
        action="store_true",
        help="skip the exact-mesh check of the trajectories",
    )
    bench.add_argument(
        "--scheduler",
        metavar="ADDR",
        help="run the problems on the Dask cluster of this scheduler "
        "(tcp://HOST:PORT; default: here, one after the other)",
    )
    add_json_flag(bench)
    bench.set_defaults(run=run_bench, progress_message="motion bench: planning…")


def run_bench(args: argparse.Namespace) -> int:
    """Find, plan, print; exit 3 when a valid problem is unsolved."""
    from workbench._dask import check_scheduler
    from workbench.motion import find_problems, run_problems, summarise

    scheduler = None if args.scheduler is None else check_scheduler(args.scheduler)
    robot = load_robot_from_args(args)
    name = args.robot_name or Path(args.robot).stem
    try:
        problems = find_problems(
            args.source, robot_name=name, scenarios=args.scenario, limit=args.limit
        )
    except InputError as err:
        if args.robot_name is None and "no problem for robot" in str(err):
            raise InputError(f"{err} (name it with --robot-name)") from None
        raise
    problems[0].read_request(robot)  # the robot's joints are in the requests
    results = run_problems(
        robot,
        problems,
        seed=args.seed,
        planner=args.planner,
        time_limit=args.time_limit,
        iteration_limit=args.iteration_limit,
        pose_goal=args.pose_goal,
        verify=not args.no_verify,
        scheduler=scheduler,
        progress=functools.partial(
            args.progress.count, unit="problems", label="motion bench"
        ),
    )
    args.progress.finish()
    summary = summarise(results)
    unsolved = [r for r in results if r.validity.valid and not r.solved]
    if args.json:
        print_json(
            {
                "robot": robot.name,
                "robot_name": name,
                "source": str(args.source),
                "seed": args.seed,
                "planner": args.planner,
                "time_limit": args.time_limit,
                "iteration_limit": args.iteration_limit,
                "pose_goal": args.pose_goal,
                "verified": not args.no_verify,
                "scheduler": scheduler,
                "summary": [_plain(asdict(s)) for s in summary],
                "problems": [_plain(asdict(r)) for r in results],
                "all_solved": not unsolved,
            }
        )
    else:
        _print_table(name, args, summary, results)
    if unsolved:
        valid = sum(r.validity.valid for r in results)
        print(
            f"workbench: error: {len(unsolved)} of {valid} valid problems unsolved",
            file=sys.stderr,
        )
        return EXIT_INFEASIBLE
    return 0


def _plain(record: dict[str, Any]) -> dict[str, Any]:
    """NaN as null, at any depth (JSON has no NaN)."""
    return {
        key: _plain(value)
        if isinstance(value, dict)
        else None
        if isinstance(value, float) and math.isnan(value)
        else value
        for key, value in record.items()
    }


def _print_table(
    name: str, args: argparse.Namespace, summary: list[Any], results: list[Any]
) -> None:
    print(
        f"{name}: {len(results)} problems of {args.source}, {args.planner}, "
        f"seed {args.seed}, time limit {args.time_limit:g} s"
        + (", pose goals" if args.pose_goal else "")
    )
    head = (
        "scenario", "valid", "solved", "plan median", "plan p95", "plan max",
        "smoothing", "total", "exact check", "with contacts",
    )  # fmt: skip
    rows = [head]
    for s in summary:
        contacts = "–" if not s.verified else f"{s.with_contacts} of {s.verified}"
        rows.append(
            (
                s.scenario,
                f"{s.valid}/{s.problems}",
                f"{s.solved}/{s.valid}",
                format_time(s.planning_median),
                format_time(s.planning_p95),
                format_time(s.planning_max),
                format_time(s.smoothing_median),
                format_time(s.total_median),
                format_time(s.verification_median),
                contacts,
            )
        )
    widths = [max(len(row[k]) for row in rows) for k in range(len(head))]
    for row in rows:
        cells = [cell.ljust(w) for cell, w in zip(row, widths, strict=True)]
        print("  ".join(cells).rstrip())
    for r in results:
        if not r.solved:
            what = "invalid" if not r.validity.valid else "unsolved"
            print(f"{what}: {r.scenario} {r.index}: {r.reason}: {r.detail}")
