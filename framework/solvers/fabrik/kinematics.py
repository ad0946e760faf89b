"""Pinocchio forward kinematics of single configurations, with a private ``pin.Data`` (no allocation per call).

:meth:`framework.model.robot.Robot.frame_placement` builds a ``pin.Data`` and converts coordinates on every call
(~0.1 ms); the solvers here call forward kinematics once per solve (FABRIK) or per iteration (Jacobian), so they
keep their own data and skip the coordinate conversion when joint coordinates already are Pinocchio's ``q``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ...model.joints import JointKind
from ...model.robot import Robot


class PointKinematics:
    """World position of one frame, and world placements of joints, for one configuration at a time.

    Args:
        robot: the robot.
        frame: the frame whose origin is the end-effector point.
    """

    def __init__(self, robot: Robot, frame: str) -> None:
        self.robot = robot
        self.model = robot.model
        self.data = robot.model.createData()
        self.frame_id = robot.frame_id(frame)
        simple = (JointKind.REVOLUTE, JointKind.PRISMATIC)
        self._direct = robot.model.nq == robot.n and all(
            j.kind in simple and j.idx_q == j.index for j in robot.joints
        )

    def q(self, x: np.ndarray) -> np.ndarray:
        """Pinocchio configuration ``(nq,)`` of joint coordinates ``x`` ``(n,)``."""
        return np.asarray(x, dtype=float) if self._direct else self.robot.to_pinocchio(x)

    def position(self, x: np.ndarray) -> np.ndarray:
        """World position ``(3,)`` [m] of the frame at ``x``."""
        pin.forwardKinematics(self.model, self.data, self.q(x))
        return pin.updateFramePlacement(self.model, self.data, self.frame_id).translation.copy()

    def joint_placement(self, x: np.ndarray, joint_id: int) -> pin.SE3:
        """World placement of Pinocchio joint ``joint_id`` (0: the world) at ``x``."""
        pin.forwardKinematics(self.model, self.data, self.q(x))
        return self.data.oMi[joint_id].copy()
