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
   speed plus ``√(2 a d)``); then each joint's change of velocity clamped to ``± a dt``. The limits hold by construction
   (:func:`~framework.tracking.timing.command`, compiled).

A step says whether the goal is met, which joints a limit held back, and why the task is missed: held back by the
limits (the target moves faster than the robot may), or the goal itself misses it (beyond reach, a singularity).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..costs import Objective, Pose, Term
from ..costs.problem import Problem
from ..engine import LocalSettings, solve_local
from ..engine.draws import stream
from ..errors import TaskError
from ..model.robot import Robot
from .timing import command, joint_limits


class ServoStep(NamedTuple):
    """One tick's answer (its arrays are the servo's own state: read them, do not write them).

    Attributes:
        q: ``(n,)`` the configuration to command [rad / m].
        velocity: ``(n,)`` ``(q - q_before) / dt`` [rad/s, m/s].
        goal: ``(n,)`` where the task is met (or most nearly, when it cannot be).
        reached: ``q`` is the goal and the goal meets the task (within the tolerance).
        goal_reached: the goal meets the task.
        held: ``bool (n,)`` the coordinates a velocity or acceleration limit held short of the goal.
        reason: ``""`` when reached; else why not.
        names: the robot's coordinate names (for :attr:`limited`).
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
        self.robot = robot
        self.problem = Problem(robot, objective)
        self.velocity_limits, self.acceleration_limits = joint_limits(robot, velocity_scale, acceleration)
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
        goal, n = found.x, self.q.shape[0]
        q, velocity, held = np.empty(n), np.empty(n), np.empty(n, dtype=bool)
        count = command(self.q, self.velocity, goal, self.goal, self.velocity_limits, self.acceleration_limits,
                        self.robot.lower, self.robot.upper, float(dt), q, velocity, held)
        self.q, self.velocity, self.goal = q, velocity, goal  # (replaced each tick, never written: shared)
        reached = found.reached and not count
        reason = "" if reached else self._why(found.reached, held)
        return tuple.__new__(ServoStep, (q, velocity, goal, reached, found.reached, held, reason,
                                         self.robot.coordinate_names))

    def _why(self, goal_reached: bool, held: np.ndarray) -> str:
        if not goal_reached:
            return "the goal misses the task (beyond reach, or a singularity): moving as near as the limits allow"
        names = ", ".join(self.robot.coordinate_names[i] for i in np.flatnonzero(held))
        return f"held back by the limits ({names}): the target moves faster than the robot may"
