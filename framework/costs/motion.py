"""Motion of a joint group: distance to the previous configuration (paper 000 eq. 10, paper 002 eq. 16)."""

from __future__ import annotations

from typing import ClassVar

from collections.abc import Sequence

import numpy as np

from ..errors import TaskError
from ..model.robot import Robot
from ..validate import all_finite
from . import blocks as B
from .base import Term, TermEntry
from .kinds import BlockKind
from .lie import wrap_angle
from .program import Block
from .workspace import RESIDUAL, views


def coordinates_residual(ws) -> int:
    """``x[idx] − x₀`` (differences of continuous joints wrapped to ``[−π, π)``); unit Jacobian rows."""
    v = views(ws)
    block, row = v.blocks[ws.block], ws.row
    p, q, n = block.params, block.indices, ws.n
    for c in range(block.rows):
        k = v.indices[q + c]
        d = v.x[k] - v.params[p + c]
        v.r[row + c] = wrap_angle(d) if v.wraps[k] else d
        if ws.mode != RESIDUAL:
            for i in range(n):
                v.J[row + c, i] = 0.0
            v.J[row + c, k] = 1.0
    return block.rows


#: Coordinates of the robot against values: ``x[idx] − x₀`` (count) [rad or m], params ``x₀`` (count); linear in
#: ``x`` (no curvature).
COORDINATES = BlockKind("coordinates", coordinates_residual, unit_rows=True)


def coordinates_block(indices: Sequence[int], previous: np.ndarray, rho: int, scale: float = 1.0) -> Block:
    """A :data:`COORDINATES` block ``x[indices] − previous`` (differences of continuous joints wrapped)."""
    indices = np.asarray(indices, dtype=np.int64)
    if indices.size == 0:
        raise TaskError("a joint-space term needs at least one coordinate")
    return Block(COORDINATES, rho, int(indices.size), params=np.asarray(previous, dtype=float), indices=indices,
                 scale=scale)

NORMS = ("l2", "l1")


def motion_name(group: str) -> str:
    """A motion term's default name for its joint group: ``motion[group]``."""
    return f"motion[{group}]"


class Motion(Term):
    """Distance of a joint group to its previous values (a regularizer).

    ``norm="l2"``: ``‖x_g − x_g^prev‖₂`` (paper 000 eq. 10); ``norm="l1"``: ``‖x_g − x_g^prev‖₁ / (n_g π)``
    (paper 002 eq. 16), with ``n_g`` the group size. ``previous`` is either the whole configuration ``(n,)`` or
    the group's values ``(n_g,)``; ``group`` is a group name (``"base"``, ``"arm1"``, ``"all"``) or a joint name.
    Residual ``x_g − x_g^prev`` [rad / m], with differences of continuous joints wrapped to ``[−π, π)``.
    """

    task_type, task_keys, category = "motion", ("group", "previous", "norm"), "motion"
    #: what the term's values are, in errors
    values_are: ClassVar[str] = "previous configuration"
    #: the entry's keys, for the task-file reference (docs/taskfile.md)
    task_doc: ClassVar[dict[str, str]] = {
        'group': 'a joint group, a joint, or "all"',
        'previous': 'the configuration measured from (default: [previous], the previous waypoint on a path)',
        'norm': '"l2" (default) or "l1" (paper 002\'s normalized L1)'
    }
    #: a robot, and an entry of this type for it (checked by tests/test_taskfile_doc.py)
    task_example: ClassVar[tuple[str, str]] = ('puma560', 'type = "motion"\ngroup = "arm"\nweight = 0.1')

    @classmethod
    def from_entry(cls, entry: TermEntry) -> Motion:
        """``previous`` defaults to the case's configuration before it (the previous waypoint's along a path)."""
        previous = entry.value("previous") if entry.has("previous") else entry.previous
        return cls(entry.text("group"), previous, norm=entry.text("norm", "l2"), name=entry.name)

    level = "regularizer"
    has_target = True

    def __init__(self, group: str, previous: Sequence[float], *, norm: str = "l2", name: str | None = None):
        if norm not in NORMS:
            raise TaskError(f"motion norm must be one of {NORMS}; got {norm!r}")
        self.group, self.norm = group, norm
        self.name = name or motion_name(group)
        self.set_target(previous)

    def set_target(self, previous: Sequence[float]) -> None:
        """Change the previous configuration (the whole ``(n,)`` or the group's ``(n_g,)``)."""
        try:
            previous = np.array(previous, dtype=float)
        except (TypeError, ValueError):
            raise TaskError(f"{self.values_are} of group {self.group!r} must be numbers") from None
        if previous.ndim != 1 or not all_finite(previous):
            raise TaskError(f"{self.values_are} of group {self.group!r} must be a finite vector")
        self.previous = previous
        self._touch()

    def indices(self, robot: Robot) -> np.ndarray:
        """The group's coordinates in ``robot``'s search vector (read-only; remembered per robot: a path reads
        them at every waypoint)."""
        cache = self.__dict__.get("_indices")
        if cache is None or cache[0] is not robot or cache[1] != self.group:
            idx = np.array(robot.group(self.group))
            idx.setflags(write=False)
            cache = self._indices = (robot, self.group, idx)
        return cache[2]

    def previous_values(self, robot: Robot) -> np.ndarray:
        idx = self.indices(robot)
        if self.previous.shape == (robot.n,):
            return self.previous[idx]
        if self.previous.shape == (len(idx),):
            return self.previous
        sizes = f"{len(idx)}" if len(idx) == robot.n else f"{len(idx)} (the group's) or {robot.n} (the robot's)"
        raise TaskError(f"{self.values_are} of group {self.group!r} must have {sizes} values; got "
                        f"{self.previous.shape[0]}")

    def validate(self, robot: Robot) -> None:
        self.previous_values(robot)

    def why_unmet(self, robot: Robot, x: np.ndarray) -> str | None:
        """Targets outside the joint bounds (the search stays inside them), named with their bounds."""
        idx, values = self.indices(robot), self.previous_values(robot)
        out = [(int(i), v) for i, v in zip(idx, values) if not robot.lower[i] <= v <= robot.upper[i]]
        if not out:
            return None
        i, v = out[0]
        name, lo, hi = robot.coordinate_names[i], robot.lower[i], robot.upper[i]
        unit = "m" if robot.coordinate_is_linear(i) else "rad"
        degrees = " (degrees given for radians?)" if unit == "rad" and abs(v) > 2 * np.pi else ""
        return (f"{name}'s target {v:g} lies outside its bounds [{lo:.4g}, {hi:.4g}] {unit}{degrees}"
                + (f", and {len(out) - 1} more" if len(out) > 1 else ""))

    def parameters(self, robot: Robot) -> np.ndarray:
        """The block's parameters, the previous values (read without building the block: a path moves them at
        every waypoint)."""
        return self.previous_values(robot)

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        idx = self.indices(robot)
        if self.norm == "l2":
            return (coordinates_block(idx, self.previous_values(robot), B.NORM),)
        return (coordinates_block(idx, self.previous_values(robot), B.L1, 1.0 / (len(idx) * np.pi)),)


class JointTarget(Motion):
    """Joint values held at targets, as a task (a posture to reach, e.g. a wrist angle or a folded arm):
    ``‖x_g − x_g*‖₂`` for a group or joint ``g``; ``target`` is the whole configuration ``(n,)`` or the group's
    ``(n_g,)``. Reached first like every task term; its error is held to the angular tolerance [rad], or to the
    linear one [m] when the group holds a translation (prismatic or planar coordinates).
    """

    task_type, task_keys, category = "joint_target", ("group", "target"), None
    values_are: ClassVar[str] = "joint target"
    #: the entry's keys, for the task-file reference (docs/taskfile.md)
    task_doc: ClassVar[dict[str, str]] = {
        'group': 'a joint group, a joint, or "all"',
        'target': 'its joint values [rad or m]'
    }
    #: a robot, and an entry of this type for it (checked by tests/test_taskfile_doc.py)
    task_example: ClassVar[tuple[str, str]] = ('puma560', 'type = "joint_target"\ngroup = "joint6"\ntarget = [0.5]')

    @classmethod
    def from_entry(cls, entry: TermEntry) -> JointTarget:
        return cls(entry.text("group"), entry.value("target"), name=entry.name)

    level = "task"

    def __init__(self, group: str, target: Sequence[float], *, name: str | None = None):
        super().__init__(group, target, norm="l2", name=name or f"joints[{group}]")

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        idx = self.indices(robot)
        linear = any(robot.coordinate_is_linear(i) for i in idx)
        block = coordinates_block(idx, self.previous_values(robot), B.NORM)
        return (block._replace(tolerance=B.TOL_LINEAR if linear else B.TOL_ANGULAR),)
