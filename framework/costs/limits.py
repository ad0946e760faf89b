"""Penalty on joint-limit violations (paper 001): ``δ · Σ (max(0, l − x) + max(0, x − u))``."""

from __future__ import annotations

from typing import ClassVar

from collections.abc import Sequence

import numpy as np

from ..errors import TaskError
from ..model.bounds import check_bounds
from ..model.robot import Robot
from . import blocks as B
from .base import Term, TermEntry
from .kinds import BlockKind
from .program import Block
from .workspace import RESIDUAL, views


def limits_residual(ws) -> int:
    """``min(0, x − l) + max(0, x − u)`` per coordinate (n); Jacobian ``1`` outside the limits, 0 inside."""
    v = views(ws)
    block, row, n = v.blocks[ws.block], ws.row, ws.n
    p = block.params
    for k in range(n):
        lo, hi = v.params[p + k], v.params[p + n + k]
        value = v.x[k]
        v.r[row + k] = value - lo if value < lo else (value - hi if value > hi else 0.0)
        if ws.mode != RESIDUAL:
            for i in range(n):
                v.J[row + k, i] = 0.0
            v.J[row + k, k] = 1.0 if (value < lo or value > hi) else 0.0
    return n


#: Limit violations of every coordinate: params ``l`` (n), ``u`` (n).
LIMITS = BlockKind("joint limits", limits_residual)


class JointLimitPenalty(Term):
    """Sum of limit violations [rad or m] times ``weight`` (δ, large: 1e3 by default).

    Limits default to the robot's search bounds; pass ``lower``/``upper`` ``(n,)`` for others. Zero inside.
    A ``"value"`` term: the local engine keeps every step inside the box, where it is zero.
    """

    task_type, task_keys = "joint_limits", ()
    task_doc: ClassVar[dict[str, str]] = {}
    #: a robot, and an entry of this type for it (checked by tests/test_taskfile_doc.py)
    task_example: ClassVar[tuple[str, str]] = ('puma560', 'type = "joint_limits"\nweight = 0.001')

    @classmethod
    def from_entry(cls, entry: TermEntry) -> JointLimitPenalty:
        return cls(name=entry.name or "joint_limits")

    level = "value"
    penalizes_limits = True  # the problem's "penalty" bounds mode adds one unless the objective has one

    def __init__(
        self,
        weight: float = 1e3,
        *,
        lower: Sequence[float] | None = None,
        upper: Sequence[float] | None = None,
        name: str = "joint_limits",
    ):
        if not np.isfinite(weight) or weight < 0:
            raise TaskError(f"joint-limit penalty weight must be finite and >= 0; got {weight!r}")
        self.weight, self.name = float(weight), name
        self.lower = None if lower is None else np.asarray(lower, dtype=float)
        self.upper = None if upper is None else np.asarray(upper, dtype=float)

    def limits(self, robot: Robot) -> tuple[np.ndarray, np.ndarray]:
        lower = robot.lower if self.lower is None else self.lower
        upper = robot.upper if self.upper is None else self.upper
        return lower, upper

    def validate(self, robot: Robot) -> None:
        check_bounds(*self.limits(robot), robot.coordinate_names, what="joint-limit penalty limits")

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        lower, upper = self.limits(robot)
        return (Block(LIMITS, B.L1, robot.n, params=np.concatenate([lower, upper]), scale=self.weight),)
