"""Trajectory tracking: one IK solve per waypoint, each seeded by the previous solution (paper 000 Fig. 5,
paper 002 Algorithm 1).

For waypoint ``k`` the task is built from the waypoint (position ``t_k``, optional rotation ``R_k``) and the
previous configuration ``q_{k-1}`` (``q_0 = initial``): position of the tracking frame, its orientation, the motion
of each joint group to ``q_{k-1}`` and, for two coordinated arms, the second frame at ``t_k + t_r`` (paper 000
eq. 8) or held at ``t_r`` from the first (paper 001). Describe it declaratively with :class:`TrackingTask` or
pass any callable ``builder(k, position, rotation, previous) -> Objective``::

    task = TrackingTask(frame="arm1_ee", follower="arm2_ee", offset=(0.2, -0.3, -0.2), position_weight=1.2,
                        motion={"base": 0.1, "arm1": 0.4, "arm2": 0.4})          # paper 000 eq. 11
    result = track(robot, paper000("circular"), task, solver="cmaes_fast", iterations_per_point=300, initial=q0)
    result.position_error.mean(), result.smoothness(robot).max_step["arm1"]

Warm start: the previous solution seeds each solve (the local engine's start, CMA-ES mean, first population
members). With ``predict`` the tracker adds a first-order *predictor*: the previous solution moved onto the new
waypoint by a few Levenberg-Marquardt steps of the local engine; on by default for solvers that carry their
search distribution along the path (CMA-ES), which then start from the task.

A :class:`TrackingTask` builds its problem once and moves its targets in place at every waypoint
(``set_target``); a custom builder's objective is rebuilt per waypoint.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .costs import JointLimitPenalty, Motion, Objective, Orientation, Position, RelativePosition
from .costs.base import check_weight
from .costs.program import wrapping_coordinates
from .engine import LocalSettings, residuals, solve_local
from .errors import TaskError
from .problem import Problem
from .robot import Robot
from .solve import IKResult, solve
from .solvers import IKSolver, ik_solver
from .trajectory import Trajectory

#: ``builder(k, position (3,), rotation (3, 3) or None, previous (n,)) -> Objective`` for waypoint ``k``.
TaskBuilder = Callable[[int, np.ndarray, "np.ndarray | None", np.ndarray], Objective]
#: ``callback(k, result)`` after each waypoint; returning True stops the tracking (points done are kept).
TrackingCallback = Callable[[int, IKResult], "bool | None"]

#: Generations of the global phase of a solver that has one (the hybrid) at the first waypoint, whose start may
#: be far from the path: the branch it settles on is kept along the whole path (with none, the Puma circle
#: under paper 002's weights settles on a branch from which point 2's optimum does not reach).
FIRST_GLOBAL_ITERATIONS = 30
COORDINATIONS = ("target", "relative")

#: Step size [rad / m] of a CMA-ES that continues from the previous waypoint's search distribution (solvers with
#: a ``covariance`` option; the shape: :func:`continued`): its mean starts at the Jacobian prediction, already on
#: the task, and the optimum is about this far from it. Paper 000's paths, 40 points: mean error 1e-12 to 2e-11 m
#: at 1e-4 (1e-3: 2e-10, 0.02: 4e-7); a fresh identity covariance gives 1e-8 to 4e-8 m whatever the step.
CONTINUED_SIGMA0 = 1e-4

#: The first waypoint of such a solver has no previous distribution: its mean starts at the Jacobian prediction,
#: its covariance is :func:`task_covariance` (the task's null space wide, its row space narrowed by
#: ``TASK_SPACE_RATIO``) and its step ``FIRST_SIGMA0`` [rad / m]. Paper 000's four paths from the paper's q_prev,
#: 4 seeds: first-point error 1e-9 to 3e-9 m (identity covariance: 1e-6 to 4e-6 m whatever the step).
FIRST_SIGMA0, TASK_SPACE_RATIO = 0.1, 1e-4


@dataclass(frozen=True)
class TrackingTask:
    """The per-waypoint task, declaratively: which frames follow the path and how terms are weighted.

    Attributes:
        frame: frame that follows the trajectory (default: the robot's first end-effector).
        position_weight: weight of ``‖p_frame − t_k‖`` [m] (α of paper 000, κ of paper 002).
        orientation_weight: weight of the orientation error ``|sin(φ/2)|`` (λ of paper 002); used only when
            the trajectory has orientations.
        motion: joint group -> weight of its motion ``‖q_g − q_g^prev‖`` (β, γ of paper 000, μ of paper 002);
            a single number weights the group ``"all"``; an empty mapping turns motion off.
        motion_norm: ``"l2"`` (paper 000 eq. 10) or ``"l1"`` (paper 002 eq. 16, ``‖·‖₁ / (n π)``).
        follower: second frame of a coordinated dual-arm task, or ``None``.
        offset: ``t_r`` ``(3,)`` [m], world axes: the follower's target is ``t_k + t_r``.
        follower_weight: weight of the follower's term (default: ``position_weight``).
        coordination: ``"target"``: ``‖p_follower − (t_k + t_r)‖`` (paper 000 eq. 8); ``"relative"``:
            ``‖p_follower − (p_frame + t_r)‖`` (paper 001's relative-position error).
        joint_limits: weight δ of a joint-limit penalty (paper 001), or ``None`` for none.
    """

    frame: str | None = None
    position_weight: float = 1.0
    orientation_weight: float = 1.0
    motion: Mapping[str, float] | float = field(default_factory=lambda: {"all": 0.1})
    motion_norm: str = "l2"
    follower: str | None = None
    offset: Sequence[float] | None = None
    follower_weight: float | None = None
    coordination: str = "target"
    joint_limits: float | None = None

    def __post_init__(self) -> None:
        check_weight(self.position_weight)
        check_weight(self.orientation_weight)
        motion = {"all": self.motion} if isinstance(self.motion, (int, float)) else dict(self.motion)
        for weight in motion.values():
            check_weight(weight)
        object.__setattr__(self, "motion", motion)
        if self.coordination not in COORDINATIONS:
            raise TaskError(f"coordination must be one of {COORDINATIONS}; got {self.coordination!r}")
        if (self.follower is None) != (self.offset is None):
            raise TaskError("a coordinated task needs both a follower frame and an offset t_r (or neither)")
        if self.offset is not None:
            offset = np.asarray(self.offset, dtype=float)
            if offset.shape != (3,) or not np.all(np.isfinite(offset)):
                raise TaskError(f"the relative offset t_r must be 3 finite numbers [m]; got {self.offset!r}")
            object.__setattr__(self, "offset", offset)

    def frame_of(self, robot: Robot) -> str:
        return self.frame or robot.end_effectors[0]

    def objective(
        self, robot: Robot, k: int, position: np.ndarray, rotation: np.ndarray | None, previous: np.ndarray
    ) -> Objective:
        """The weighted terms of waypoint ``k``: position, [orientation], [follower], motion, [limits]."""
        frame = self.frame_of(robot)
        objective = self.position_weight * Position(frame, position, name="position")
        if rotation is not None and self.orientation_weight > 0:
            objective = objective + self.orientation_weight * Orientation(frame, rotation, name="orientation")
        if self.follower is not None:
            weight = self.position_weight if self.follower_weight is None else self.follower_weight
            if self.coordination == "target":
                term = Position(self.follower, position + self.offset, name="follower")
            else:
                term = RelativePosition(frame, self.follower, self.offset, name="follower")
            objective = objective + weight * term
        for group, weight in self.motion.items():
            objective = objective + weight * Motion(
                group, previous, norm=self.motion_norm, name=f"motion[{group}]"
            )
        if self.joint_limits is not None:
            objective = objective + JointLimitPenalty(self.joint_limits)
        return objective

    def update(self, objective: Objective, position: np.ndarray, rotation: np.ndarray | None,
               previous: np.ndarray) -> bool:
        """Move the targets of an objective built by :meth:`objective` to the next waypoint, in place.

        Returns False when the objective does not have the shape this waypoint needs (it must be rebuilt).
        """
        terms = {t.name: t for _, t in objective}
        if ("orientation" in terms) != (rotation is not None and self.orientation_weight > 0):
            return False
        terms["position"].set_target(position)
        if "orientation" in terms:
            terms["orientation"].set_target(rotation)
        if self.follower is not None and self.coordination == "target":
            terms["follower"].set_target(position + self.offset)
        for group in self.motion:
            terms[f"motion[{group}]"].set_target(previous)
        return True

    def frames(self, robot: Robot) -> tuple[str, ...]:
        """The frames that track: the main frame and, if any, the follower."""
        return (self.frame_of(robot),) + ((self.follower,) if self.follower else ())


# ---------------------------------------------------------------------------------------------- smoothness
@dataclass(frozen=True)
class Smoothness:
    """Joint steps between consecutive waypoints, per joint group, as numbers.

    The step of group ``g`` at waypoint ``k >= 1`` is ``‖q_g,k − q_g,k−1‖∞`` (the largest single joint move)
    [rad, or m for prismatic/planar translations]; angles of continuous joints and planar headings are wrapped.

    Attributes:
        max_step, mean_step: group -> largest / mean step along the path (``k = 1 .. K−1``).
        worst_point: group -> waypoint ``k`` of the largest step (where the motion jumps).
        approach: group -> step from the initial configuration to the first waypoint (not part of the path).
        steps: group -> ``(K − 1,)`` the steps themselves.
    """

    max_step: dict[str, float]
    mean_step: dict[str, float]
    worst_point: dict[str, int]
    approach: dict[str, float]
    steps: dict[str, np.ndarray] = field(repr=False)


def joint_steps(robot: Robot, Q: np.ndarray, initial: np.ndarray | None = None) -> Smoothness:
    """Smoothness of a joint path ``Q`` ``(K, n)`` per group of ``robot`` (and ``"all"``)."""
    Q = robot.check_population(Q, "joint path")
    start = Q[0] if initial is None else robot.check_population(initial, "initial configuration")[0]
    D = np.diff(np.vstack([start, Q]), axis=0)
    wrap = wrapping_coordinates(robot)
    D[:, wrap] = (D[:, wrap] + np.pi) % (2 * np.pi) - np.pi
    groups = {"all": np.arange(robot.n), **{g: np.asarray(i) for g, i in robot.groups.items()}}
    max_step, mean_step, worst, approach, steps = {}, {}, {}, {}, {}
    for name, idx in groups.items():
        s = np.abs(D[:, idx]).max(axis=1)
        approach[name] = float(s[0])
        path = s[1:]
        steps[name] = path
        max_step[name] = float(path.max()) if path.size else 0.0
        mean_step[name] = float(path.mean()) if path.size else 0.0
        worst[name] = int(np.argmax(path)) + 1 if path.size else 0
    return Smoothness(max_step, mean_step, worst, approach, steps)


# ---------------------------------------------------------------------------------------------- result
@dataclass(frozen=True)
class TrackingResult:
    """What tracking a trajectory produced, one entry per waypoint done (``len(result)`` of them).

    Attributes:
        trajectory: the desired path (all ``K`` waypoints, even if stopped early).
        configurations: ``Q`` ``(k, n)`` joint coordinates per waypoint [rad / m].
        initial: ``(n,)`` the configuration before the first waypoint (``q_prev`` of the first solve).
        position_error: ``(k,)`` sum of the unweighted position terms [m] (with a follower: ``e_t1 + e_t2``).
        orientation_error: ``(k,)`` sum of the orientation terms (``|sin(φ/2)|``; zeros without orientation).
        motion_error: ``(k,)`` sum of the unweighted motion terms (each in its own norm).
        task_error, cost: ``(k,)`` task error (decides success) and objective value per waypoint.
        terms: term name -> ``(k,)`` unweighted values.
        iterations, evaluations: ``(k,)`` per waypoint; times: ``(k,)`` seconds per waypoint.
        success: ``(k,)`` ``task_error <= tolerance``.
        stop_reason: ``"completed"``, ``"interrupted"`` (Ctrl-C) or ``"callback"``.
        solver, settings: what ran, with every setting.
        wall_time, cpu_time: seconds for the whole run (wall clock, and CPU time of this process).
    """

    trajectory: Trajectory
    configurations: np.ndarray
    initial: np.ndarray
    position_error: np.ndarray
    orientation_error: np.ndarray
    motion_error: np.ndarray
    task_error: np.ndarray
    cost: np.ndarray
    terms: dict[str, np.ndarray] = field(repr=False)
    iterations: np.ndarray = field(repr=False)
    evaluations: np.ndarray = field(repr=False)
    times: np.ndarray = field(repr=False)
    success: np.ndarray = field(repr=False)
    stop_reason: str = "completed"
    solver: str = ""
    settings: dict[str, Any] = field(default_factory=dict, repr=False)
    wall_time: float = 0.0
    cpu_time: float = 0.0

    def __len__(self) -> int:
        return self.configurations.shape[0]

    @property
    def completed(self) -> bool:
        """True when every waypoint of the trajectory was solved."""
        return len(self) == self.trajectory.K

    @property
    def all_success(self) -> bool:
        return self.completed and bool(self.success.all())

    def frame_positions(self, robot: Robot, frames: Sequence[str] | str | None = None) -> np.ndarray:
        """World positions of ``frames`` along the joint path: ``(k, len(frames), 3)`` [m]."""
        return robot.frame_poses(self.configurations, frames).positions

    def smoothness(self, robot: Robot) -> Smoothness:
        """Joint steps per group (see :func:`joint_steps`)."""
        return joint_steps(robot, self.configurations, self.initial)

    def summary(self, robot: Robot | None = None) -> dict[str, float]:
        """Mean / max errors, totals and (with ``robot``) the largest joint step along the path."""
        out = {
            "points": float(len(self)),
            "position_mean": _mean(self.position_error),
            "position_max": _max(self.position_error),
            "orientation_mean": _mean(self.orientation_error),
            "orientation_max": _max(self.orientation_error),
            "motion_mean": _mean(self.motion_error),
            "motion_max": _max(self.motion_error),
            "success_rate": _mean(self.success.astype(float)),
            "evaluations": float(self.evaluations.sum()),
            "time": self.wall_time,
            "cpu_time": self.cpu_time,
        }
        if robot is not None and len(self):
            smooth = self.smoothness(robot)
            out["max_step"] = smooth.max_step["all"]
            out["mean_step"] = smooth.mean_step["all"]
        return out


def _mean(a: np.ndarray) -> float:
    return float(a.mean()) if a.size else float("nan")


def _max(a: np.ndarray) -> float:
    return float(a.max()) if a.size else float("nan")


# ---------------------------------------------------------------------------------------------- the loop
def track(
    robot: Robot,
    trajectory: Trajectory,
    task: TrackingTask | TaskBuilder | None = None,
    *,
    solver: str = "hybrid",
    seed: int | np.random.Generator = 0,
    iterations_per_point: int = 300,
    population: int = 30,
    initial: np.ndarray | None = None,
    warm_start: bool = True,
    warm_spread: float = 0.02,
    predict: bool | None = None,
    tolerance: float = 1e-4,
    stop_at_tolerance: bool = False,
    bounds: str = "resample",
    priorities: bool = True,
    options: Mapping[str, Any] | None = None,
    progress: bool | None = None,
    callback: TrackingCallback | None = None,
) -> TrackingResult:
    """Track ``trajectory`` with ``robot``: one :func:`~framework.solve.solve` per waypoint.

    Args:
        robot: any robot.
        trajectory: the waypoints (positions, optional orientations) for the tracking frame.
        task: a :class:`TrackingTask`, a builder ``(k, position, rotation, previous) -> Objective``, or ``None``
            (the first end-effector follows the path, motion weight 0.1 on all joints).
        solver: ``"hybrid"``, ``"multistart_lm"`` or a registered metaheuristic.
        seed: seed or generator; one generator runs through all waypoints, so runs are reproducible.
        iterations_per_point: iteration budget of each solve (300 in paper 000; 500 in paper 002).
        population: population size of each solve.
        initial: ``(n,)`` configuration before the first waypoint (paper 000's ``q_prev``): the first motion
            reference and warm start. Default: the centre of the search box.
        warm_start: seed each solve with the previous solution (``False``: cold starts, as in the papers).
        warm_spread: for warm-started waypoints after the first, the search starts local: CMA-ES-type solvers
            (those with a ``sigma0`` option) get ``sigma0 = warm_spread``, population solvers get half their
            first population drawn from ``N(previous, warm_spread²)`` [rad / m]; ``0`` seeds only the previous
            solution (CMA-ES mean / one member) with the solver's default spread.
        predict: add the engine's predictor to the warm start (default: for solvers that continue their search
            distribution; local solvers start from the previous solution). ``cmaes_fast`` warm-started with the
            predictor continues from
            the previous waypoint's distribution: mean at the prediction, its adapted covariance
            (:attr:`~framework.solve.IKResult.state`, see :func:`continued`) and ``sigma0 =``
            :data:`CONTINUED_SIGMA0`; at the first waypoint, :func:`task_covariance` and :data:`FIRST_SIGMA0`
            (``options`` override both; ``predict=False`` falls back to ``warm_spread``).
        tolerance: a waypoint succeeds if every task term is within this [m, or rad for orientations].
        stop_at_tolerance: stop each solve as soon as the task error is within ``tolerance``.
        bounds: ``"resample"``, ``"clip"`` or ``"penalty"`` (see :class:`~framework.problem.Problem`).
        priorities: task terms first (default) or the weighted sum as it stands (the papers), see
            :class:`~framework.problem.Problem`.
        options: solver options (a solver with a global phase, the hybrid, runs :data:`FIRST_GLOBAL_ITERATIONS`
            generations of it at the first waypoint unless ``options`` set them).
        progress: show a progress bar (``None``: only on a terminal).
        callback: ``callback(k, ik_result)`` after each waypoint; returning True stops early.

    Returns:
        A :class:`TrackingResult`. Ctrl-C stops cleanly: the waypoints done are kept
        (``stop_reason == "interrupted"``).

    Raises:
        TaskError: bad task or weights; ConfigurationError: ``initial`` of the wrong shape or not finite.
    """
    if not isinstance(trajectory, Trajectory):
        raise TaskError(f"track() needs a framework.trajectory.Trajectory; got {type(trajectory).__name__}")
    if int(iterations_per_point) != iterations_per_point or iterations_per_point < 1:
        raise TaskError(f"iterations_per_point must be a positive integer; got {iterations_per_point!r}")
    builder = _builder(robot, task)
    spec = task if isinstance(task, TrackingTask) else (TrackingTask() if task is None else None)
    q0 = (
        robot.middle.copy()
        if initial is None
        else robot.check_population(initial, "initial configuration")[0]
    )
    q0 = q0.copy()
    options = dict(options or {})
    method = ik_solver(solver, options)  # checks the name and the options once
    carry = method.carries_distribution
    predict = carry if predict is None else bool(predict)
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    if not np.isfinite(warm_spread) or warm_spread < 0:
        raise TaskError(f"warm_spread must be a number >= 0 [rad / m]; got {warm_spread!r}")
    state: dict[str, Any] = {}  # the previous solve's search distribution, for solvers that continue it

    rows: list[tuple[IKResult, tuple[str, ...]]] = []
    previous = q0
    stop_reason = "completed"
    problem: Problem | None = None
    start, cpu_start = time.perf_counter(), time.process_time()
    with _Progress(progress, trajectory.K, f"tracking {trajectory.name} ({solver})") as bar:
        try:
            for k in range(trajectory.K):
                rotation = trajectory.rotation(k)
                position = trajectory.positions[k]
                moved = problem is not None and spec is not None and spec.update(
                    problem.objective, position, rotation, previous)
                if not moved:
                    problem = Problem(robot, builder(k, position, rotation, previous), bounds=bounds,
                                      priorities=priorities)
                seeds, solver_options = _warm_start(problem, previous, k, method, options, warm_start, warm_spread,
                                                    predict and warm_start, population, rng, carry, state)
                result = solve(problem, solver, seed=rng, max_iterations=iterations_per_point,
                               population=population, tolerance=tolerance, stop_at_tolerance=stop_at_tolerance,
                               initial=seeds, options=solver_options or None)
                if result.stop_reason == "interrupted":
                    stop_reason = "interrupted"
                    break
                rows.append((result, problem.program.term_kinds))
                previous, state = result.configuration, result.state
                bar.advance(result.task_error)
                if callback is not None and callback(k, result):
                    stop_reason = "callback"
                    break
        except KeyboardInterrupt:
            stop_reason = "interrupted"
    settings = {
        "solver": solver,
        "iterations_per_point": int(iterations_per_point),
        "population": population,
        "warm_start": warm_start,
        "warm_spread": warm_spread,
        "predict": predict,
        "tolerance": tolerance,
        "stop_at_tolerance": stop_at_tolerance,
        "bounds": bounds,
        "priorities": priorities,
        "options": options,
        "task": task if isinstance(task, TrackingTask) else getattr(task, "__name__", repr(task)),
    }
    times = (time.perf_counter() - start, time.process_time() - cpu_start)
    return _result(trajectory, q0, rows, stop_reason, solver, settings, times, tolerance)


def _warm_start(
    problem: Problem,
    previous: np.ndarray,
    k: int,
    method: IKSolver,
    options: dict[str, Any],
    warm_start: bool,
    warm_spread: float,
    predict: bool,
    population: int,
    rng: np.random.Generator,
    carry: bool,
    state: dict[str, Any],
) -> tuple[np.ndarray | None, dict[str, Any]]:
    """Warm-start points ``(k, n)`` (or ``None``: cold) and solver options for waypoint ``k`` (see :func:`track`);
    ``carry``: the solver continues its search distribution, ``state``: the previous solve's
    :attr:`~framework.solve.IKResult.state` (empty at the first waypoint)."""
    defaults = method.option_names
    if not warm_start:  # a local solver would otherwise start from the motion terms' previous configuration
        return None, ({"warm_start": False, **options} if "warm_start" in defaults else options)
    seeds = [predictor(problem, previous), previous] if predict else [previous]
    if k == 0:  # the first waypoint may be far from the initial configuration: the solver's own spread
        if "global_iterations" in defaults:  # and a global phase where the solver has one
            return np.array(seeds), {"global_iterations": FIRST_GLOBAL_ITERATIONS, **options}
        covariance = task_covariance(problem, seeds[0]) if carry else None
        if covariance is not None:  # CMA-ES from the prediction, along the task's null space first
            return np.array(seeds), {"sigma0": FIRST_SIGMA0, "covariance": covariance, **options}
        return np.array(seeds), options
    if method.uses_jacobians:
        return np.array(seeds), options
    if carry and state:  # CMA-ES: mean at the prediction, the previous waypoint's adapted covariance, a small step
        return np.array(seeds), {"sigma0": CONTINUED_SIGMA0, **continued(state, task_covariance(problem, seeds[0])),
                                 **options}
    if warm_spread > 0 and method.step_option:
        return np.array(seeds), {method.step_option: warm_spread, **options}
    if warm_spread > 0:
        robot = problem.robot
        cloud = previous + warm_spread * rng.standard_normal((population // 2, robot.n))
        seeds += list(np.clip(cloud, robot.lower, robot.upper))
    return np.array(seeds), options


def _builder(robot: Robot, task: TrackingTask | TaskBuilder | None) -> TaskBuilder:
    if task is None:
        task = TrackingTask()
    if isinstance(task, TrackingTask):
        for frame in task.frames(robot):
            robot.frame_id(frame)
        for group in task.motion:
            robot.group(group)

        def build(
            k: int, position: np.ndarray, rotation: np.ndarray | None, previous: np.ndarray
        ) -> Objective:
            return task.objective(robot, k, position, rotation, previous)

        return build
    if not callable(task):
        raise TaskError(f"task must be a TrackingTask or a callable builder; got {type(task).__name__}")
    return task


def waypoint_errors(result: IKResult, kinds: Sequence[str]) -> tuple[float, float, float]:
    """A waypoint's position, orientation and motion errors: the sums of its unweighted terms of each kind
    (``kinds``: :attr:`~framework.costs.program.Program.term_kinds` of its problem)."""
    totals = {"position": 0.0, "orientation": 0.0, "motion": 0.0}
    for value, kind in zip(result.terms.values(), kinds):
        if kind in totals:
            totals[kind] += value
    return totals["position"], totals["orientation"], totals["motion"]


def _result(trajectory, q0, rows, stop_reason, solver, settings, times, tolerance) -> TrackingResult:
    results = [r for r, _ in rows]
    names = list(results[0].terms) if results else []
    terms = {name: np.array([r.terms.get(name, np.nan) for r in results]) for name in names}

    sums = np.array([waypoint_errors(r, kinds) for r, kinds in rows]).reshape(len(rows), 3)

    return TrackingResult(
        trajectory=trajectory,
        configurations=np.array([r.configuration for r in results]).reshape(len(results), q0.shape[0]),
        initial=q0,
        position_error=sums[:, 0],
        orientation_error=sums[:, 1],
        motion_error=sums[:, 2],
        task_error=np.array([r.task_error for r in results]),
        cost=np.array([r.cost for r in results]),
        terms=terms,
        iterations=np.array([r.iterations for r in results], dtype=int),
        evaluations=np.array([r.evaluations for r in results], dtype=int),
        times=np.array([r.wall_time for r in results]),
        success=np.array([r.success for r in results], dtype=bool),
        stop_reason=stop_reason,
        solver=solver,
        settings=settings,
        wall_time=times[0],
        cpu_time=times[1],
    )


def continued(state: dict[str, Any], task: np.ndarray | None) -> dict[str, Any]:
    """The previous waypoint's solver state with its covariance mixed half and half with ``task`` (the
    :func:`task_covariance` at the new prediction; the task's directions turn along a path) and rescaled to a
    largest eigenvalue of 1. Paper 000's paths, first 120 points: mean error 2e-12 to 6e-10 m, against 5e-10 to
    9e-9 m with the previous shape alone (the trapezoid's corners)."""
    if task is None or "covariance" not in state:
        return dict(state)
    C = 0.5 * (np.asarray(state["covariance"]) + task)
    return {**state, "covariance": C / float(np.linalg.eigvalsh(C)[-1])}


# ---------------------------------------------------------------------------------------------- predictor
def task_covariance(problem: Problem, x: np.ndarray, *, ratio: float = TASK_SPACE_RATIO) -> np.ndarray | None:
    """``(n, n)`` covariance for a search from ``x`` on the task: identity on the null space of the stacked task
    Jacobian, ``ratio`` on its row space (moves that leave the task are ``1/√ratio`` times narrower).

    ``None`` when ``x`` is not on the task (task error above 1e-9) or there is no task term.
    """
    if not problem.program.task_rows or problem.evaluate(x).task_error[0] > 1e-9:
        return None
    _, J = residuals(problem.program, x)
    row = np.linalg.pinv(J, rcond=1e-10) @ J  # projector onto the row space
    row = 0.5 * (row + row.T)
    return np.eye(problem.robot.n) - (1.0 - ratio) * row


#: The predictor: a few Levenberg-Marquardt steps of the local engine, no restart, no regularization.
PREDICTOR = LocalSettings(tolerance=1e-12, max_iterations=5, restarts=False, regularize=False, polish=0)


def predictor(problem: Problem, x: np.ndarray) -> np.ndarray:
    """``x`` moved onto the task by a few Levenberg-Marquardt steps of the local engine (the tracking predictor);
    ``x`` itself when the problem has no task term."""
    if not problem.program.task_rows:
        return np.array(x, dtype=float)
    return solve_local(problem.program, x, np.random.default_rng(0), PREDICTOR).x.copy()


# ---------------------------------------------------------------------------------------------- progress
class _Progress:
    """A rich progress bar over waypoints, or nothing (not a terminal, or ``enabled=False``)."""

    def __init__(self, enabled: bool | None, total: int, description: str):
        self.total, self.description = total, description
        self.enabled = enabled
        self._bar = None

    def __enter__(self) -> _Progress:  # noqa: PYI034
        from rich.console import Console

        console = Console(stderr=True)
        enabled = console.is_terminal if self.enabled is None else self.enabled
        if enabled:
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

            self._bar = Progress(
                TextColumn("{task.description}"),
                BarColumn(),
                MofNCompleteColumn(),
                TimeRemainingColumn(),
                TextColumn("error {task.fields[error]}"),
                console=console,
                transient=True,
            )
            self._bar.__enter__()
            self._task = self._bar.add_task(self.description, total=self.total, error="-")
        return self

    def advance(self, error: float) -> None:
        if self._bar is not None:
            self._bar.update(self._task, advance=1, error=f"{error:.1e}")

    def __exit__(self, *exc) -> None:
        if self._bar is not None:
            self._bar.__exit__(*exc)
