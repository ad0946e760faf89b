"""Cone of a frame axis: the axis within an angle of a world direction (keep a camera roughly level)."""

from __future__ import annotations

from typing import ClassVar

from collections.abc import Sequence

import numpy as np

from ..errors import TaskError
from ..model.robot import Robot
from . import blocks as B
from .base import TermEntry
from .direction import Direction, axis_world
from .kinds import BlockKind
from .program import Block
from .workspace import RESIDUAL, views


def cone_residual(ws) -> int:
    """``θ − α`` when the axis ``w = R_a e`` is outside the cone (0 inside), ``θ = atan2(‖d × w‖, d·w)``, and its
    Jacobian ``dθ = cosθ (d×w)·(d×dw)/sinθ − sinθ d·dw`` with ``dw = ω_i × w`` (zero inside the cone)."""
    v = views(ws)
    block, row, n = v.blocks[ws.block], ws.row, ws.n
    p, fa, params, Jf = block.params, block.fa, v.params, v.jacobians
    w0, w1, w2, d0, d1, d2 = axis_world(v.poses, fa, params, p)
    c0, c1, c2 = d1 * w2 - d2 * w1, d2 * w0 - d0 * w2, d0 * w1 - d1 * w0
    s = np.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
    co = d0 * w0 + d1 * w1 + d2 * w2
    theta = np.arctan2(s, co)
    active = theta > params[p + 6]
    v.r[row] = theta - params[p + 6] if active else 0.0
    if ws.mode == RESIDUAL:
        return 1
    for i in range(n):
        g = 0.0
        if active and s > 0.0:
            o0, o1, o2 = Jf[fa, 3, i], Jf[fa, 4, i], Jf[fa, 5, i]
            e0, e1, e2 = o1 * w2 - o2 * w1, o2 * w0 - o0 * w2, o0 * w1 - o1 * w0  # dw = ω × w
            x0, x1, x2 = d1 * e2 - d2 * e1, d2 * e0 - d0 * e2, d0 * e1 - d1 * e0  # d × dw
            g = co * (c0 * x0 + c1 * x1 + c2 * x2) / s - s * (d0 * e0 + d1 * e1 + d2 * e2)
        v.J[row, i] = g
    return 1


#: A frame axis ``e`` within ``α`` of a world direction ``d``: ``θ − α`` outside the cone, else 0 (1) [rad], a
#: hinge; params ``e, d, α`` (7); its second order is left to Gauss-Newton.
CONE = BlockKind("cone", cone_residual, hinge=True)


class Cone(Direction):
    """The frame's ``axis`` within ``max_angle`` [rad] of the world ``direction`` (a cone around it): zero inside,
    the angle in excess outside ("keep the camera roughly level", BioIK's cone goal).

    Residual (1,): ``θ − max_angle`` when the axis is outside the cone, else 0 [rad]; a task term held to the
    angular tolerance.
    """

    task_type, task_keys = "cone", ("frame", "direction", "axis", "max_angle")
    #: the entry's keys, for the task-file reference (docs/taskfile.md)
    task_doc: ClassVar[dict[str, str]] = {
        'frame': 'the frame whose axis is held',
        'direction': "the cone's axis [world] (3 numbers)",
        'axis': "the frame's axis [frame] (default [0, 0, 1])",
        'max_angle': "the cone's half angle [rad]"
    }
    #: a robot, and an entry of this type for it (checked by tests/test_taskfile_doc.py)
    task_example: ClassVar[tuple[str, str]] = ('puma560', 'type = "cone"\nframe = "ee"\ndirection = [0, 0, -1]\nmax_angle = "pi/8"')

    @classmethod
    def from_entry(cls, entry: TermEntry) -> Cone:
        return cls(entry.text("frame"), entry.value("direction"), entry.number("max_angle"),
                   axis=entry.value("axis", (0.0, 0.0, 1.0)), name=entry.name)

    def __init__(self, frame: str, direction: Sequence[float], max_angle: float, *,
                 axis: Sequence[float] = (0.0, 0.0, 1.0), name: str | None = None):
        if not (isinstance(max_angle, (int, float)) and np.isfinite(max_angle) and 0 <= max_angle <= np.pi):
            raise TaskError(f"cone max_angle must be an angle in [0, pi] rad; got {max_angle!r}")
        self.max_angle = float(max_angle)
        super().__init__(frame, direction, axis=axis, name=name or f"cone[{frame}]")

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        params = np.concatenate([self.axis, self.direction, [self.max_angle]])
        return (Block(CONE, B.NORM, 1, self.frames, params, tolerance=B.TOL_ANGULAR),)

    def __repr__(self) -> str:
        return (f"Cone({self.frame!r}, {np.round(self.direction, 6).tolist()}, max_angle={self.max_angle:g}, "
                f"axis={self.axis.tolist()})")
