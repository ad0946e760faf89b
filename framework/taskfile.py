"""Declarative task files (TOML): a robot, weighted cost terms, solver settings and the cases to solve.

A task file reads top to bottom like the experiment it describes::

    [task]
    name = "youbot_dual_coordinated_ik"
    robot = "youbot_dual_mobile"          # index name, or a path relative to the task file

    [solver]
    name = "cmaes"                        # any registered solver, or "hybrid"
    population = 30
    max_iterations = 1000

    [previous]                            # q_prev by joint group; numbers or expressions ("pi/2")
    base = [0, 0, "pi/2"]

    [[terms]]
    type = "position"                     # position | orientation | motion | relative_position | joint_limits
    frame = "arm1_ee"
    target = "t_e1"                       # an expression over the case's variables
    weight = 1.2

    [[cases]]                             # one IK solve per case; its keys are variables of the expressions
    name = "target 1"
    t_e1 = [0.5, -0.2, 0.45]

Expressions are numbers, vectors (lists), the names of a case's variables, ``pi``, ``+ - * /``,
parentheses and the rotation matrices ``Rx(a)``, ``Ry(a)``, ``Rz(a)``; nothing else is evaluated. Angles are in radians, lengths in metres.
"""

from __future__ import annotations

import ast
import operator
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .costs import JointLimitPenalty, Motion, Objective, Orientation, Position, RelativePosition
from .errors import MetaikError, TaskError
from .loading import load_robot
from .problem import Problem
from .robot import Robot

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

_OPS = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv}


def _rotation(axis: int):
    def matrix(angle: float) -> np.ndarray:
        c, s = np.cos(angle), np.sin(angle)
        i, j = [(1, 2), (2, 0), (0, 1)][axis]
        R = np.eye(3)
        R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
        return R

    return matrix


_ROTATIONS = {"Rx": _rotation(0), "Ry": _rotation(1), "Rz": _rotation(2)}
SOLVER_KEYS = {"name", "population", "max_iterations", "tolerance", "seed", "bounds", "options", "stop_at_tolerance"}
TERM_KEYS = {
    "position": {"frame", "target"},
    "orientation": {"frame", "target"},
    "motion": {"group", "previous", "norm"},
    "relative_position": {"frame_a", "frame_b", "offset"},
    "joint_limits": set(),
}


def evaluate(expression: Any, variables: Mapping[str, Any], where: str) -> np.ndarray | float:
    """Value of a number, list, or expression string over ``variables`` (see the module docstring)."""
    if isinstance(expression, (list, tuple)):
        return np.array([evaluate(e, variables, where) for e in expression], dtype=float)
    if isinstance(expression, (int, float)) and not isinstance(expression, bool):
        return float(expression)
    if not isinstance(expression, str):
        raise TaskError(f"{where}: expected a number, list or expression, got {expression!r}")
    try:
        tree = ast.parse(expression, mode="eval")
    except SyntaxError as err:
        raise TaskError(f"{where}: cannot parse expression {expression!r}") from err
    names = {"pi": np.pi, **variables}

    def walk(node: ast.AST):
        if isinstance(node, ast.Expression):
            return walk(node.body)
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)):
            return float(node.value)
        if isinstance(node, ast.Name):
            if node.id not in names:
                raise TaskError(f"{where}: unknown name {node.id!r} in {expression!r}; known: {sorted(names)}")
            value = names[node.id]
            return value if isinstance(value, float) else evaluate(value, {}, where)
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            value = walk(node.operand)
            return -value if isinstance(node.op, ast.USub) else value
        if isinstance(node, ast.BinOp) and type(node.op) in _OPS:
            return _OPS[type(node.op)](walk(node.left), walk(node.right))
        if isinstance(node, ast.List):
            return np.array([walk(e) for e in node.elts], dtype=float)
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in _ROTATIONS:
            if len(node.args) != 1 or node.keywords:
                raise TaskError(f"{where}: {node.func.id}() takes one angle [rad]")
            return _ROTATIONS[node.func.id](float(walk(node.args[0])))
        raise TaskError(f"{where}: {expression!r} is not a number/vector expression")

    return walk(tree)


@dataclass(frozen=True)
class Case:
    """One IK solve of a task file: its name, problem and variables."""

    name: str
    problem: Problem
    variables: dict[str, Any] = field(default_factory=dict)


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


def load_task(path: str | Path) -> TaskFile:
    """Parse and validate a task file; every error names the file and the entry at fault."""
    path = Path(path)
    if not path.is_file():
        raise TaskError(f"task file {path} does not exist")
    try:
        raw = tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise TaskError(f"{path}: not valid TOML: {err}") from err
    try:
        return _parse(path, raw)
    except MetaikError as err:
        if str(path) in str(err):
            raise
        raise type(err)(f"{path}: {err}") from err


def _parse(path: Path, raw: dict[str, Any]) -> TaskFile:
    task = _table(raw, "task", path)
    if "robot" not in task:
        raise TaskError("[task] needs a robot (index name or file path)")
    robot_source = task["robot"]
    local = path.parent / str(robot_source)
    robot = load_robot(local if local.is_file() else robot_source, **_robot_options(task))
    solver = dict(raw.get("solver", {}))
    unknown = set(solver) - SOLVER_KEYS
    if unknown:
        raise TaskError(f"[solver] has unknown keys {sorted(unknown)}; known: {sorted(SOLVER_KEYS)}")
    terms = raw.get("terms")
    if not terms:
        raise TaskError("a task needs at least one [[terms]] entry")
    cases_raw = raw.get("cases") or [{"name": task.get("name", path.stem)}]
    cases = []
    for i, case in enumerate(cases_raw):
        variables = {k: v for k, v in case.items() if k != "name"}
        name = str(case.get("name", f"case {i + 1}"))
        previous = _previous(robot, raw.get("previous", {}), variables, path)
        objective = _objective(robot, terms, variables, previous)
        cases.append(Case(name, Problem(robot, objective, bounds=solver.get("bounds", "resample")), variables))
    return TaskFile(path, task.get("name", path.stem), task.get("description", ""), robot, solver, tuple(cases), raw)


def _table(raw: Mapping, key: str, path: Path) -> dict:
    if key not in raw or not isinstance(raw[key], dict):
        raise TaskError(f"missing [{key}] table")
    return raw[key]


def _robot_options(task: Mapping[str, Any]) -> dict[str, Any]:
    options = {}
    for key in ("joints", "locked", "end_effectors", "xacro_args"):
        if key in task:
            options[key] = task[key]
    if "bounds" in task:
        options["bounds"] = {k: tuple(evaluate(v, {}, f"[task] bounds.{k}")) for k, v in task["bounds"].items()}
    return options


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


def _objective(robot: Robot, terms: list, variables: Mapping, previous: np.ndarray) -> Objective:
    objective = None
    for i, spec in enumerate(terms):
        where = f"[[terms]] #{i + 1}"
        kind = spec.get("type")
        if kind not in TERM_KEYS:
            raise TaskError(f"{where}: unknown type {kind!r}; known: {sorted(TERM_KEYS)}")
        unknown = set(spec) - TERM_KEYS[kind] - {"type", "weight", "name"}
        if unknown:
            raise TaskError(f"{where} ({kind}): unknown keys {sorted(unknown)}")
        weight = evaluate(spec.get("weight", 1.0), variables, f"{where} weight")
        name = spec.get("name")
        value = lambda key: evaluate(spec[key], variables, f"{where} {key}")  # noqa: E731
        try:
            if kind == "position":
                term = Position(spec["frame"], value("target"), name=name)
            elif kind == "orientation":
                term = Orientation(spec["frame"], value("target"), name=name)
            elif kind == "relative_position":
                term = RelativePosition(spec["frame_a"], spec["frame_b"], value("offset"), name=name)
            elif kind == "motion":
                prev = value("previous") if "previous" in spec else previous
                term = Motion(spec["group"], prev, norm=spec.get("norm", "l2"), name=name)
            else:
                term = JointLimitPenalty(name=name or "joint_limits")
        except KeyError as err:
            raise TaskError(f"{where} ({kind}) needs a {err.args[0]!r} entry") from None
        weighted = weight * term
        objective = weighted if objective is None else objective + weighted
    return objective
