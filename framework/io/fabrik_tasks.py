"""Reach task files: position targets for a mobile manipulator, solved by M-FABRIK or its Jacobian baselines.

A task file with a ``[reach]`` table is a reach task (``metaik run`` solves it with :func:`run_reach_task`)::

    [task]
    name = "paper003_square"
    robot = "youbot_mobile"          # an arm on a planar base (joint group "base")
    frame = "arm_ee"                 # optional: the end-effector (default: the robot's first)

    [solver]
    name = "mfabrik"                 # "mfabrik", "pinv" or "dls"
    tolerance = 1e-3                 # success threshold on the position error [m]
    max_iterations = 1000
    seed = 0                         # random targets and starts

    [reach]
    orientation = "follow_joint1"    # base heading rule: "face_target", "follow_joint1" or "fixed"
    step = 0.1                       # optional: Algorithm 2's ρ [m] between consecutive base positions
    start = { base = [-1.3, -0.6, 0], arm = [0, "pi/6", "-pi/3", "pi/6", 0] }   # or random starts (below)
    random = 1000                    # either: this many random targets (FK of random configurations), each
                                     #         from its own random start (paper 003 Tables 2-3)
    [reach.trajectory]               # or: a path of set-points (any [trajectory] type of the task-file format),
    type = "sinusoid"                #     each solve warm-started from the previous one
    ...
    [reach.environment]              # optional obstacles in the floor plane
    margin = 0.2                     # safety margin [m] (the rejection area is the obstacles dilated by it)
    bounds = [[-1.5, 1.5], [-1.5, 1.5]]   # navigable box [m]
    obstacles = [
      { type = "rectangle", centre = [0, 0], size = [0.4, 0.4], angle = 0 },
      { type = "circle", centre = [0.9, 0.8], radius = 0.15 },
      { type = "polygon", points = [[0, 0], [1, 0], [0, 1]] },
    ]

Numbers may be expressions (``"pi/6"``), as everywhere in task files.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..solvers.baselines.solver import BUSS
from ..costs import Position
from ..errors import TaskError
from ..costs.problem import Problem
from ..model.robot import Robot
from ..geometry.scene import Scene
from ..solvers.solve import IKResult, solve
from ..solvers.registry import ik_solver
from .task_values import robot_of_task, evaluate, trajectory_from_table
from ..tracking import TrackingResult, TrackingTask, track
from ..tracking.trajectory import Trajectory
from ..solvers.fabrik.environment import Circle, Environment, Polygon, Rectangle
from ..solvers.fabrik.mfabrik import MFabrik
from ..solvers.fabrik.mobile import BaseOrientation
from ..solvers.fabrik.steps import Steps, algorithm2

#: Solvers of reach tasks.
REACH_SOLVERS = ("mfabrik", "pinv", "dls")
REACH_KEYS = {"orientation", "step", "start", "random", "trajectory", "environment"}
SOLVER_KEYS = {"name", "tolerance", "max_iterations", "seed"}
ENVIRONMENT_KEYS = {"margin", "bounds", "obstacles"}
OBSTACLE_KEYS = {"circle": {"centre", "radius"}, "rectangle": {"centre", "size", "angle"}, "polygon": {"points"}}


@dataclass(frozen=True)
class ReachTask:
    """A parsed reach task file.

    Attributes:
        path, name, description: the file, its ``[task]`` name and description.
        robot: the mobile manipulator; ``frame`` its end-effector.
        solver: ``name``, ``tolerance`` [m], ``max_iterations``, ``seed``.
        orientation: the base heading rule of M-FABRIK.
        step: Algorithm 2's ρ [m], or None (M-FABRIK only: the Jacobian baselines solve the same set-points
            without it, see :func:`run_reach_task`).
        environment: obstacles, margin and navigable box (None: free floor).
        start: the start configuration ``(n,)`` (None with random starts).
        targets: set-points ``(m, 3)`` [m] of a path, or None for random targets.
        random: number of random targets (0 for a path).
    """

    path: Path
    name: str
    description: str
    robot: Robot
    frame: str
    solver: dict[str, Any]
    orientation: BaseOrientation
    step: float | None
    environment: Environment | None
    start: np.ndarray | None
    targets: np.ndarray | None
    random: int

    @property
    def is_path(self) -> bool:
        return self.targets is not None

    def solver_options(self, name: str, options: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """The options of reach solver ``name``: the baselines' :data:`~framework.solvers.baselines.solver.BUSS`, M-FABRIK's
        base orientation and environment from the task; ``options`` added."""
        if name not in REACH_SOLVERS:
            raise TaskError(f"unknown reach solver {name!r}; reach tasks are solved by {list(REACH_SOLVERS)}")
        chosen = dict(BUSS.__dict__) if name != "mfabrik" else {"orientation": self.orientation.value,
                                                                 "environment": self.environment}
        return {**chosen, **(options or {})}

    def planner(self) -> MFabrik:
        """The M-FABRIK planner of Algorithm 2's steps: the ``mfabrik`` solver's, with the task's environment and base
        orientation (built once per robot and options)."""
        return ik_solver("mfabrik", self.solver_options("mfabrik")).planner(self.robot, self.frame)[1]

    def solve_function(self, name: str | None = None, *, options: Mapping[str, Any] | None = None,
                       seed: int | None = None) -> Callable[..., IKResult]:
        """``solve(target, x0, tolerance=, max_iterations=)``: the chosen solver through :func:`framework.solve` on
        one reach problem (a :class:`~framework.costs.Position` term, its target moved to each call), with
        :meth:`solver_options`; ``seed`` replaces the task's."""
        name = name or self.solver["name"]
        chosen = ik_solver(name, self.solver_options(name, options)).options  # checked once, passed as they are
        term = Position(self.frame, np.zeros(3))
        problem = Problem(self.robot, 1.0 * term)
        seed = self.solver["seed"] if seed is None else seed

        def call(target: np.ndarray, x0: np.ndarray, *, tolerance: float, max_iterations: int) -> IKResult:
            term.set_target(target)
            return solve(problem, name, initial=x0, tolerance=tolerance, max_iterations=max_iterations,
                         options=chosen, seed=seed)

        return call

    def random_pairs(self) -> tuple[np.ndarray, np.ndarray]:
        """``(targets (k, 3) [m], starts (k, n))``: FK of random configurations, and random starts (seeded)."""
        rng = np.random.default_rng(self.solver["seed"])
        X = self.robot.random_configurations(rng, self.random)
        targets = self.robot.frame_poses(X, self.frame).positions[:, 0]
        return targets, self.robot.random_configurations(rng, self.random)


@dataclass(frozen=True)
class ReachRun:
    """What :func:`run_reach_task` returns.

    Attributes:
        task, solver: what ran.
        targets: ``(k, 3)`` [m] the targets, in order.
        results: one :class:`~framework.solvers.solve.IKResult` per target.
        path: a path's :class:`~framework.tracking.TrackingResult` (``tracking.track``), or None.
        steps: Algorithm 2's steps before each set-point of a path (M-FABRIK with a step ``ρ``), or None.
    """

    task: ReachTask
    solver: str
    targets: np.ndarray
    results: tuple[IKResult, ...]
    path: TrackingResult | None = None
    steps: tuple[Steps, ...] | None = None

    @property
    def configurations(self) -> np.ndarray:
        """``(k, n)`` the configuration reached for each target."""
        return np.array([r.configuration for r in self.results]).reshape(-1, self.task.robot.n)

    @property
    def iterations(self) -> np.ndarray:
        """``(k,)`` each solve's iterations."""
        return np.array([r.iterations for r in self.results], dtype=int)

    @property
    def wall_times(self) -> np.ndarray:
        """``(k,)`` [s] each solve's wall-clock time."""
        return np.array([r.wall_time for r in self.results])

    @property
    def position_errors(self) -> np.ndarray:
        """``(k,)`` [m] each target's position error, by Pinocchio's forward kinematics."""
        reached = self.task.robot.frame_poses(self.configurations, self.task.frame).positions[:, 0]
        return np.linalg.norm(reached - self.targets[: len(reached)], axis=1)

    @property
    def success_rate(self) -> float:
        """The fraction of targets reached."""
        return float(np.mean([r.success for r in self.results])) if self.results else float("nan")

    @property
    def success(self) -> bool:
        """Every target reached and every base transition planned."""
        return all(r.success for r in self.results) and all(s.success for s in self.steps or ())

    @property
    def base_positions(self) -> np.ndarray:
        """``(k, 2)`` [m] every base position the run visits: each solution and every intermediate configuration."""
        points = [r.configuration[list(self.task.robot.groups["base"][:2])] for r in self.results]
        points += [b[:2] for s in self.steps or () for b in s.bases]
        return np.array(points).reshape(-1, 2)


def is_reach_task(raw: Mapping[str, Any]) -> bool:
    """True for a task file dictionary with a ``[reach]`` table."""
    return "reach" in raw


def reach_task_from_dict(raw: Mapping[str, Any], path: Path, *, points: int | None = None) -> ReachTask:
    """A :class:`ReachTask` from a parsed TOML dictionary (``path`` locates relative robot and path files)."""
    task = raw.get("task")
    if not isinstance(task, dict) or "robot" not in task:
        raise TaskError("[task] needs a robot (index name or file path)")
    robot = robot_of_task(task, path)
    if "base" not in robot.groups:
        raise TaskError(f"robot {robot.name} has no joint group 'base': reach tasks need a mobile base")
    frame = str(task.get("frame", robot.end_effectors[0] if robot.end_effectors else ""))
    robot.frame_id(frame)  # raises UnknownFrameError naming close matches
    solver = _check_keys(dict(raw.get("solver", {})), SOLVER_KEYS, "[solver]")
    solver = {"name": "mfabrik", "tolerance": 1e-3, "max_iterations": 1000, "seed": 0, **solver}
    if solver["name"] not in REACH_SOLVERS:
        raise TaskError(f"[solver] name {solver['name']!r}: reach tasks are solved by {list(REACH_SOLVERS)}")
    if not (float(solver["tolerance"]) > 0):
        raise TaskError(f"[solver] tolerance must be > 0 [m]; got {solver['tolerance']}")
    reach = _check_keys(dict(raw["reach"]), REACH_KEYS, "[reach]")
    try:
        orientation = BaseOrientation(reach.get("orientation", "follow_joint1"))
    except ValueError as err:
        raise TaskError(f"[reach] orientation must be one of {[o.value for o in BaseOrientation]}; "
                        f"got {reach.get('orientation')!r}") from err
    step = float(evaluate(reach["step"], {}, "[reach] step")) if "step" in reach else None
    if step is not None and not step > 0:
        raise TaskError(f"[reach] step must be > 0 [m]; got {step}")
    if ("random" in reach) == ("trajectory" in reach):
        raise TaskError("[reach] needs either random = N (random targets) or a [reach.trajectory] path")
    targets, random = None, 0
    if "random" in reach:
        random = int(reach["random"])
        if random < 1 or random != reach["random"]:
            raise TaskError(f"[reach] random must be a positive integer; got {reach['random']!r}")
        if points is not None:
            random = points
    else:
        targets = trajectory_from_table(reach["trajectory"], {}, path, points, "[reach.trajectory]").positions
    start = _start(reach.get("start"), robot) if "start" in reach else None
    if targets is not None and start is None:
        raise TaskError("[reach] a path needs a start configuration (start = { base = [...], arm = [...] })")
    environment = _environment(reach["environment"]) if "environment" in reach else None
    if "obstacles" in raw:  # [[obstacles]], as IK task files give them: their shadows on the floor
        scene = Scene.from_tables(raw["obstacles"], "[[obstacles]]", path.parent)
        base = environment or Environment()
        environment = Environment.from_scene(scene, margin=base.margin, bounds=base.bounds, obstacles=base.obstacles)
    return ReachTask(path, str(task.get("name", path.stem)), str(task.get("description", "")), robot, frame,
                     solver, orientation, step, environment, start, targets, random)


def run_reach_task(task: ReachTask, *, solver: str | None = None, progress: Callable[[int, int], None] | None = None,
                   ) -> ReachRun:
    """Solve every target of ``task``: random pairs one :func:`framework.solve` each, a path by
    :func:`framework.tracking.track` (each set-point from the previous solution) and, for M-FABRIK with a step
    ``ρ``, Algorithm 2's steps between consecutive solutions."""
    name = solver or task.solver["name"]
    tolerance, cap = float(task.solver["tolerance"]), int(task.solver["max_iterations"])
    if task.is_path:
        results: list[IKResult] = []

        def keep(k: int, result: IKResult) -> None:
            results.append(result)
            if progress is not None:
                progress(k + 1, len(task.targets))

        path = track(task.robot, Trajectory.from_array(task.targets, task.name),
                     TrackingTask(frame=task.frame, motion={}), solver=name, seed=task.solver["seed"],
                     max_iterations=cap, initial=task.start, tolerance=tolerance, predict=False,
                     options=task.solver_options(name), progress=False, callback=keep)
        steps = None
        if name == "mfabrik" and task.step is not None:
            steps = algorithm2(task.planner(), task.start, path.configurations, task.targets, task.step)
        return ReachRun(task, name, task.targets, tuple(results), path, steps)
    solve_one = task.solve_function(name)
    targets, starts = task.random_pairs()
    if task.start is not None:
        starts[:] = task.start
    results = []
    for k, (target, x0) in enumerate(zip(targets, starts)):
        results.append(solve_one(target, x0, tolerance=tolerance, max_iterations=cap))
        if progress is not None:
            progress(k + 1, len(targets))
    return ReachRun(task, name, targets, tuple(results))


def _check_keys(table: dict[str, Any], known: set[str], where: str) -> dict[str, Any]:
    unknown = set(table) - known
    if unknown:
        raise TaskError(f"{where} has unknown keys {sorted(unknown)}; known: {sorted(known)}")
    return table


def _start(spec: Any, robot: Robot) -> np.ndarray:
    """The start configuration from ``{group = [...], ...}`` (every joint group given) or a full list."""
    if isinstance(spec, list):
        x = np.asarray(evaluate(spec, {}, "[reach] start"), dtype=float).reshape(-1)
    elif isinstance(spec, dict):
        x = np.zeros(robot.n)
        missing = set(robot.groups) - set(spec)
        unknown = set(spec) - set(robot.groups)
        if missing or unknown:
            raise TaskError(f"[reach] start needs every joint group of {robot.name} {sorted(robot.groups)}; "
                            f"missing {sorted(missing)}, unknown {sorted(unknown)}")
        for group, idx in robot.groups.items():
            values = np.asarray(evaluate(spec[group], {}, f"[reach] start.{group}"), dtype=float).reshape(-1)
            if values.size != len(idx):
                raise TaskError(f"[reach] start.{group} needs {len(idx)} values; got {values.size}")
            x[list(idx)] = values
    else:
        raise TaskError("[reach] start must be a table of joint groups or a list of joint coordinates")
    if x.shape != (robot.n,) or not np.all(np.isfinite(x)):
        raise TaskError(f"[reach] start must be {robot.n} finite joint coordinates; got {x.tolist()}")
    return x


def _environment(spec: Any) -> Environment:
    if not isinstance(spec, dict):
        raise TaskError("[reach.environment] must be a table")
    _check_keys(spec, ENVIRONMENT_KEYS, "[reach.environment]")
    obstacles = []
    for i, entry in enumerate(spec.get("obstacles", [])):
        where = f"[reach.environment] obstacle {i + 1}"
        kind = entry.get("type") if isinstance(entry, dict) else None
        if kind not in OBSTACLE_KEYS:
            raise TaskError(f"{where}: type must be one of {sorted(OBSTACLE_KEYS)}; got {kind!r}")
        _check_keys({k: v for k, v in entry.items() if k != "type"}, OBSTACLE_KEYS[kind], where)

        def value(key: str, entry=entry, where=where) -> Any:
            if key not in entry:
                raise TaskError(f"{where} ({entry['type']}) needs {key}")
            return evaluate(entry[key], {}, f"{where} {key}")

        if kind == "circle":
            obstacles.append(Circle(tuple(value("centre")), float(value("radius"))))
        elif kind == "rectangle":
            angle = float(value("angle")) if "angle" in entry else 0.0
            obstacles.append(Rectangle(tuple(value("centre")), tuple(value("size")), angle))
        else:
            obstacles.append(Polygon(tuple(map(tuple, np.asarray(value("points"), dtype=float)))))
    bounds = None
    if "bounds" in spec:
        b = np.asarray(evaluate(spec["bounds"], {}, "[reach.environment] bounds"), dtype=float)
        if b.shape != (2, 2):
            raise TaskError(f"[reach.environment] bounds must be [[xmin, xmax], [ymin, ymax]]; got {b.tolist()}")
        bounds = ((b[0, 0], b[0, 1]), (b[1, 0], b[1, 1]))
    margin = float(evaluate(spec.get("margin", 0.2), {}, "[reach.environment] margin"))
    return Environment(obstacles, margin=margin, bounds=bounds)
