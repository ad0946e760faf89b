"""A servo loop: one control tick at a time, the robot's state held, joint velocity and acceleration limits hard.

``Servo(robot, objective)`` holds the configuration and its velocity; :meth:`Servo.step` answers one tick of
``dt`` seconds in two parts:

1. **Where to go**: the task's targets as they are now (moved by the caller between ticks, or by ``step``'s
   ``target`` for a servo made by :meth:`Servo.pose`) solved by the local engine from the last tick's goal (a
   moving target's goal moves little: one or two iterations), within the joint bounds — or as near as it gets, for
   a target beyond reach.
2. **How far this tick**: the step towards that goal, every joint scaled by one factor (the joint-space direction
   kept) so that no joint exceeds its velocity limit (the URDF's ``<limit velocity>``, times ``velocity_scale``) nor,
   with ``acceleration``, the speed from which it can still meet the goal without overshooting (the goal's own
   speed plus ``√(2 a d)``); then each joint's change of velocity clamped to ``± a dt``. The limits hold by construction (:func:`command`, compiled).

A step says whether the goal is met, which joints a limit held back, and why the task is missed: held back by the
limits (the target moves faster than the robot may), or the goal itself misses it (beyond reach, a singularity).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..compiled.native import compiled
from ..costs import Objective, Pose, Term
from ..costs.problem import Problem
from ..engine import LocalSettings, solve_local
from ..engine.draws import stream
from ..errors import TaskError
from ..model.robot import Robot


@dataclass(frozen=True)
class ServoStep:
    """One tick's answer (its arrays are read-only: the servo's own state).

    Attributes:
        q: ``(n,)`` the configuration to command [rad / m].
        velocity: ``(n,)`` ``(q - q_before) / dt`` [rad/s, m/s].
        goal: ``(n,)`` where the task is met (or most nearly, when it cannot be).
        reached: ``q`` is the goal and the goal meets the task (within the tolerance).
        goal_reached: the goal meets the task.
        held: ``bool (n,)`` the coordinates a velocity or acceleration limit held short of the goal.
        reason: ``""`` when reached; else why not.
    """

    q: np.ndarray
    velocity: np.ndarray
    goal: np.ndarray
    reached: bool
    goal_reached: bool
    held: np.ndarray
    reason: str
    names: tuple[str, ...] = ()

    @property
    def limited(self) -> tuple[str, ...]:
        """The names of the coordinates :attr:`held` marks."""
        return tuple(self.names[i] for i in np.flatnonzero(self.held))


class Servo:
    """A robot's state and one IK solve per control tick within its velocity and acceleration limits.

    Args:
        robot: the robot.
        objective: the task (terms whose targets the caller moves between ticks).
        q0: ``(n,)`` the starting configuration (default: the middle of the bounds), at rest.
        velocity_scale: factor on the URDF's joint velocity limits (a joint without one there: unlimited).
        acceleration: joint acceleration limits [rad/s², m/s²]: a number, ``(n,)``, or ``None`` (none).
        tolerance: the task's tolerance [m, rad].
        iterations: the engine's iterations per tick for the goal (its bounded time).
    """

    def __init__(self, robot: Robot, objective: Term | Objective, *, q0: np.ndarray | None = None,
                 velocity_scale: float = 1.0, acceleration: float | np.ndarray | None = None,
                 tolerance: float = 1e-6, iterations: int = 20):
        if isinstance(velocity_scale, bool) or not (isinstance(velocity_scale, (int, float))
                                                     and 0 < velocity_scale < np.inf):
            raise TaskError(f"velocity_scale must be a factor > 0; got {velocity_scale!r}")
        self.robot = robot
        self.problem = Problem(robot, objective)
        self.velocity_limits = velocity_limits(robot) * float(velocity_scale)
        self.acceleration_limits = (np.full(robot.n, np.inf) if acceleration is None
                                    else _positive(acceleration, robot.n, "acceleration"))
        self.q = robot.middle.copy() if q0 is None else robot.check_population(q0, "q0")[0].copy()
        self.velocity = np.zeros(robot.n)
        self.goal = self.q.copy()  # (the state's arrays are replaced each tick, never written)
        self.settings = LocalSettings(tolerance=tolerance, max_iterations=iterations, restarts=False, polish=1,
                                      regularize=False)
        self._draws = stream(0)  # (no restarts: never drawn from)
        self._term: Term | None = None

    @classmethod
    def pose(cls, robot: Robot, frame: str, target=None, **options) -> Servo:
        """A servo of one frame's pose (``target``: the first one; default: where the frame is at ``q0``)."""
        q0 = options.get("q0")
        start = robot.frame_placement(robot.middle if q0 is None else q0, frame) if target is None else target
        servo = cls(robot, Pose(frame, start), **options)
        servo._term = servo.problem.objective.terms[0][1]
        return servo

    def step(self, dt: float, target=None) -> ServoStep:
        """One tick of ``dt`` seconds towards the task's targets (``target``: a pose servo's new target first)."""
        if isinstance(dt, bool) or not (isinstance(dt, (int, float)) and 0 < dt < np.inf):
            raise TaskError(f"dt must be a positive number of seconds; got {dt!r}")
        if target is not None:
            if self._term is None:
                raise TaskError("step(target=...) is for a servo made by Servo.pose; move your terms' targets instead")
            self._term.set_target(target)
        found = solve_local(self.problem.program, self.goal, self._draws, self.settings)
        goal = found.x
        q, velocity = np.empty_like(self.q), np.empty_like(self.q)
        held = command(self.q, self.velocity, goal, self.goal, self.velocity_limits, self.acceleration_limits,
                       self.robot.lower, self.robot.upper, float(dt), q, velocity)
        for a in (q, velocity, goal):  # shared with the step's answer: nobody writes into them
            a.flags.writeable = False
        self.q, self.velocity, self.goal = q, velocity, goal
        reached = bool(found.reached) and not held.any()
        reason = "" if reached else self._why(found.reached, held)
        return ServoStep(q, velocity, goal, reached, bool(found.reached), held, reason, self.robot.coordinate_names)

    def _why(self, goal_reached: bool, held: np.ndarray) -> str:
        if not goal_reached:
            return "the goal misses the task (beyond reach, or a singularity): moving as near as the limits allow"
        names = ", ".join(self.robot.coordinate_names[i] for i in np.flatnonzero(held))
        return f"held back by the limits ({names}): the target moves faster than the robot may"


@compiled
def command(q, velocity, goal, last_goal, v_max, a_max, lower, upper, dt, q_next, v_next):
    """The next configuration ``q_next`` and velocity ``v_next`` ``(n,)`` towards ``goal`` (moving from
    ``last_goal`` in ``dt``) from ``q`` moving at ``velocity``: the step scaled by one factor so that no joint exceeds
    ``v_max`` nor the speed from which it still meets the goal without overshooting (the goal's own speed plus
    ``√(2 a_max d)``), then each joint's change of velocity clamped to ``± a_max dt``, the result kept in
    ``[lower, upper]``. Returns which joints a limit held short of the goal ``bool (n,)``."""
    n = q.shape[0]
    scale = 1.0
    for i in range(n):
        wanted = abs(goal[i] - q[i]) / dt
        if wanted > 0.0:
            cap = min(v_max[i], abs(goal[i] - last_goal[i]) / dt + np.sqrt(2.0 * a_max[i] * abs(goal[i] - q[i])))
            scale = min(scale, cap / wanted)
    held = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        v = scale * (goal[i] - q[i]) / dt
        change = a_max[i] * dt
        v = min(velocity[i] + change, max(velocity[i] - change, v))
        v = min(v_max[i], max(-v_max[i], v))
        x = min(upper[i], max(lower[i], q[i] + v * dt))
        v_next[i] = (x - q[i]) / dt
        q_next[i] = x
        held[i] = abs(x - goal[i]) > 1e-12
    return held


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


def _positive(value, n: int, what: str) -> np.ndarray:
    """``(n,)`` limits from a number or ``n`` numbers, each > 0."""
    try:
        limits = np.broadcast_to(np.asarray(value, dtype=float), (n,)).copy()
    except (TypeError, ValueError):
        limits = None
    if limits is None or not np.all(limits > 0):
        raise TaskError(f"{what} limits must be numbers > 0 (one, or one per coordinate: {n}); got {value!r}")
    return limits
