"""Relative position of two frames: the coordinated dual-arm task (paper 000 eq. 8, paper 001)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..robot import Robot
from . import blocks as B
from .base import Term, as_vector
from .program import Block


class RelativePosition(Term):
    """``‖p_b(x) − (p_a(x) + offset)‖₂`` [m]: frame ``b`` held at ``offset`` (world axes) from frame ``a``.

    With a fixed target for ``a`` this is paper 000's coordinated task ``t*_b = t*_a + t_r``, expressed on the
    actual position of ``a`` (paper 001's relative-position error of arm B). Residual ``p_b − p_a − offset``.
    """

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
        return (Block(B.RELATIVE, B.NORM, 3, self.frames, self.offset, tolerance=B.TOL_LINEAR),)

    def target_points(self, robot: Robot, x: np.ndarray) -> dict[str, np.ndarray]:
        return {self.frame_b: robot.frame_poses(x, self.frame_a).positions[0, 0] + self.offset}


class RelativePose(Term):
    """The pose of ``frame_b`` in ``frame_a`` held at ``offset`` (two hands holding one object: the object's grasp
    poses, moving with the hands wherever they go): ``‖R_aᵀ(p_b − p_a) − o‖ + sin(φ/2)``, ``φ`` the angle of
    ``R_oᵀ R_aᵀ R_b``. ``offset``: a ``pinocchio.SE3``, a 4x4 matrix or a ``(position, rotation)`` pair, in
    ``frame_a``'s coordinates.

    Residuals (3 + 3): the position error in ``frame_a`` [m] (linear tolerance) and the rotation vector [rad]
    (angular tolerance); their second order is left to Gauss-Newton in the Newton phase.
    """

    level = "task"
    has_target = True
    fixed_layout = True

    def __init__(self, frame_a: str, frame_b: str, offset, *, name: str | None = None):
        self.frames = (frame_a, frame_b)
        self.name = name or f"relative_pose[{frame_a}, {frame_b}]"
        self.set_target(offset)

    def set_target(self, offset) -> None:
        """Move the offset (pose of ``frame_b`` in ``frame_a``)."""
        from .pose import pose_from

        self.position, self.rotation = pose_from(offset, f"offset of {self.name}")
        self._touch()

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        return (Block(B.RELATIVE_LOCAL, B.NORM, 3, self.frames, self.position, tolerance=B.TOL_LINEAR),
                Block(B.RELATIVE_ROTATION, B.HALFSIN, 3, self.frames, self.rotation.ravel(), tolerance=B.TOL_ANGULAR))
