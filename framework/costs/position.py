"""Position of a frame: Euclidean distance to a target point (paper 000 eq. 9, paper 002 eq. 5)."""

from __future__ import annotations

from typing import ClassVar

from collections.abc import Sequence

import numpy as np

from ..compiled.native import internal
from ..model.robot import Robot
from . import blocks as B
from ..model.reach import reach_hint
from .base import Term, TermEntry, as_vector, finite_rows
from .curvature import position_curvature
from .kinds import BlockKind
from .program import Block
from .workspace import JACOBIAN_ONLY, RESIDUAL, views


def position_residual(ws) -> int:
    """``p_a − t`` (3) [m] at rows ``ws.row``; Jacobian ``J_p,a``."""
    v = views(ws)
    block, row = v.blocks[ws.block], ws.row
    p, fa = block.params, block.fa
    if ws.mode != JACOBIAN_ONLY:
        for c in range(3):
            v.r[row + c] = v.poses[fa, 9 + c] - v.params[p + c]
    if ws.mode != RESIDUAL:
        translation_jacobian(v.jacobians, fa, -1, v.J, row, ws.n)
    return 3


def position_second_order(ws) -> int:
    """``Σ μ_c ∇²(p_a)_c``: exact (the product of exponentials)."""
    v = views(ws)
    fa, mu = v.blocks[ws.block].fa, v.multipliers
    position_curvature(fa, mu[0], mu[1], mu[2], v.jacobians, v.chain_ptr, v.chain_idx, v.hessian)
    return 0


@internal(inline=True)
def translation_jacobian(jacobians, f, minus, J, row, n) -> None:
    """``J[row:row + 3]``: the translation rows of frame ``f``'s Jacobian, less frame ``minus``'s (``-1``: none)."""
    for c in range(3):
        for i in range(n):
            J[row + c, i] = jacobians[f, c, i] if minus < 0 else jacobians[f, c, i] - jacobians[minus, c, i]


#: A frame's origin at a world point: ``p_a − t`` (3) [m], params ``t`` (3).
POSITION = BlockKind("position", position_residual, position_second_order)


class Position(Term):
    """``‖p_frame(x) − target‖₂`` [m], with ``p_frame`` and ``target`` in the world frame.

    Residual ``p_frame(x) − target`` (3,) [m]; a task term held to the linear tolerance.
    """

    task_type, task_keys, category = "position", ("frame", "target"), "position"
    #: the entry's keys, for the task-file reference (docs/taskfile.md)
    task_doc: ClassVar[dict[str, str]] = {
        'frame': 'the frame placed',
        'target': 'its target position [m, world]'
    }
    #: a robot, and an entry of this type for it (checked by tests/test_taskfile_doc.py)
    task_example: ClassVar[tuple[str, str]] = ('puma560', 'type = "position"\nframe = "ee"\ntarget = [0.4, 0.1, 0.3]')

    @classmethod
    def from_entry(cls, entry: TermEntry) -> Position:
        return cls(entry.text("frame"), entry.value("target"), name=entry.name)

    level = "task"
    has_target = True
    fixed_layout = True

    def __init__(self, frame: str, target: Sequence[float], *, name: str | None = None):
        self.frame = frame
        self.frames = (frame,)
        self.name = name or f"position[{frame}]"
        self.set_target(target)

    def set_target(self, target: Sequence[float]) -> None:
        """Move the target point ``(3,)`` [m, world] (a problem holding the term re-reads it)."""
        self.target = as_vector(target, 3, lambda: f"position target of {self.frame!r}")
        self._touch()

    def why_unmet(self, robot: Robot, x: np.ndarray) -> str | None:
        return reach_hint(robot, self.frame, self.target)

    def target_parameters(self, robot: Robot, targets: Sequence) -> np.ndarray:
        """``(B, 3)`` target points [m, world] of a batch, validated at once."""
        return finite_rows(targets, (3,), f"position targets of {self.frame!r}")

    def parameters(self, robot: Robot) -> np.ndarray:
        return self.target

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        return (Block(POSITION, B.NORM, 3, self.frames, self.target, tolerance=B.TOL_LINEAR),)

    def target_points(self, robot: Robot, x: np.ndarray) -> dict[str, np.ndarray]:
        return {self.frame: self.target}

    def frame_target(self) -> tuple[str, np.ndarray, None]:
        return self.frame, self.target, None

    def __repr__(self) -> str:
        return f"Position({self.frame!r}, {np.round(self.target, 6).tolist()})"
