"""Orientation of a frame: the rotation between the frame and a target (paper 002 eq. 6-15).

Residual ``r = log(R_targetᵀ R(x))`` (3,) [rad]: its norm is the angle φ ∈ [0, π] of the relative rotation.
Value ``ρ(r) = sin(‖r‖/2)`` — the norm of the relative quaternion's vector part, paper 002's measure: 0 for
equal rotations, 1 for a half turn. Success holds the angle ``‖r‖`` to the angular tolerance [rad].
Quaternion targets are ``(x, y, z, w)`` (scalar last, as ``scipy.spatial.transform.Rotation``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import TaskError
from ..robot import Robot
from ..rotations import rotation_defects, rotation_target
from . import blocks as B
from .base import Term, finite_rows
from .program import Block


class Orientation(Term):
    """``sin(φ/2)`` (unitless) for the angle φ between the frame's rotation and the target's.

    The target is a ``(3, 3)`` rotation matrix (or a ``pinocchio.SE3``'s rotation), or a quaternion given with its
    order named: ``quat_xyzw=`` (scipy's order) or ``quat_wxyz=`` (Eigen's constructor order, ROS messages spell
    out x, y, z, w). A bare 4-vector as ``target`` is read as ``(x, y, z, w)``.
    """

    level = "task"
    has_target = True
    fixed_layout = True

    def __init__(self, frame: str, target: Sequence[float] | np.ndarray | None = None, *,
                 quat_xyzw: Sequence[float] | None = None, quat_wxyz: Sequence[float] | None = None,
                 name: str | None = None):
        self.frame = frame
        self.frames = (frame,)
        self.name = name or f"orientation[{frame}]"
        self.set_target(target, quat_xyzw=quat_xyzw, quat_wxyz=quat_wxyz)

    def set_target(self, target: Sequence[float] | np.ndarray | None = None, *,
                   quat_xyzw: Sequence[float] | None = None, quat_wxyz: Sequence[float] | None = None) -> None:
        """Change the target rotation (world frame): a matrix, or a quaternion with its order named."""
        self.target = rotation_target(target, quat_xyzw, quat_wxyz, f"orientation target of {self.frame!r}")
        self._touch()

    def target_parameters(self, robot: Robot, targets) -> np.ndarray:
        """``(B, 9)`` row-major target rotations of a batch: ``(B, 3, 3)`` matrices are validated at once (as
        :meth:`set_target` validates one); other forms one by one."""
        if not (isinstance(targets, np.ndarray) and targets.ndim == 3 and targets.shape[1:] == (3, 3)):
            return super().target_parameters(robot, targets)
        what = f"orientation targets of {self.frame!r}"
        R = finite_rows(targets, (3, 3), what)
        bad = np.flatnonzero(rotation_defects(R))
        if bad.size:
            raise TaskError(f"{what}: item {bad[0]} is not a rotation matrix (RᵀR = I, det > 0)")
        return R.reshape(-1, 9)

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        return (Block(B.ORIENTATION, B.HALFSIN, 3, self.frames, self.target.ravel(), tolerance=B.TOL_ANGULAR),)
