"""Declarative task files (TOML): a robot, weighted cost terms, solver settings and the cases to solve.

A task file reads top to bottom like the experiment it describes::

    [task]
    name = "youbot_dual_coordinated_ik"
    robot = "youbot_dual_mobile"          # index name, or a path relative to the task file
    priorities = false                    # the paper's weighted sum decides (default true: the task terms first)

    [solver]
    name = "cmaes"                        # any registered solver, or "hybrid"
    population = 30
    max_iterations = 1000

    [previous]                            # q_prev by joint group; numbers or expressions ("pi/2")
    base = [0, 0, "pi/2"]

    [[terms]]
    type = "position"                     # any term type (framework.costs.TERM_TYPES; docs/taskfile.md lists
                                          # each one's keys)
    frame = "arm1_ee"
    target = "t_e1"                       # an expression over the case's variables
    weight = 1.2

    [[cases]]                             # one IK solve per case; its keys are variables of the expressions
    name = "target 1"
    t_e1 = [0.5, -0.2, 0.45]

**Collisions.** ``self_collision`` and ``obstacles`` terms (optional ``margin`` [m]) keep the robot's links apart
and clear of the ``[[obstacles]]`` entries (``type = "box" | "sphere" | "capsule" | "plane" | "mesh"``, keys in
:data:`framework.geometry.scene.TABLES`); ``[task] srdf`` names an SRDF whose disabled pairs are not checked,
``disabled_collisions = [["link_a", "link_b"], ...]`` lists more such pairs, and ``free_at`` (a configuration, or
a list of them) declares poses collision-free: the pairs in contact there are not checked (see
:class:`~framework.geometry.collision.RobotShape`)::

    [[obstacles]]
    type = "box"                          # a table
    name = "table"
    center = [0.6, 0.0, 0.35]
    size = [0.8, 1.2, 0.05]

Expressions are numbers, vectors (lists), the names of a case's variables, ``pi``, ``+ - * /``,
parentheses and the rotation matrices ``Rx(a)``, ``Ry(a)``, ``Rz(a)``; nothing else is evaluated. Angles are in radians, lengths in metres.

**Trajectory tracking.** A ``[trajectory]`` table turns the task into tracking (``metaik run`` then solves one IK
per waypoint, each warm-started from the previous solution, see :func:`framework.tracking.track`). The terms
are rebuilt at every waypoint with three more variables: ``t`` (waypoint position [m]), ``R`` (its rotation, if
the path has an orientation) and ``k`` (its index); motion terms without ``previous`` measure the motion to the
previous waypoint's solution, and ``[previous]`` is the configuration before the first waypoint::

    [trajectory]
    type = "circle"                       # circle | lemniscate | rose | sinusoid | line | paper000 | file | waypoints
    centre = [0.5, 0.25, 0.45]
    radius = 0.05
    points = 200
    plane = "yz"                          # the circle's plane through the centre (default "yz")
    orientation = "Ry(pi/2)"              # optional: the same rotation at every waypoint

    [[terms]]
    type = "position"
    frame = "arm1_ee"
    target = "t"                          # the waypoint
    [[terms]]
    type = "position"
    frame = "arm2_ee"
    target = "t + t_r"                    # coordinated arm (paper 000 eq. 8); t_r from the case

A case may carry its own ``trajectory`` table (``[cases.trajectory]``), which replaces the top-level one.
``[solver]`` also takes ``warm_start`` (default true) and ``predict`` (Jacobian predictor; default: hybrid only);
``max_iterations`` is the budget of each waypoint's solve. A timed path (``[trajectory] rate = 100`` [Hz] or
``duration = 5`` [s]) may be tracked within the joint limits: ``[solver] velocity_scale = 0.5`` (the URDF's velocity
limits times 0.5) and ``acceleration = 10`` [rad/s²] hold each waypoint to what they allow (those held back lag, and
the result says so), ``retime = true`` instead gives the path the fastest times that keep them.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..geometry.collision import RobotShape
from ..costs import TERM_TYPES, Objective, Program, Term
from ..costs.base import TermEntry
from ..errors import MetaikError, SolverError, TaskError
from .placement import PlacementTask, is_placement_task, placement_task_from_dict
from ..costs.problem import Problem
from ..resources import data_dir
from ..model.robot import Robot
from ..geometry.scene import Scene
from .task_values import ROBOT_KEYS, robot_of_task, evaluate, expression_names, read_toml, trajectory_from_table
from ..tracking.trajectory import Trajectory
from ..solvers.registry import ik_solver
from ..solvers.settings import DEFAULTS
from ..solvers.solve import check_settings
from ..validate import check_table

#: Keys of ``[task]``, and the top-level tables of an IK / tracking task file.
#: ``[task]`` keys and the kind of their values (:data:`framework.validate.KINDS`).
TASK_KEYS = {"name": "text", "description": "text", "priorities": "bool", "srdf": "text",
             "disabled_collisions": "list", "free_at": "list", **ROBOT_KEYS}
TABLES = {"task", "solver", "previous", "terms", "cases", "trajectory", "bench", "obstacles"}
#: ``[solver]`` keys and the kind of their values.
SOLVER_KEYS = {"name": "text", "population": "integer", "max_iterations": "integer", "tolerance": "number",
               "seed": "integer", "bounds": "text", "options": "table", "stop_at_tolerance": "bool",
               "warm_start": "bool", "predict": "bool", "velocity_scale": "number", "acceleration": "number",
               "retime": "bool"}
#: Variables a tracking task defines at every waypoint.
WAYPOINT_VARIABLES = ("t", "R", "k")
@dataclass(frozen=True)
class Case:
    """One IK solve of a task file: its name, problem and variables.

    For a tracking task also: ``trajectory`` (the waypoints), ``builder`` (the terms of waypoint ``k``, see
    :data:`framework.tracking.TaskBuilder`) and ``initial`` (``(n,)`` the configuration before the first
    waypoint); ``problem`` is then the problem of the first waypoint.
    """

    name: str
    problem: Problem
    variables: dict[str, Any] = field(default_factory=dict)
    trajectory: Trajectory | None = None
    builder: Callable[..., Objective] | None = field(default=None, repr=False)
    initial: np.ndarray | None = field(default=None, repr=False)

    @property
    def is_tracking(self) -> bool:
        return self.trajectory is not None


@dataclass(frozen=True)
class TaskFile:
    """A parsed task file."""

    path: Path
    name: str
    description: str
    robot: Robot
    solver: dict[str, Any]
    cases: tuple[Case, ...]
    raw: dict[str, Any] = field(repr=False, default_factory=dict)
    priorities: bool = True
    scene: Scene = field(default_factory=Scene)

    @property
    def is_tracking(self) -> bool:
        """True for a trajectory-tracking task (a ``[trajectory]`` table, top level or per case)."""
        return any(c.is_tracking for c in self.cases)


def resolve_task(name: str) -> Path:
    """A task file path from a path or the name of a shipped task."""
    path = Path(name)
    if path.is_file():
        return path
    shipped = data_dir("tasks") / (name if name.endswith(".toml") else f"{name}.toml")
    if shipped.is_file():
        return shipped
    raise TaskError(f"task file {name} does not exist (and is not a shipped task: see `metaik tasks`)")


def load_task(path: str | Path, *, points: int | None = None) -> TaskFile | PlacementTask:
    """Parse and validate a task file; every error names the file and the entry at fault.

    A file with a ``[placement]`` table is a base-placement task (:class:`framework.io.placement.PlacementTask`);
    every other one (IK, tracking, M-FABRIK's reach and paths) a :class:`TaskFile`.

    ``points`` overrides the number of waypoints of a tracking task (parametric paths are re-sampled, paths
    from files or lists keep ``points`` evenly spaced waypoints).
    """
    path = Path(path)
    raw = read_toml(path)
    try:
        if is_placement_task(raw):  # where a mobile base should stand
            return placement_task_from_dict(raw, path)
        return _parse(path, raw, points=points)
    except MetaikError as err:
        if str(path) in str(err):
            raise
        raise type(err)(f"{path}: {err}") from err


def task_from_dict(raw: dict[str, Any], path: str | Path, *, points: int | None = None) -> TaskFile:
    """A task from an already-read TOML dictionary; ``path`` locates relative robot and trajectory files."""
    return _parse(Path(path), raw, points=points)


def _parse(path: Path, raw: dict[str, Any], *, points: int | None = None) -> TaskFile:
    task = _table(raw, "task", path)
    unknown_tables = sorted(set(raw) - TABLES)
    if "reach" in unknown_tables:
        raise TaskError("[reach] tables are no more: an M-FABRIK task is an ordinary task file ([solver] name = "
                        "\"mfabrik\" with [solver.options], [previous] the start, a [trajectory], [[terms]] and "
                        "[[obstacles]]; see tasks/paper003_*.toml)")
    if unknown_tables:
        raise TaskError(f"unknown tables {unknown_tables}; known: {sorted(TABLES)} (and [placement] "
                        "for a base-placement task)")
    check_table(task, TASK_KEYS, "[task]")
    if "robot" not in task:
        raise TaskError("[task] needs a robot (index name or file path)")
    robot = robot_of_task(task, path)
    solver = dict(_table(raw, "solver", path, required=False))
    check_table(solver, SOLVER_KEYS, "[solver]")
    _check_solver(solver)
    terms = _tables(raw, "terms")
    if not terms:
        raise TaskError("a task needs at least one [[terms]] entry")
    cases_raw = _tables(raw, "cases") or [{"name": task.get("name", path.stem)}]
    cases = []
    bounds = solver.get("bounds", "resample")
    priorities = task.get("priorities", True)
    if not isinstance(priorities, bool):
        raise TaskError(f"[task] priorities must be true or false; got {priorities!r}")
    world = _World(robot, path, task.get("srdf"), _tables(raw, "obstacles"), task.get("disabled_collisions", ()),
                   task.get("free_at"))
    for i, case in enumerate(cases_raw):
        variables = {k: v for k, v in case.items() if k not in ("name", "trajectory")}
        name = str(case.get("name", f"case {i + 1}"))
        previous = _previous(robot, _table(raw, "previous", path, required=False), variables, path)
        spec = case.get("trajectory", raw.get("trajectory"))
        if spec is None:
            objective = _objective(robot, terms, variables, previous, world)
            cases.append(Case(name, Problem(robot, objective, bounds=bounds, priorities=priorities), variables))
            continue
        reserved = sorted(set(variables) & set(WAYPOINT_VARIABLES))
        if reserved:
            raise TaskError(f"case {name!r}: {reserved} are waypoint variables of a tracking task; rename them")
        trajectory = trajectory_from_table(spec, variables, path, points, f"case {name!r}: trajectory")
        _check_uses_waypoint(terms)
        builder = _TermsAtWaypoint(robot, terms, variables, world)
        first = builder(0, trajectory.positions[0], trajectory.rotation(0), previous)
        cases.append(Case(name, Problem(robot, first, bounds=bounds, priorities=priorities), variables, trajectory,
                          builder, previous))
    return TaskFile(path, task.get("name", path.stem), task.get("description", ""), robot, solver, tuple(cases), raw,
                    priorities, world.scene)


def _check_solver(solver: Mapping[str, Any]) -> None:
    """The ``[solver]`` table's name, options and settings, checked as a solve checks them (once, here: a bad one
    is a :class:`TaskError` naming it before anything runs)."""
    try:
        ik_solver(solver.get("name", DEFAULTS.solver), solver.get("options"))
        check_settings(**{k: solver[k] for k in ("seed", "tolerance", "max_iterations", "population") if k in solver})
    except SolverError as err:
        raise TaskError(f"[solver] {err}") from None


def _table(raw: Mapping, key: str, path: Path, *, required: bool = True) -> dict:
    if key not in raw:
        if required:
            raise TaskError(f"missing [{key}] table")
        return {}
    if not isinstance(raw[key], dict):
        raise TaskError(f"{key} must be a [{key}] table; got {raw[key]!r}")
    return raw[key]


def _tables(raw: Mapping, key: str) -> list[dict]:
    """The array of tables ``[[key]]`` (empty if absent)."""
    value = raw.get(key, [])
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        raise TaskError(f"{key} must be an array of tables ([[{key}]] entries); got {value!r}")
    return value


def _previous(robot: Robot, table: Mapping[str, Any], variables: Mapping, path: Path) -> np.ndarray:
    """The previous configuration ``(n,)``: the box centre, overwritten group by group by ``[previous]``."""
    previous = robot.middle.copy()
    for group, values in table.items():
        idx = robot.group(group)
        values = np.atleast_1d(evaluate(values, variables, f"[previous] {group}"))
        if values.shape != idx.shape:
            raise TaskError(f"[previous] {group} needs {len(idx)} values; got {len(values)}")
        previous[idx] = values
    return previous


class _World:
    """The robot's collision shape (built when a collision term first asks, once per task file) and the
    ``[[obstacles]]`` scene."""

    def __init__(self, robot: Robot, path: Path, srdf: str | None, obstacles: list[dict],
                 disabled: Sequence = (), free_at: Sequence | None = None):
        self.robot, self.srdf = robot, None if srdf is None else path.parent / srdf
        self.scene = Scene.from_tables(obstacles, "[[obstacles]]", path.parent)
        for pair in disabled:
            if not (isinstance(pair, list) and len(pair) == 2 and all(isinstance(link, str) for link in pair)):
                raise TaskError(f"[task] disabled_collisions holds pairs of link names; got {pair!r}")
        self.disabled = [tuple(pair) for pair in disabled]
        if free_at is not None and not _numeric(free_at):
            raise TaskError(f"[task] free_at must be a configuration (a list of numbers) or a list of them; got "
                            f"{free_at!r}")
        self.free_at = None if free_at is None else robot.check_population(np.asarray(free_at, dtype=float),
                                                                           "[task] free_at")
        self._shape: RobotShape | None = None

    @property
    def shape(self) -> RobotShape:
        if self._shape is None:
            self._shape = RobotShape(self.robot, srdf=self.srdf, disabled=self.disabled, free_at=self.free_at)
        return self._shape


def _numeric(value: Sequence) -> bool:
    """Whether ``value`` is a list of numbers or a list of such lists (TOML arrays)."""
    rows = value if value and isinstance(value[0], list) else [value]
    return all(isinstance(row, list) and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in row)
               for row in rows)


def _objective(robot: Robot, terms: list, variables: Mapping, previous: np.ndarray, world: _World,
               follows: list[int] | None = None) -> Objective:
    """The terms of a task file's ``[[terms]]`` (each read by its class, :data:`~framework.costs.TERM_TYPES`);
    ``follows`` gets the indices of those that measure from ``previous``."""
    pairs: list[tuple[float, Term]] = []  # one Objective at the end (each ``+`` would check every pair again)
    for i, spec in enumerate(terms):
        where = f"[[terms]] #{i + 1}"
        kind = spec.get("type")
        if kind not in TERM_TYPES:
            raise TaskError(f"{where}: unknown type {kind!r}; known: {sorted(TERM_TYPES)}")
        cls = TERM_TYPES[kind]
        accepted = {"type", "weight", "name", *cls.task_keys}
        unknown = set(spec) - accepted
        if unknown:
            raise TaskError(f"{where} ({kind}): unknown keys {sorted(unknown)}; {kind} takes {sorted(accepted)}")
        weight = evaluate(spec.get("weight", 1.0), variables, f"{where} weight")
        entry = TermEntry(spec, f"{where} ({kind})", lambda value, at: evaluate(value, variables, at), previous, world)
        pairs.append((weight, cls.from_entry(entry)))  # (Objective checks the weights)
        if follows is not None and entry.follows:
            follows.append(i)
    return Objective(tuple(pairs))


# ---------------------------------------------------------------------------------------------- tracking
class _TermsAtWaypoint:
    """The task file's terms at one waypoint: a :data:`framework.tracking.TaskBuilder`."""

    def __init__(self, robot: Robot, terms: list, variables: Mapping[str, Any], world: _World):
        self.robot, self.terms, self.variables, self.world = robot, terms, dict(variables), world
        self.__name__ = "task file terms"

    def __call__(self, k: int, position: np.ndarray, rotation: np.ndarray | None, previous: np.ndarray,
                 follows: list[int] | None = None) -> Objective:
        point = {**self.variables, "t": position, "k": float(k)}
        if rotation is not None:
            point["R"] = rotation
        return _objective(self.robot, self.terms, point, previous, self.world, follows)

    def path_parameters(self, problem: Problem, trajectory: Trajectory) -> tuple[np.ndarray, tuple] | None:
        """``(P, follows)``: the parameters ``P (K, p)`` of ``problem`` (built by this builder) at every waypoint of
        ``trajectory``, and those that follow the previous solution (the reference of the motion terms without a
        ``previous`` of their own), for :func:`framework.tracking.track`'s compiled stretches; ``None`` when the
        waypoints' objectives differ in more than their parameters (their terms or weights; or the problem added
        a term of its own, as ``bounds="penalty"`` adds a joint-limit penalty)."""
        program = problem.program
        P = np.empty((trajectory.K, program.packed.params.size))
        follows: list[int] = []  # the terms that measure from the previous solution
        for k in range(trajectory.K):
            objective = self(k, trajectory.positions[k], trajectory.rotation(k), self.robot.middle,
                             follows if k == 0 else None)
            at = Program(self.robot, objective)
            if at.layout is not program.layout or at.weight_list != program.weight_list:
                return None
            P[k] = at.packed.params
        return P, program.layout.references_of(follows)


def _check_uses_waypoint(terms: list) -> None:
    """A tracking task whose terms never read ``t`` or ``R`` would solve the same IK at every waypoint."""
    for spec in terms:
        for value in spec.values():
            if isinstance(value, str) and expression_names(value) & {"t", "R"}:
                return
    raise TaskError("a [trajectory] task needs terms that use the waypoint: target = \"t\" (position) or \"R\"")
