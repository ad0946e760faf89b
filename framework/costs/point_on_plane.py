"""Point on a plane: a frame's origin held on a world plane (a tool on a table, a foot on the ground), free
within it."""

from __future__ import annotations

from typing import ClassVar

from collections.abc import Sequence

import numpy as np

from ..model.robot import Robot
from . import blocks as B
from .base import Term, TermEntry, as_vector
from .curvature import position_curvature
from .direction import unit_vector
from .kinds import BlockKind
from .program import Block
from .workspace import RESIDUAL, views


def plane_residual(ws) -> int:
    """``nᵀ(p_a − c)`` (1) [m], the signed distance of the frame's origin to the plane through ``c`` with unit
    normal ``n``; Jacobian ``nᵀ J_p,a``."""
    v = views(ws)
    block, row, n = v.blocks[ws.block], ws.row, ws.n
    p, fa, params = block.params, block.fa, v.params
    n0, n1, n2 = params[p + 3], params[p + 4], params[p + 5]
    v.r[row] = (n0 * (v.poses[fa, 9] - params[p]) + n1 * (v.poses[fa, 10] - params[p + 1])
                + n2 * (v.poses[fa, 11] - params[p + 2]))
    if ws.mode != RESIDUAL:
        for i in range(n):
            v.J[row, i] = n0 * v.jacobians[fa, 0, i] + n1 * v.jacobians[fa, 1, i] + n2 * v.jacobians[fa, 2, i]
    return 1


def plane_second_order(ws) -> int:
    """``μ nᵀ∂²p_a``: exact (the product of exponentials)."""
    v = views(ws)
    block, mu = v.blocks[ws.block], v.multipliers[0]
    p = block.params
    position_curvature(block.fa, mu * v.params[p + 3], mu * v.params[p + 4], mu * v.params[p + 5], v.jacobians,
                       v.chain_ptr, v.chain_idx, v.hessian)
    return 0


#: A frame's origin on a world plane: ``nᵀ(p_a − c)`` (1) [m]; params ``c`` (3), unit ``n`` (3).
PLANE = BlockKind("point on a plane", plane_residual, plane_second_order)


class PointOnPlane(Term):
    """``|nᵀ(p_frame − point)|`` [m]: the frame's origin on the plane through ``point`` [m, world] with normal
    ``normal`` (normalized), anywhere within it.

    Residual (1,): the signed distance to the plane [m]; a task term held to the linear tolerance.
    """

    level = "task"
    has_target = True
    fixed_layout = True
    task_type, task_keys, category = "point_on_plane", ("frame", "point", "normal"), "position"
    #: the entry's keys, for the task-file reference (docs/taskfile.md)
    task_doc: ClassVar[dict[str, str]] = {
        'frame': 'the frame held on the plane',
        'point': 'a point of the plane [m, world]',
        'normal': "the plane's normal [world]"
    }
    #: a robot, and an entry of this type for it (checked by tests/test_taskfile_doc.py)
    task_example: ClassVar[tuple[str, str]] = ('puma560', 'type = "point_on_plane"\nframe = "ee"\npoint = [0.0, 0.0, 0.3]\nnormal = [0, 0, 1]')

    @classmethod
    def from_entry(cls, entry: TermEntry) -> PointOnPlane:
        return cls(entry.text("frame"), entry.value("point"), entry.value("normal"), name=entry.name)

    def __init__(self, frame: str, point: Sequence[float], normal: Sequence[float], *, name: str | None = None):
        self.frame = frame
        self.frames = (frame,)
        self.name = name or f"plane[{frame}]"
        self.set_target((point, normal))

    def set_target(self, target: tuple[Sequence[float], Sequence[float]]) -> None:
        """Move the plane: ``(point (3,) [m, world], normal (3,))``."""
        point, normal = target
        self.point = as_vector(point, 3, lambda: f"plane point of {self.frame!r}")
        self.normal = unit_vector(normal, f"plane normal of {self.frame!r}")
        self._parameters = np.concatenate([self.point, self.normal])
        self._touch()

    def parameters(self, robot: Robot) -> np.ndarray:
        return self._parameters

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        return (Block(PLANE, B.NORM, 1, self.frames, self._parameters, tolerance=B.TOL_LINEAR),)

    def __repr__(self) -> str:
        return f"PointOnPlane({self.frame!r}, {np.round(self.point, 6).tolist()}, {np.round(self.normal, 6).tolist()})"
