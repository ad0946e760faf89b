"""Point on a line: a frame's origin held on a world line (a tool along a rail, a needle on its insertion axis),
free along it."""

from __future__ import annotations

from typing import ClassVar

from collections.abc import Sequence

import numpy as np

from ..model.robot import Robot
from . import blocks as B
from .base import Term, TermEntry, as_vector
from .curvature import position_curvature
from .direction import perpendicular_basis, unit_vector
from .kinds import BlockKind
from .program import Block
from .workspace import RESIDUAL, views


def line_residual(ws) -> int:
    """``(b₁ᵀ(p_a − c), b₂ᵀ(p_a − c))`` (2) [m]: the frame's origin off the line through ``c`` with direction ``d``,
    in a basis ``(b₁, b₂)`` of the plane perpendicular to ``d`` (its norm the distance to the line); Jacobian
    ``b_kᵀ J_p,a``."""
    v = views(ws)
    block, row, n = v.blocks[ws.block], ws.row, ws.n
    p, fa, params = block.params, block.fa, v.params
    d0, d1, d2 = v.poses[fa, 9] - params[p], v.poses[fa, 10] - params[p + 1], v.poses[fa, 11] - params[p + 2]
    for k in range(2):
        q = p + 3 + 3 * k
        v.r[row + k] = params[q] * d0 + params[q + 1] * d1 + params[q + 2] * d2
        if ws.mode != RESIDUAL:
            for i in range(n):
                v.J[row + k, i] = (params[q] * v.jacobians[fa, 0, i] + params[q + 1] * v.jacobians[fa, 1, i]
                                   + params[q + 2] * v.jacobians[fa, 2, i])
    return 2


def line_second_order(ws) -> int:
    """``(μ₁ b₁ + μ₂ b₂)ᵀ∂²p_a``: exact (the product of exponentials)."""
    v = views(ws)
    block, mu, params = v.blocks[ws.block], v.multipliers, v.params
    p = block.params
    m0 = mu[0] * params[p + 3] + mu[1] * params[p + 6]
    m1 = mu[0] * params[p + 4] + mu[1] * params[p + 7]
    m2 = mu[0] * params[p + 5] + mu[1] * params[p + 8]
    position_curvature(block.fa, m0, m1, m2, v.jacobians, v.chain_ptr, v.chain_idx, v.hessian)
    return 0


#: A frame's origin on a world line: its offset from the line in a basis ``(b₁, b₂)`` perpendicular to the line's
#: direction (2) [m]; params ``c`` (3), ``b₁`` (3), ``b₂`` (3).
LINE = BlockKind("point on a line", line_residual, line_second_order)


class PointOnLine(Term):
    """The distance [m] of the frame's origin to the line through ``point`` [m, world] along ``direction``
    (normalized): the origin held on the line, anywhere along it.

    Residual (2,): the origin's offset from the line in a basis of the plane perpendicular to it [m]; a task term
    held to the linear tolerance.
    """

    level = "task"
    has_target = True
    fixed_layout = True
    task_type, task_keys, category = "point_on_line", ("frame", "point", "direction"), "position"
    #: the entry's keys, for the task-file reference (docs/taskfile.md)
    task_doc: ClassVar[dict[str, str]] = {
        'frame': 'the frame held on the line',
        'point': 'a point of the line [m, world]',
        'direction': "the line's direction [world]"
    }
    #: a robot, and an entry of this type for it (checked by tests/test_taskfile_doc.py)
    task_example: ClassVar[tuple[str, str]] = ('puma560', 'type = "point_on_line"\nframe = "ee"\npoint = [0.4, 0.0, 0.3]\ndirection = [0, 1, 0]')

    @classmethod
    def from_entry(cls, entry: TermEntry) -> PointOnLine:
        return cls(entry.text("frame"), entry.value("point"), entry.value("direction"), name=entry.name)

    def __init__(self, frame: str, point: Sequence[float], direction: Sequence[float], *, name: str | None = None):
        self.frame = frame
        self.frames = (frame,)
        self.name = name or f"line[{frame}]"
        self.set_target((point, direction))

    def set_target(self, target: tuple[Sequence[float], Sequence[float]]) -> None:
        """Move the line: ``(point (3,) [m, world], direction (3,))``."""
        point, direction = target
        self.point = as_vector(point, 3, lambda: f"line point of {self.frame!r}")
        self.direction = unit_vector(direction, f"line direction of {self.frame!r}")
        self._parameters = np.concatenate([self.point, *perpendicular_basis(self.direction)])
        self._touch()

    def parameters(self, robot: Robot) -> np.ndarray:
        return self._parameters

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        return (Block(LINE, B.NORM, 2, self.frames, self._parameters, tolerance=B.TOL_LINEAR),)

    def __repr__(self) -> str:
        return (f"PointOnLine({self.frame!r}, {np.round(self.point, 6).tolist()}, "
                f"{np.round(self.direction, 6).tolist()})")
