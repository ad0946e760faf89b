"""What every task file reads the same way: expressions, trajectories and the TOML itself.

IK, tracking, reach (:mod:`framework.io.fabrik_tasks`) and base-placement task files (:mod:`framework.
placement_taskfile`) write numbers as expressions (``"pi/6"``, ``"[0.3, 0, t[2]]"``, ``"Ry(pi/2)"``) and paths as
``[trajectory]`` tables; :mod:`framework.io.taskfile` documents both and dispatches a file to its reader.
"""

from __future__ import annotations

import ast
import functools
import operator
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import TaskError
from ..model.bounds import bound_pair
from ..model.rotations import rotation_from
from ..tracking.trajectory import Trajectory
from ..tracking.paths import circle, lemniscate, line, paper000, point_count, rose, sinusoid

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
#: ``[trajectory]`` types -> (required keys, optional keys); every type also takes ``name`` and ``orientation`` (with ``quaternion`` naming the order of 4 numbers).
TRAJECTORY_KEYS: dict[str, tuple[set[str], set[str]]] = {
    "circle": ({"centre", "radius"}, {"points", "plane", "start_angle", "turns"}),
    "lemniscate": ({"centre", "a"}, {"points", "plane"}),
    "rose": ({"centre", "radius", "amplitude"}, {"points", "petals", "plane"}),
    "sinusoid": ({"start", "stop", "amplitude", "wavenumber"}, {"points", "axis", "phase", "saturation"}),
    "line": ({"start", "stop"}, {"points"}),
    "paper000": ({"path"}, {"points"}),
    "file": ({"path"}, set()),
    "waypoints": ({"positions"}, set()),
}


def read_toml(path: Path) -> dict[str, Any]:
    """The TOML dictionary of the file at ``path``; a :class:`TaskError` naming it when missing or malformed."""
    if not path.is_file():
        raise TaskError(f"task file {path} does not exist")
    try:
        return tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise TaskError(f"{path}: not valid TOML: {err}") from err


def evaluate(expression: Any, variables: Mapping[str, Any], where: str) -> np.ndarray | float:
    """Value of a number, list, or expression string over ``variables`` (see the module docstring)."""
    if isinstance(expression, np.ndarray):
        return expression.astype(float)
    if isinstance(expression, (list, tuple)):
        return np.array([evaluate(e, variables, where) for e in expression], dtype=float)
    if isinstance(expression, (int, float)) and not isinstance(expression, bool):
        return float(expression)
    if not isinstance(expression, str):
        raise TaskError(f"{where}: expected a number, list or expression, got {expression!r}")
    try:
        tree = _parsed(expression)
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
            with np.errstate(all="raise"):
                try:
                    return _OPS[type(node.op)](walk(node.left), walk(node.right))
                except (ZeroDivisionError, FloatingPointError, ValueError) as err:
                    raise TaskError(f"{where}: cannot evaluate {expression!r}: {err}") from None
        if isinstance(node, ast.List):
            return np.array([walk(e) for e in node.elts], dtype=float)
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in _ROTATIONS:
            if len(node.args) != 1 or node.keywords:
                raise TaskError(f"{where}: {node.func.id}() takes one angle [rad]")
            return _ROTATIONS[node.func.id](float(walk(node.args[0])))
        raise TaskError(f"{where}: {expression!r} is not a number/vector expression")

    return walk(tree)


@functools.lru_cache(maxsize=4096)
def _parsed(expression: str) -> ast.Expression:
    """The syntax tree of an expression, parsed once (a path's terms evaluate the same strings at every
    waypoint; the tree is only read)."""
    return ast.parse(expression, mode="eval")


def expression_names(expression: str) -> set[str]:
    try:
        tree = _parsed(expression)
    except SyntaxError:
        return set()
    return {node.id for node in ast.walk(tree) if isinstance(node, ast.Name)}


def trajectory_from_table(spec: Any, variables: Mapping, path: Path, points: int | None,
                          where: str) -> Trajectory:
    """A :class:`Trajectory` from a ``[trajectory]`` table (see the module docstring)."""
    if not isinstance(spec, dict):
        raise TaskError(f"{where} must be a table")
    kind = spec.get("type")
    if kind not in TRAJECTORY_KEYS:
        raise TaskError(f"{where}: unknown type {kind!r}; known: {sorted(TRAJECTORY_KEYS)}")
    required, optional = TRAJECTORY_KEYS[kind]
    missing = required - set(spec)
    if missing:
        raise TaskError(f"{where} ({kind}) needs {sorted(missing)}")
    unknown = set(spec) - required - optional - {"type", "name", "orientation", "quaternion", "rate", "duration"}
    if unknown:
        raise TaskError(f"{where} ({kind}): unknown keys {sorted(unknown)}; known: {sorted(required | optional)}")

    def value(key: str) -> Any:
        return evaluate(spec[key], variables, f"{where} {key}")

    def integer(key: str, default: int) -> int:
        number = value(key) if key in spec else default
        if not np.isfinite(number) or float(number) != int(number):
            raise TaskError(f"{where} {key} must be an integer; got {number!r}")
        return int(number)

    n = points if points is not None else integer("points", 200)
    name = str(spec.get("name", kind))
    plane = spec.get("plane", "yz")
    if kind == "circle":
        trajectory = circle(value("centre"), value("radius"), n, plane=plane,
                            start_angle=value("start_angle") if "start_angle" in spec else 0.0,
                            turns=value("turns") if "turns" in spec else 1.0, name=name)
    elif kind == "lemniscate":
        trajectory = lemniscate(value("centre"), value("a"), n, plane=plane, name=name)
    elif kind == "rose":
        trajectory = rose(value("centre"), value("radius"), value("amplitude"), n, petals=integer("petals", 3),
                          plane=plane, name=name)
    elif kind == "sinusoid":
        trajectory = sinusoid(value("start"), value("stop"), value("amplitude"), value("wavenumber"), n,
                              axis=value("axis") if "axis" in spec else (0.0, 0.0, 1.0),
                              phase=value("phase") if "phase" in spec else 0.0,
                              saturation=value("saturation") if "saturation" in spec else None, name=name)
    elif kind == "line":
        trajectory = line(value("start"), value("stop"), n, name=name)
    elif kind == "paper000":
        trajectory = paper000(str(spec["path"]), n).renamed(name if "name" in spec else str(spec["path"]))
    else:
        if kind == "file":
            local = path.parent / str(spec["path"])
            trajectory = Trajectory.from_file(local if local.is_file() else Path(str(spec["path"])), name)
        else:
            trajectory = Trajectory.from_array(value("positions"), name)
        if points is not None:
            keep = np.linspace(0, trajectory.K - 1, point_count(points)).round().astype(int)
            trajectory = trajectory[np.unique(keep)]
    if "orientation" in spec:
        order = str(spec["quaternion"]) if "quaternion" in spec else None
        trajectory = trajectory.with_orientation(rotation_from(value("orientation"), f"{where} orientation", order))
    if "rate" in spec or "duration" in spec:  # a timed path: waypoints at a rate [Hz], or spread over a duration [s]
        if "rate" in spec and "duration" in spec:
            raise TaskError(f"{where}: give rate [Hz] or duration [s], not both")
        timing = {key: float(value(key)) for key in ("rate", "duration") if key in spec}
        trajectory = trajectory.timed(**timing)
    return trajectory


#: ``[task]`` keys that say how to load its robot (the options of :func:`framework.load_robot`), and their kinds.
ROBOT_KEYS = {"robot": "text", "joints": "names", "locked": "table", "end_effectors": "names", "groups": "table",
              "xacro_args": "table", "bounds": "table", "package_dirs": "folders", "floating_base": "bool",
              "quaternion": "text", "trusted": "bool"}


def robot_of_task(task: Mapping[str, Any], path: Path):
    """The robot of a task file's ``[task]`` table (``path``: the file): ``robot`` an index name or a file
    relative to the task file, loaded with the table's :data:`ROBOT_KEYS` (``package_dirs`` relative to the task
    file), as :func:`framework.load_robot` loads it; every kind of task file reads its robot here."""
    from ..model.loading import load_robot

    if "robot" not in task:
        raise TaskError("[task] needs a robot (index name or file path)")
    local = path.parent / str(task["robot"])
    return load_robot(local if local.is_file() else task["robot"], **_robot_options(task, path))


def _robot_options(task: Mapping[str, Any], path: Path) -> dict[str, Any]:
    options = {}
    for key in ("joints", "locked", "end_effectors", "groups", "xacro_args", "floating_base", "quaternion", "trusted"):
        if key in task:
            options[key] = task[key]
    if "package_dirs" in task:  # relative to the task file
        given = task["package_dirs"]
        options["package_dirs"] = [{k: path.parent / str(v) for k, v in item.items()} if isinstance(item, dict)
                                   else path.parent / str(item) for item in ([given] if isinstance(given, dict)
                                                                              else given)]
    if "bounds" in task:
        where = "[task] bounds.{}".format
        options["bounds"] = {k: bound_pair(evaluate(v, {}, where(k)), where(k), TaskError)
                             for k, v in task["bounds"].items()}
    return options
