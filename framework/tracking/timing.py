"""Joint velocity and acceleration limits along timed paths: what they are (the URDF's ``<limit velocity>``, times a
factor; acceleration limits given), the step a limit allows towards a configuration (:func:`command`, compiled:
the servo loop's and the limited tracking's), and the fastest time scaling of a tracked path that keeps them
(:func:`retimed`).

A path's motion is judged waypoint to waypoint: the velocity of segment ``k`` is ``(q_k - q_{k-1}) / Δt_k`` (the
configuration before the first waypoint counts as one interval, the path's first, before it), its acceleration
``(v_k - v_{k-1}) / Δt_k``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..compiled.native import compiled
from ..errors import TaskError
from ..model.robot import Robot


class JointLimits(NamedTuple):
    """``velocity`` and ``acceleration`` ``(n,)`` [rad/s, m/s; rad/s², m/s²] (``inf``: none)."""

    velocity: np.ndarray
    acceleration: np.ndarray


def joint_limits(robot: Robot, velocity_scale: float = 1.0,
                 acceleration: float | np.ndarray | None = None) -> JointLimits:
    """The robot file's velocity limits times ``velocity_scale``, and ``acceleration`` (a number, ``(n,)`` or
    ``None``: none)."""
    if isinstance(velocity_scale, bool) or not (isinstance(velocity_scale, (int, float))
                                                 and 0 < velocity_scale < np.inf):
        raise TaskError(f"velocity_scale must be a factor > 0; got {velocity_scale!r}")
    a = np.full(robot.n, np.inf) if acceleration is None else positive_limits(acceleration, robot.n, "acceleration")
    return JointLimits(velocity_limits(robot) * float(velocity_scale), a)


def velocity_limits(robot: Robot) -> np.ndarray:
    """``(n,)`` each coordinate's velocity limit from the robot file [rad/s, m/s] (``inf`` where it gives none or
    0)."""
    limits = np.full(robot.n, np.inf)
    given = np.asarray(robot.model.velocityLimit, dtype=float)
    for joint in robot.joints:
        for k, i in enumerate(joint.coordinates):
            value = given[joint.idx_v + k] if joint.idx_v + k < given.size else 0.0
            limits[i] = value if np.isfinite(value) and value > 0 else np.inf
    return limits


def positive_limits(value, n: int, what: str) -> np.ndarray:
    """``(n,)`` limits from a number or ``n`` numbers, each > 0."""
    try:
        limits = np.broadcast_to(np.asarray(value, dtype=float), (n,)).copy()
    except (TypeError, ValueError):
        limits = None
    if limits is None or not np.all(limits > 0):
        raise TaskError(f"{what} limits must be numbers > 0 (one, or one per coordinate: {n}); got {value!r}")
    return limits


@compiled
def command(q, velocity, goal, last_goal, v_max, a_max, lower, upper, dt, q_next, v_next, held):
    """The next configuration ``q_next`` and velocity ``v_next`` ``(n,)`` towards ``goal`` (moving from
    ``last_goal`` in ``dt``) from ``q`` moving at ``velocity``: the step scaled by one factor so that no joint
    exceeds ``v_max`` nor the speed from which it still meets the goal without overshooting (the goal's own speed
    plus ``√(2 a_max d)``), then each joint's change of velocity clamped to ``± a_max dt``, the result kept in
    ``[lower, upper]``; ``held`` ``bool (n,)``: the joints a limit held short of the goal. Returns how many."""
    n = q.shape[0]
    scale = 1.0
    for i in range(n):
        wanted = abs(goal[i] - q[i]) / dt
        if wanted > 0.0:
            cap = min(v_max[i], abs(goal[i] - last_goal[i]) / dt + np.sqrt(2.0 * a_max[i] * abs(goal[i] - q[i])))
            scale = min(scale, cap / wanted)
    count = 0
    for i in range(n):
        v = scale * (goal[i] - q[i]) / dt
        change = a_max[i] * dt
        v = min(velocity[i] + change, max(velocity[i] - change, v))
        v = min(v_max[i], max(-v_max[i], v))
        x = min(upper[i], max(lower[i], q[i] + v * dt))
        v_next[i] = (x - q[i]) / dt
        q_next[i] = x
        held[i] = abs(x - goal[i]) > 1e-12
        count += held[i]
    return count


def segment_intervals(times: np.ndarray) -> np.ndarray:
    """``(K,)`` the interval of each segment, the first (from the configuration before the path) as long as the
    path's first interval (1 s for a path of one waypoint)."""
    gaps = np.diff(times)
    return np.concatenate([[gaps[0] if gaps.size else 1.0], gaps])


def motion(initial: np.ndarray, configurations: np.ndarray, intervals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(velocities (K, n), accelerations (K, n))`` of the segments (the first acceleration from rest)."""
    steps = np.diff(np.vstack([initial, configurations]), axis=0)
    V = steps / intervals[:, None]
    A = np.diff(np.vstack([np.zeros(V.shape[1]), V]), axis=0) / intervals[:, None]
    return V, A


def retimed(times: np.ndarray, initial: np.ndarray, configurations: np.ndarray, limits: JointLimits,
            passes: int = 200) -> np.ndarray:
    """The fastest times ``(K,)`` for the tracked ``configurations`` that keep ``limits``: each segment as long as
    the path gives it, or as its joints' velocity limits need; then, with acceleration limits, the segments around
    a too large change of velocity stretched together until it fits (``passes`` sweeps at most). The first
    waypoint keeps its time."""
    intervals = segment_intervals(times)
    steps = np.abs(np.diff(np.vstack([initial, configurations]), axis=0))
    intervals = _tied(np.maximum(intervals, (steps / limits.velocity).max(axis=1)))
    if np.isfinite(limits.acceleration).any():
        for _ in range(passes):
            _, A = motion(initial, configurations, intervals)
            ratio = (np.abs(A) / limits.acceleration).max(axis=1)
            if ratio.max() <= 1.0:
                break
            stretch = np.sqrt(np.maximum(ratio, 1.0)) * (1 + 1e-6)  # segment k and the one before it, together
            stretch[:-1] = np.maximum(stretch[:-1], stretch[1:])
            intervals = _tied(intervals * stretch)
    return times[0] + np.concatenate([[0.0], np.cumsum(intervals[1:])])


def _tied(intervals: np.ndarray) -> np.ndarray:
    """The segment intervals with the first (before the path) as long as the path's first, as times express them."""
    if intervals.size > 1:
        intervals[0] = intervals[1] = max(intervals[0], intervals[1])
    return intervals
