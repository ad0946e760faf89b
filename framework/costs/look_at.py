"""Look-at of a frame axis: a camera or a sensor aimed at a world point, free to turn about its line of sight."""

from __future__ import annotations

from typing import ClassVar

from collections.abc import Sequence

import numpy as np

from ..model.robot import Robot
from . import blocks as B
from .base import Term, TermEntry, as_vector
from .direction import unit_vector
from .kinds import BlockKind
from .program import Block
from .workspace import RESIDUAL, views


def look_at_residual(ws) -> int:
    """``w − u`` (``w = R_a e``, ``u`` the unit line of sight to ``t``) and its Jacobian
    ``ω_i × w + (I − uuᵀ) J_p,i / ‖t − p_a‖``; zero at ``p_a = t``."""
    v = views(ws)
    block, row, n = v.blocks[ws.block], ws.row, ws.n
    p, fa, params, P, Jf = block.params, block.fa, v.params, v.poses, v.jacobians
    e0, e1, e2 = params[p], params[p + 1], params[p + 2]
    w0 = P[fa, 0] * e0 + P[fa, 1] * e1 + P[fa, 2] * e2
    w1 = P[fa, 3] * e0 + P[fa, 4] * e1 + P[fa, 5] * e2
    w2 = P[fa, 6] * e0 + P[fa, 7] * e1 + P[fa, 8] * e2
    v0, v1, v2 = params[p + 3] - P[fa, 9], params[p + 4] - P[fa, 10], params[p + 5] - P[fa, 11]
    dist = np.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    if dist == 0.0:
        v.r[row], v.r[row + 1], v.r[row + 2] = 0.0, 0.0, 0.0
        if ws.mode != RESIDUAL:
            for c in range(3):
                for i in range(n):
                    v.J[row + c, i] = 0.0
        return 3
    u0, u1, u2 = v0 / dist, v1 / dist, v2 / dist
    v.r[row], v.r[row + 1], v.r[row + 2] = w0 - u0, w1 - u1, w2 - u2
    if ws.mode == RESIDUAL:
        return 3
    for i in range(n):
        o0, o1, o2 = Jf[fa, 3, i], Jf[fa, 4, i], Jf[fa, 5, i]
        j0, j1, j2 = Jf[fa, 0, i], Jf[fa, 1, i], Jf[fa, 2, i]
        uj = u0 * j0 + u1 * j1 + u2 * j2
        v.J[row, i] = o1 * w2 - o2 * w1 + (j0 - u0 * uj) / dist
        v.J[row + 1, i] = o2 * w0 - o0 * w2 + (j1 - u1 * uj) / dist
        v.J[row + 2, i] = o0 * w1 - o1 * w0 + (j2 - u2 * uj) / dist
    return 3


#: A frame axis ``e`` pointing at a world point ``t``: ``R_a e − u``, ``u = (t − p_a)/‖t − p_a‖`` (3), its norm
#: ``2 sin(θ/2)``; params ``e, t`` (6); its second order is left to Gauss-Newton.
LOOK_AT = BlockKind("look-at", look_at_residual)


class LookAt(Term):
    """The frame's ``axis`` (frame coordinates, default its z axis) pointing at the world ``point`` [m]: a camera
    or a sensor aimed at a target, free to turn about its line of sight (BioIK's look-at goal).

    Residual (3,): ``R e − u`` with ``u`` the unit vector from the frame origin to the point; its norm is
    ``2 sin(θ/2)`` of the angle θ between the axis and the line of sight (the value; ≈ θ for small angles); a
    task term held to the angular tolerance.
    """

    task_type, task_keys = "look_at", ("frame", "point", "axis")
    #: the entry's keys, for the task-file reference (docs/taskfile.md)
    task_doc: ClassVar[dict[str, str]] = {
        'frame': 'the frame that looks',
        'point': 'the point looked at [m, world]',
        'axis': "the frame's viewing axis [frame] (default [0, 0, 1])"
    }
    #: a robot, and an entry of this type for it (checked by tests/test_taskfile_doc.py)
    task_example: ClassVar[tuple[str, str]] = ('puma560', 'type = "look_at"\nframe = "ee"\npoint = [0.5, 0.2, 0.0]')

    @classmethod
    def from_entry(cls, entry: TermEntry) -> LookAt:
        return cls(entry.text("frame"), entry.value("point"), axis=entry.value("axis", (0.0, 0.0, 1.0)),
                   name=entry.name)

    level = "task"
    has_target = True

    def __init__(self, frame: str, point: Sequence[float], *, axis: Sequence[float] = (0.0, 0.0, 1.0),
                 name: str | None = None):
        self.frame = frame
        self.frames = (frame,)
        self.axis = unit_vector(axis, f"axis of look-at term on {frame!r}")
        self.name = name or f"look_at[{frame}]"
        self.set_target(point)

    def set_target(self, point: Sequence[float]) -> None:
        """Move the point looked at (3,) [m, world]."""
        self.point = as_vector(point, 3, f"look-at point of {self.frame!r}")
        self._touch()

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        return (Block(LOOK_AT, B.NORM, 3, self.frames, np.concatenate([self.axis, self.point]),
                      tolerance=B.TOL_ANGULAR),)

    def __repr__(self) -> str:
        return f"LookAt({self.frame!r}, {np.round(self.point, 6).tolist()}, axis={self.axis.tolist()})"
