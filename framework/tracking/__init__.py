"""Trajectory tracking: one IK solve per waypoint, each seeded by the previous solution (paper 000 Fig. 5,
paper 002 Algorithm 1).

For waypoint ``k`` the task is built from the waypoint (position ``t_k``, optional rotation ``R_k``) and the
previous configuration ``q_{k-1}`` (``q_0 = initial``): position of the tracking frame, its orientation, the motion
of each joint group to ``q_{k-1}`` and, for two coordinated arms, the second frame at ``t_k + t_r`` (paper 000
eq. 8) or held at ``t_r`` from the first (paper 001). Describe it declaratively with :class:`TrackingTask` or
pass any callable ``builder(k, position, rotation, previous) -> Objective``::

    task = TrackingTask(frame="arm1_ee", follower="arm2_ee", offset=(0.2, -0.3, -0.2), position_weight=1.2,
                        motion={"base": 0.1, "arm1": 0.4, "arm2": 0.4})          # paper 000 eq. 11
    result = track(robot, paper000("circular"), task, solver="cmaes_fast", max_iterations=300, initial=q0)
    result.position_error.mean(), result.smoothness(robot).max_step["arm1"]

Warm start: the previous solution seeds each solve (the local engine's start, CMA-ES mean, first population
members). With ``predict`` the tracker adds a first-order *predictor*: the previous solution moved onto the new
waypoint by a few Levenberg-Marquardt steps of the local engine; on by default for solvers that carry their
search distribution along the path (CMA-ES), which then start from the task.

A :class:`TrackingTask` builds its problem once and moves its targets in place at every waypoint
(``set_target``); a custom builder's objective is rebuilt per waypoint. A task that gives its parameters along the
path (``path_parameters(problem, trajectory)``: :class:`TrackingTask`, a task file's terms) tracked by a solver
that starts from the previous solution (``hybrid``, ``multistart_lm``) runs the waypoints its local engine answers
in compiled stretches (:mod:`~framework.tracking.chain`), with the answers one solve per waypoint gives.

Paths as data: :mod:`~framework.tracking.trajectory`. The papers' Jacobian baselines along a path:
:func:`jacobian_track`, :func:`relative_jacobian_track` (:mod:`~framework.tracking.jacobian_paths`). One control
tick at a time, within joint velocity and acceleration limits: :class:`Servo` (:mod:`~framework.tracking.servo`).
"""

from .jacobian_paths import jacobian_track, relative_jacobian_track
from .loop import continued, track
from .metrics import Smoothness, TrackingResult, joint_steps, waypoint_errors
from .progress import Progress
from .servo import Servo, ServoStep
from .timing import JointLimits, joint_limits, retimed, velocity_limits
from .task import (CONTINUED_SIGMA0, COORDINATIONS, FIRST_GLOBAL_ITERATIONS, FIRST_SIGMA0, TASK_SPACE_RATIO,
                   TaskBuilder, TrackingCallback, TrackingTask)
from .warm import PREDICTOR, predictor, task_covariance

__all__ = ["CONTINUED_SIGMA0", "COORDINATIONS", "FIRST_GLOBAL_ITERATIONS", "FIRST_SIGMA0", "JointLimits", "PREDICTOR", "Progress",
           "Servo", "ServoStep", "Smoothness", "TASK_SPACE_RATIO", "TaskBuilder", "TrackingCallback", "TrackingResult", "TrackingTask",
           "continued", "jacobian_track", "joint_limits", "joint_steps", "predictor", "relative_jacobian_track", "retimed", "task_covariance", "track",
           "velocity_limits", "waypoint_errors"]
