"""Many motions at once: in this process with a progress count, or on a Dask cluster.

:func:`plan_many` plans a list of requests (a cell's task list, a benchmark)
with :func:`~workbench.motion.plan`; :func:`run_many` is the runner under it
and under :func:`~workbench.motion.run_problems`. Without a scheduler the
items run one after the other in this process, so that the times measured
are those of one core with nothing beside it. With a scheduler address they
run on that cluster (:func:`workbench._dask.connect`): the robot and the
options are sent once to every worker, each item is one task, and the results
come back in the order of the items. Each process plans one untimed motion
first (the robot's spheres built, the compiled kernels loaded), so that no
item's planning time includes them.
"""

from __future__ import annotations

import uuid
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench._dask import check_scheduler, connect
from workbench.collision import Scene
from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.motion.planner import MotionPlan, plan
from workbench.progress import ProgressCallback

Item = TypeVar("Item")
Result = TypeVar("Result")
#: Seconds of the untimed warm-up plan of each process.
WARM_UP_TIME_LIMIT = 0.05
#: ``(scene, start, goal)``: one request of :func:`plan_many`.
Request = tuple[Scene | None, npt.ArrayLike, "npt.ArrayLike | pin.SE3"]


@dataclass(slots=True, eq=False)
class Planner:
    """The robot and :func:`~workbench.motion.plan`'s options, shared by the tasks.

    Calling it plans one request; the first call in a process first plans an
    untimed one (:data:`WARM_UP_TIME_LIMIT`, no exact check) from the same
    start and goal, so that building the spheres and loading the kernels is
    timed in no result.
    """

    robot: Robot
    options: dict[str, Any]
    warm: bool = field(default=False, compare=False)

    def __call__(
        self, scene: Scene | None, start: npt.ArrayLike, goal: Any
    ) -> MotionPlan:
        """:func:`~workbench.motion.plan` of one request with the options."""
        if not self.warm:
            self.warm = True
            options = {**self.options, "verify": False}
            options["time_limit"] = WARM_UP_TIME_LIMIT
            plan(self.robot, scene, start, goal, **options)
        return plan(self.robot, scene, start, goal, **self.options)


def plan_options(
    seed: int, time_limit: float, iteration_limit: int, planner: str, verify: bool
) -> dict[str, Any]:
    """The keyword arguments of :func:`~workbench.motion.plan` a Planner passes on."""
    return {
        "seed": seed,
        "time_limit": time_limit,
        "iteration_limit": iteration_limit,
        "planner": planner,
        "verify": verify,
    }


def plan_many(
    robot: Robot,
    requests: Iterable[Request],
    *,
    seed: int = 0,
    time_limit: float = 1.0,
    iteration_limit: int = 100_000,
    planner: str = "rrtconnect",
    verify: bool = True,
    scheduler: str | None = None,
    progress: ProgressCallback | None = None,
) -> list[MotionPlan]:
    """:func:`~workbench.motion.plan` of every request, here or on a Dask cluster.

    Args:
        robot: The robot, with acceleration limits.
        requests: ``(scene, start, goal)`` each: the scene (obstacles in the
            base frame, or None), the start (nq,) [rad] and the goal (a
            configuration (nq,), several (M, nq) or a tool pose).
        seed: Seed of every plan (each request is planned from it, so a
            result does not depend on the others or on where it ran).
        time_limit: Planning budget of each request [s].
        iteration_limit: RRT-Connect iterations of each request at most.
        planner: ``"rrtconnect"`` or ``"ompl:NAME"`` (:func:`plan`).
        verify: Check each trajectory on the exact meshes.
        scheduler: A Dask scheduler address (``tcp://HOST:PORT``), or None
            to plan in this process, one request after the other.
        progress: Called as ``progress(done, total)`` after each request.

    Returns:
        One plan per request, in their order.

    Raises:
        InputError: A request is not a ``(scene, start, goal)`` triple, the
            scheduler cannot be reached or has no worker, or :func:`plan`
            refuses its arguments.
    """
    items = []
    for k, request in enumerate(requests):
        if not isinstance(request, tuple | list) or len(request) != 3:
            raise InputError(
                f"request {k} must be a (scene, start, goal) triple, got {request!r}"
            )
        scene, start, goal = request
        if not isinstance(goal, pin.SE3):
            goal = np.asarray(goal, dtype=np.float64)
        items.append((scene, np.asarray(start, dtype=np.float64), goal))
    options = plan_options(seed, time_limit, iteration_limit, planner, verify)
    return run_many(
        _plan_request,
        Planner(robot, options),
        items,
        scheduler=scheduler,
        progress=progress,
    )


def _plan_request(planner: Planner, item: tuple[Any, Any, Any]) -> MotionPlan:
    return planner(*item)


def run_many(
    task: Callable[[Any, Item], Result],
    shared: Any,
    items: Sequence[Item],
    *,
    scheduler: str | None = None,
    progress: ProgressCallback | None = None,
) -> list[Result]:
    """``task(shared, item)`` for every item, in order here or on a cluster.

    Args:
        task: A picklable (module-level) function.
        shared: Its first argument, sent once to each worker.
        items: Its second arguments (picklable).
        scheduler: A Dask scheduler address, or None for this process.
        progress: Called as ``progress(done, total)`` after each item.

    Returns:
        The results, in the order of ``items``.

    Raises:
        InputError: If the scheduler cannot be reached or has no worker.
        Exception: The first exception a task raised (the others are
            cancelled).
    """
    total = len(items)
    if scheduler is None:
        results = []
        for item in items:
            results.append(task(shared, item))
            if progress is not None:
                progress(len(results), total)
        return results
    address = check_scheduler(scheduler)
    if not items:
        return []
    from distributed import as_completed

    out: dict[int, Result] = {}
    with connect(address) as client:
        handle = client.scatter(shared, broadcast=True, hash=False)
        prefix = f"motion-{uuid.uuid4().hex}"
        futures = {
            client.submit(task, handle, item, key=f"{prefix}-{k}", pure=False): k
            for k, item in enumerate(items)
        }
        try:
            for future in as_completed(futures, loop=client.loop):
                out[futures[future]] = future.result()
                if progress is not None:
                    progress(len(out), total)
        finally:
            client.cancel(list(futures))
    return [out[k] for k in range(total)]
