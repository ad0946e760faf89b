"""Position of a frame: Euclidean distance to a target point (paper 000 eq. 9, paper 002 eq. 5)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..robot import Robot
from . import blocks as B
from .base import Term, as_vector, finite_rows
from .program import Block


class Position(Term):
    """``‖p_frame(x) − target‖₂`` [m], with ``p_frame`` and ``target`` in the world frame.

    Residual ``p_frame(x) − target`` (3,) [m]; a task term held to the linear tolerance.
    """

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

    def target_parameters(self, robot: Robot, targets: Sequence) -> np.ndarray:
        """``(B, 3)`` target points [m, world] of a batch, validated at once."""
        return finite_rows(targets, (3,), f"position targets of {self.frame!r}")

    def parameters(self, robot: Robot) -> np.ndarray:
        return self.target

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        return (Block(B.POSITION, B.NORM, 3, self.frames, self.target, tolerance=B.TOL_LINEAR),)

    def target_points(self, robot: Robot, x: np.ndarray) -> dict[str, np.ndarray]:
        return {self.frame: self.target}

    def __repr__(self) -> str:
        return f"Position({self.frame!r}, {np.round(self.target, 6).tolist()})"
