"""Paper 001's conventional method: relative Jacobian with null-space task priority, for two coordinated arms.

The dual-arm system is one redundant manipulator (all joints of both arms, ``n`` coordinates). Tasks, in
priority order (paper 001, section "Simulation results"):

1. relative position ``p_r = p_B − p_A`` at ``t_r`` [m]: ``J_r = J_B − J_A``, ``e_r = t_r − p_r``, gain ``K_r = 0.3``;
2. position of arm A at the waypoint ``t``: ``J_A``, ``e_A = t − p_A``, gain ``K_A = 0.7``.

One iteration (task-priority inverse kinematics of Nakamura / Siciliano)::

    Δq₁ = J_r⁺ K_r e_r
    Δq  = Δq₁ + (J_A N_r)⁺ (K_A e_A − J_A Δq₁),   N_r = I − J_r⁺ J_r

with SVD pseudo-inverses (:func:`~framework.solvers.baselines.jacobian.svd_pinv`). When ``J_A N_r`` loses rank (the
arms' motions conflict, or one arm is stretched) its pseudo-inverse amplifies the error: the abrupt joint
jumps paper 001 reports.
"""

from __future__ import annotations

import numpy as np

from ...model.robot import Robot
from .jacobian import position_and_jacobian, svd_pinv

#: Paper 001: gain of the priority (relative) task and of the secondary (arm A position) task.
RELATIVE_GAIN, SECONDARY_GAIN = 0.3, 0.7


def relative_jacobian_step(
    robot: Robot,
    x: np.ndarray,
    frame_a: str,
    frame_b: str,
    target: np.ndarray,
    offset: np.ndarray,
    *,
    relative_gain: float = RELATIVE_GAIN,
    secondary_gain: float = SECONDARY_GAIN,
    rcond: float = 1e-6,
) -> tuple[np.ndarray, float, float]:
    """One task-priority step from ``x`` ``(n,)``.

    Returns ``(Δx (n,), ‖e_r‖ [m], ‖e_A‖ [m])`` with the errors measured at ``x`` (before the step).
    """
    p_a, J_a = position_and_jacobian(robot, x, frame_a)
    p_b, J_b = position_and_jacobian(robot, x, frame_b)
    e_r = offset - (p_b - p_a)
    e_a = target - p_a
    J_r = J_b - J_a
    J_r_pinv = svd_pinv(J_r, rcond)
    dx1 = J_r_pinv @ (relative_gain * e_r)
    N_r = np.eye(robot.n) - J_r_pinv @ J_r
    dx = dx1 + svd_pinv(J_a @ N_r, rcond) @ (secondary_gain * e_a - J_a @ dx1)
    return dx, float(np.linalg.norm(e_r)), float(np.linalg.norm(e_a))


def relative_jacobian_ik(
    robot: Robot,
    x0: np.ndarray,
    frame_a: str,
    frame_b: str,
    target: np.ndarray,
    offset: np.ndarray,
    *,
    max_iterations: int = 100,
    tolerance: float = 1e-6,
    relative_gain: float = RELATIVE_GAIN,
    secondary_gain: float = SECONDARY_GAIN,
    rcond: float = 1e-6,
) -> tuple[np.ndarray, int]:
    """Iterate :func:`relative_jacobian_step` (clipped to the box) until both errors are below ``tolerance`` [m].

    Returns ``(x (n,), Jacobian evaluations)``.
    """
    x = np.array(x0, dtype=float)
    target, offset = np.asarray(target, dtype=float), np.asarray(offset, dtype=float)
    for iteration in range(1, max_iterations + 1):
        dx, e_r, e_a = relative_jacobian_step(
            robot,
            x,
            frame_a,
            frame_b,
            target,
            offset,
            relative_gain=relative_gain,
            secondary_gain=secondary_gain,
            rcond=rcond,
        )
        if max(e_r, e_a) < tolerance:
            return x, iteration
        x = np.clip(x + dx, robot.lower, robot.upper)
    return x, max_iterations
