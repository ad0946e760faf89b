"""Relative position of two frames: the coordinated dual-arm task (paper 000 eq. 8, paper 001)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..kinematics import FramePoses
from ..robot import Robot
from .base import LocalKinematics, Term, as_vector, row_norms


class RelativePosition(Term):
    """``‖p_b(x) − (p_a(x) + offset)‖₂`` [m]: frame ``b`` held at ``offset`` (world axes) from frame ``a``.

    With a fixed target for ``a`` this is paper 000's coordinated task ``t*_b = t*_a + t_r``, expressed on the
    actual position of ``a`` (paper 001's relative-position error of arm B).
    """

    is_task = True

    def __init__(self, frame_a: str, frame_b: str, offset: Sequence[float], *, name: str | None = None):
        self.frame_a, self.frame_b = frame_a, frame_b
        self.frames = (frame_a, frame_b)
        self.offset = as_vector(offset, 3, f"relative offset of {frame_b!r} from {frame_a!r}")
        self.name = name or f"relative[{frame_a}->{frame_b}]"

    def value(self, robot: Robot, X: np.ndarray, poses: FramePoses) -> np.ndarray:
        r = poses.position(self.frame_b) - poses.position(self.frame_a) - self.offset
        return np.linalg.norm(r, axis=-1)

    def bind(self, robot: Robot):
        def value(X: np.ndarray, poses: FramePoses) -> np.ndarray:
            return row_norms(poses.position(self.frame_b) - poses.position(self.frame_a) - self.offset)

        return value

    def residual(self, robot: Robot, x: np.ndarray, local: LocalKinematics) -> np.ndarray:
        return local.placement(self.frame_b).translation - local.placement(self.frame_a).translation - self.offset

    def jacobian(self, robot: Robot, x: np.ndarray, local: LocalKinematics) -> np.ndarray:
        return local.frame_jacobian(self.frame_b)[:3] - local.frame_jacobian(self.frame_a)[:3]
