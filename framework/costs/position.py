"""Position of a frame: Euclidean distance to a target point (paper 000 eq. 9, paper 002 eq. 5)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..kinematics import FramePoses
from ..robot import Robot
from .base import LocalKinematics, Term, as_vector, row_norms


class Position(Term):
    """``‖p_frame(x) − target‖₂`` [m], with ``p_frame`` and ``target`` in the world frame."""

    is_task = True

    def __init__(self, frame: str, target: Sequence[float], *, name: str | None = None):
        self.frame = frame
        self.frames = (frame,)
        self.target = as_vector(target, 3, f"position target of {frame!r}")
        self.name = name or f"position[{frame}]"

    def value(self, robot: Robot, X: np.ndarray, poses: FramePoses) -> np.ndarray:
        return np.linalg.norm(poses.position(self.frame) - self.target, axis=-1)

    def bind(self, robot: Robot):
        target = self.target

        def value(X: np.ndarray, poses: FramePoses) -> np.ndarray:
            return row_norms(poses.position(self.frame) - target)

        return value

    def residual(self, robot: Robot, x: np.ndarray, local: LocalKinematics) -> np.ndarray:
        return local.placement(self.frame).translation - self.target

    def jacobian(self, robot: Robot, x: np.ndarray, local: LocalKinematics) -> np.ndarray:
        return local.frame_jacobian(self.frame)[:3]
