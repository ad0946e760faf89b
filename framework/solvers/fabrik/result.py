"""What one position-IK solve returns, for FABRIK, M-FABRIK and the Jacobian baselines alike."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class ReachResult:
    """The outcome of one solve for an end-effector position.

    Attributes:
        configuration: joint coordinates ``(n,)`` of the robot [rad / m]; ``robot.frame_placement(configuration,
            frame)`` reproduces the reached position.
        position_error: ``‖target - reached‖`` [m], computed by Pinocchio's forward kinematics.
        iterations: full iterations run (FABRIK: forward + backward pass; Jacobian: one update).
        wall_time: seconds spent in the solve, set-up included.
        success: ``position_error <= tolerance``.
        reason: why it stopped: ``"converged"``, ``"max_iterations"``, ``"stalled"``, or ``"unreachable: ..."``
            (then ``configuration`` is the start configuration and ``iterations`` is 0).
        solver: ``"fabrik"``, ``"m-fabrik"``, ``"pinv"`` or ``"dls"``.
        base_path: ``(iterations + 1, 3)`` base pose ``(x [m], y [m], θ [rad])`` at the start and after each
            iteration; ``(0, 3)`` for a robot without a mobile base.
        error_history: ``(iterations + 1,)`` position error [m] at the start and after each iteration.
    """

    configuration: np.ndarray
    position_error: float
    iterations: int
    wall_time: float
    success: bool
    reason: str
    solver: str
    base_path: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)), repr=False)
    error_history: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
