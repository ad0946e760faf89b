"""Joint kinds: how a joint moves, and how many search coordinates it has (the vocabulary of the robot model
and of the compiled kinematics)."""

from __future__ import annotations

import enum


class JointKind(str, enum.Enum):
    """How a joint moves, and how many search coordinates it has."""

    REVOLUTE = "revolute"  # 1 angle [rad], bounded
    CONTINUOUS = "continuous"  # 1 angle [rad], unbounded (Pinocchio stores cos, sin)
    PRISMATIC = "prismatic"  # 1 displacement [m]
    PLANAR = "planar"  # x [m], y [m], θ [rad] in the parent's xy-plane (Pinocchio stores x, y, cos, sin)

    @property
    def width(self) -> int:
        """Number of search coordinates of one joint of this kind."""
        return 3 if self is JointKind.PLANAR else 1
