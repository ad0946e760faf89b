"""Relative position of two frames: the coordinated dual-arm task (paper 000 eq. 8, paper 001)."""

from __future__ import annotations

from typing import ClassVar

from collections.abc import Sequence

import numpy as np

from ..model.robot import Robot
from . import blocks as B
from .base import Term, TermEntry, as_vector
from .curvature import position_curvature
from .kinds import BlockKind
from .position import translation_jacobian
from .program import Block
from .workspace import JACOBIAN_ONLY, RESIDUAL, views


def relative_residual(ws) -> int:
    """``p_b − p_a − o`` (3) [m]; Jacobian ``J_p,b − J_p,a``."""
    v = views(ws)
    block, row = v.blocks[ws.block], ws.row
    p, fa, fb = block.params, block.fa, block.fb
    if ws.mode != JACOBIAN_ONLY:
        for c in range(3):
            v.r[row + c] = v.poses[fb, 9 + c] - v.poses[fa, 9 + c] - v.params[p + c]
    if ws.mode != RESIDUAL:
        translation_jacobian(v.jacobians, fb, fa, v.J, row, ws.n)
    return 3


def relative_second_order(ws) -> int:
    """``Σ μ_c ∇²(p_b − p_a)_c``: exact (the product of exponentials)."""
    v = views(ws)
    block, mu = v.blocks[ws.block], v.multipliers
    position_curvature(block.fa, -mu[0], -mu[1], -mu[2], v.jacobians, v.chain_ptr, v.chain_idx, v.hessian)
    position_curvature(block.fb, mu[0], mu[1], mu[2], v.jacobians, v.chain_ptr, v.chain_idx, v.hessian)
    return 0


#: Frame ``b``'s origin at an offset from frame ``a``'s (world axes): ``p_b − p_a − o`` (3) [m], params ``o`` (3).
RELATIVE = BlockKind("relative position", relative_residual, relative_second_order)


class RelativePosition(Term):
    """``‖p_b(x) − (p_a(x) + offset)‖₂`` [m]: frame ``b`` held at ``offset`` (world axes) from frame ``a``.

    With a fixed target for ``a`` this is paper 000's coordinated task ``t*_b = t*_a + t_r``, expressed on the
    actual position of ``a`` (paper 001's relative-position error of arm B). Residual ``p_b − p_a − offset``.
    """

    task_type, task_keys, category = "relative_position", ("frame_a", "frame_b", "offset"), "position"
    #: the entry's keys, for the task-file reference (docs/taskfile.md)
    task_doc: ClassVar[dict[str, str]] = {
        'frame_a': 'the first frame',
        'frame_b': 'the second frame',
        'offset': "frame_b's position minus frame_a's [m, world]"
    }
    #: a robot, and an entry of this type for it (checked by tests/test_taskfile_doc.py)
    task_example: ClassVar[tuple[str, str]] = ('youbot_dual', 'type = "relative_position"\nframe_a = "arm1_ee"\nframe_b = "arm2_ee"\noffset = [0.0, 0.3, 0.0]')

    @classmethod
    def from_entry(cls, entry: TermEntry) -> RelativePosition:
        return cls(entry.text("frame_a"), entry.text("frame_b"), entry.value("offset"), name=entry.name)

    level = "task"
    has_target = True
    fixed_layout = True

    def __init__(self, frame_a: str, frame_b: str, offset: Sequence[float], *, name: str | None = None):
        self.frame_a, self.frame_b = frame_a, frame_b
        self.frames = (frame_a, frame_b)
        self.name = name or f"relative[{frame_a}->{frame_b}]"
        self.set_target(offset)

    def set_target(self, offset: Sequence[float]) -> None:
        """Change the offset ``(3,)`` [m, world axes] of frame ``b`` from frame ``a``."""
        self.offset = as_vector(offset, 3, f"relative offset of {self.frame_b!r} from {self.frame_a!r}")
        self._touch()

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        return (Block(RELATIVE, B.NORM, 3, self.frames, self.offset, tolerance=B.TOL_LINEAR),)

    def target_points(self, robot: Robot, x: np.ndarray) -> dict[str, np.ndarray]:
        return {self.frame_b: robot.frame_poses(x, self.frame_a).positions[0, 0] + self.offset}
