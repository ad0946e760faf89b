"""The Jacobian baselines stepped along a trajectory, with the same result record as the optimizer's tracker.

Each waypoint starts from the previous waypoint's configuration (the first from ``initial``) and applies up to
``iterations_per_point`` closed-loop Jacobian steps, stopping early below ``tolerance``. The default, one step
per waypoint, is resolved-rate control as a controller runs it (one step per control cycle); more steps
converge at every waypoint (Newton-like, which hides the jumps inside a waypoint's iterations). The result is a
:class:`~framework.tracking.TrackingResult`, so errors and smoothness (:func:`~framework.tracking.joint_steps`:
where the baseline jumps) compare one to one with :func:`~framework.tracking.track`.
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from ..costs import Position, Program
from ..costs.motion import motion_name
from ..errors import TaskError
from ..model.robot import Robot
from .metrics import TrackingResult, spans
from .task import FOLLOWER, POSITION
from .trajectory import Trajectory
from ..solvers.baselines.jacobian import jacobian_ik
from ..solvers.baselines.relative import RELATIVE_GAIN, SECONDARY_GAIN, relative_jacobian_ik
from ..solvers.baselines.solver import JACOBIAN_BASELINES

#: A waypoint counts as reached when its position error is at most this [m] (the papers' tolerance).
SUCCESS_TOLERANCE = 1e-4


def jacobian_track(
    robot: Robot,
    trajectory: Trajectory,
    frame: str | None = None,
    *,
    method: str = "pinv",
    initial: np.ndarray | None = None,
    gain: float = 1.0,
    iterations_per_point: int = 1,
    tolerance: float = 1e-6,
    rcond: float = 1e-6,
    damping: float = 0.05,
) -> TrackingResult:
    """Track the positions of ``trajectory`` with ``frame`` (default: first end-effector) by ``"pinv"`` or
    ``"dls"`` closed-loop IK (one arm, or a mobile arm: the base is just more joints).

    Args:
        gain: fraction of the error corrected per step (1 = Gauss-Newton).
        iterations_per_point: Jacobian steps per waypoint (1: resolved rate); tolerance: error [m] that ends a
            waypoint early.
        rcond: SVD cut-off of ``"pinv"``; damping: ``λ`` [m/rad] of ``"dls"``.
    """
    if method not in JACOBIAN_BASELINES:
        raise TaskError(f"unknown Jacobian method {method!r}; use one of {sorted(JACOBIAN_BASELINES)}")
    baseline = JACOBIAN_BASELINES[method]({"gain": gain, "rcond": rcond, "damping": damping})
    frame = frame or robot.end_effectors[0]
    robot.frame_id(frame)
    x = _initial(robot, initial)
    q0, rows = x.copy(), []
    term = Position(frame, trajectory.positions[0])
    program = Program(robot, 1.0 * term)  # one program, its target moved to each waypoint
    for k in range(trajectory.K):
        start = time.perf_counter()
        term.set_target(trajectory.positions[k])
        run = jacobian_ik(program, x, baseline.inverse_of, gain=gain, max_iterations=iterations_per_point,
                          tolerance=tolerance)
        x = run.x
        rows.append((x.copy(), run.evaluations, time.perf_counter() - start))
    settings = {
        "method": method,
        "frame": frame,
        "gain": gain,
        "iterations_per_point": iterations_per_point,
        "tolerance": tolerance,
        "rcond": rcond,
        "damping": damping,
    }
    return _result(robot, trajectory, q0, rows, [frame], None, method, settings, tolerance)


def relative_jacobian_track(
    robot: Robot,
    trajectory: Trajectory,
    frame_a: str,
    frame_b: str,
    offset: Sequence[float],
    *,
    initial: np.ndarray | None = None,
    iterations_per_point: int = 1,
    tolerance: float = 1e-6,
    relative_gain: float = RELATIVE_GAIN,
    secondary_gain: float = SECONDARY_GAIN,
    rcond: float = 1e-6,
) -> TrackingResult:
    """Paper 001's conventional method along a path: arm A (``frame_a``) on the waypoints, arm B
    (``frame_b``) held at ``offset`` ``t_r`` [m] from A, by the relative Jacobian with task priority.

    The position error per waypoint is ``‖t − p_A‖ + ‖p_B − p_A − t_r‖`` [m] (as the optimizer's
    ``TrackingTask(coordination="relative")``); the motion error ``‖q_k − q_{k−1}‖₂``.
    """
    offset = np.asarray(offset, dtype=float)
    if offset.shape != (3,) or not np.all(np.isfinite(offset)):
        raise TaskError(f"the relative offset t_r must be 3 finite numbers [m]; got {offset!r}")
    robot.frame_id(frame_a)
    robot.frame_id(frame_b)
    x = _initial(robot, initial)
    q0, rows = x.copy(), []
    for k in range(trajectory.K):
        start = time.perf_counter()
        x, evaluations = relative_jacobian_ik(
            robot,
            x,
            frame_a,
            frame_b,
            trajectory.positions[k],
            offset,
            max_iterations=iterations_per_point,
            tolerance=tolerance,
            relative_gain=relative_gain,
            secondary_gain=secondary_gain,
            rcond=rcond,
        )
        rows.append((x.copy(), 2 * evaluations, time.perf_counter() - start))
    settings = {
        "method": "relative_jacobian",
        "frames": (frame_a, frame_b),
        "offset": offset.tolist(),
        "relative_gain": relative_gain,
        "secondary_gain": secondary_gain,
        "iterations_per_point": iterations_per_point,
        "tolerance": tolerance,
        "rcond": rcond,
    }
    return _result(
        robot, trajectory, q0, rows, [frame_a, frame_b], offset, "relative_jacobian", settings, tolerance
    )


def _initial(robot: Robot, initial: np.ndarray | None) -> np.ndarray:
    if initial is None:
        return robot.middle.copy()
    return np.clip(robot.check_population(initial, "initial configuration")[0], robot.lower, robot.upper)


def _result(robot, trajectory, q0, rows, frames, offset, solver, settings, tolerance) -> TrackingResult:
    Q = np.array([r[0] for r in rows])
    P = robot.frame_poses(Q, frames).positions
    terms = {POSITION: np.linalg.norm(P[:, 0] - trajectory.positions, axis=1)}
    if offset is not None:
        terms[FOLLOWER] = np.linalg.norm(P[:, 1] - P[:, 0] - offset, axis=1)
    position = sum(terms.values())
    orientation = np.zeros(len(Q))
    motion = np.linalg.norm(np.diff(np.vstack([q0, Q]), axis=0), axis=1)
    terms[motion_name("all")] = motion
    evaluations = np.array([r[1] for r in rows], dtype=int)
    times = np.array([r[2] for r in rows])
    return TrackingResult(
        trajectory=trajectory,
        configurations=Q,
        initial=q0,
        position_error=position,
        orientation_error=orientation,
        motion_error=motion,
        task_error=position.copy(),
        cost=np.full(len(Q), np.nan),
        terms=terms,
        iterations=evaluations.copy(),
        evaluations=evaluations,
        times=times,
        success=position <= SUCCESS_TOLERANCE,
        stop_reason="completed",
        solver=solver,
        settings=settings,
        wall_time=float(times.sum()),
        cpu_time=float(times.sum()),
        reason=_missed(position),
    )


def _missed(position: np.ndarray) -> str:
    """The reason line of a Jacobian path: the waypoints whose position error exceeds the tolerance."""
    missed = np.flatnonzero(position > SUCCESS_TOLERANCE).tolist()
    if not missed:
        return ""
    return (f"{len(missed)} of {len(position)} waypoints missed (k = {spans(missed)}); the worst by "
            f"{position.max():.3g} m (tolerance {SUCCESS_TOLERANCE:g} m)")
