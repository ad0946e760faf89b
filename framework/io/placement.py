"""Base-placement task files: where should a mobile manipulator stand so its hands reach given targets.

A file with a ``[placement]`` table::

    [task]
    name = "youbot_dual_base_placement"
    robot = "youbot_dual_mobile"

    [placement]
    radius = 0.7          # candidate base positions within this distance [m] of the targets' mean
    step = 0.1            # grid spacing [m]
    headings = 12         # base headings tried per position

    [placement.targets]   # frame = a point [m, world] (expressions as in task files: "0.3 + 0.9")
    arm1_ee = [1.2, 0.6, 0.3]
    arm2_ee = [1.2, 0.9, 0.3]

``metaik run`` ranks the candidate base poses (:func:`framework.reach.capability.base_placements`), solves the whole
robot from the best one (both hands, motion minimized on the task) and, with ``--record``, records it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import TaskError
from ..model.robot import Robot
from .task_values import robot_of_task, evaluate

PLACEMENT_KEYS = {"radius", "step", "headings", "group", "seed", "targets"}


@dataclass(frozen=True)
class PlacementTask:
    """A base-placement task: the robot, the hand targets (frame -> point [m, world]) and the search settings."""

    path: Path
    name: str
    description: str
    robot: Robot
    targets: dict[str, np.ndarray]
    settings: dict[str, Any]


def is_placement_task(raw: Mapping[str, Any]) -> bool:
    return "placement" in raw


def placement_task_from_dict(raw: Mapping[str, Any], path: Path) -> PlacementTask:
    """Parse a base-placement task; errors name the entry at fault."""
    task, table = raw.get("task"), raw.get("placement")
    if not isinstance(task, dict) or "robot" not in task:
        raise TaskError("[task] needs a robot (index name or file path)")
    if not isinstance(table, dict):
        raise TaskError("[placement] must be a table")
    unknown = sorted(set(table) - PLACEMENT_KEYS)
    if unknown:
        raise TaskError(f"[placement] has unknown keys {unknown}; known: {sorted(PLACEMENT_KEYS)}")
    extra = sorted(set(raw) - {"task", "placement"})
    if extra:
        raise TaskError(f"a placement task holds [task] and [placement] only; found {extra}")
    robot = robot_of_task(task, path)
    targets_raw = table.get("targets")
    if not isinstance(targets_raw, dict) or not targets_raw:
        raise TaskError("[placement.targets] must map each hand frame to a point [x, y, z]")
    targets = {}
    for frame, value in targets_raw.items():
        point = np.atleast_1d(np.asarray(evaluate(value, {}, f"[placement.targets] {frame}"), dtype=float))
        if point.shape != (3,):
            raise TaskError(f"[placement.targets] {frame} must be a point [x, y, z]; got {value!r}")
        robot.frame_id(frame)
        targets[frame] = point
    settings = {}
    for key, kind in (("radius", float), ("step", float), ("headings", int), ("group", str), ("seed", int)):
        if key in table:
            value = table[key]
            if kind is str and not isinstance(value, str) or kind is not str and (
                    isinstance(value, bool) or not isinstance(value, (int, float)) or value <= 0 and key != "seed"
                    or kind is int and value != int(value)):
                raise TaskError(f"[placement] {key} must be a positive {kind.__name__}; got {value!r}")
            settings[key] = kind(value)
    return PlacementTask(path, str(task.get("name", path.stem)), str(task.get("description", "")), robot, targets,
                         settings)
