"""The tracking loop: one solve per waypoint, each warm-started from the previous solution (:func:`track`)."""


from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..costs import Objective
from ..errors import TaskError
from ..costs.problem import Problem
from ..model.robot import Robot
from ..solvers.settings import DEFAULTS
from ..solvers.solve import IKResult, check_settings, make_request, result_of, solve
from ..solvers import IKSolver, Outcome, ik_solver
from .trajectory import Trajectory
from .chain import Chain
from .metrics import TrackingResult, path_reason, waypoint_errors
from .progress import Progress
from .timing import JointLimits, command, joint_limits, retimed, segment_intervals
from .task import (
    CONTINUED_SIGMA0,
    FIRST_GLOBAL_ITERATIONS,
    FIRST_SIGMA0,
    TaskBuilder,
    TrackingCallback,
    TrackingTask,
)
from .warm import predictor, task_covariance


# ---------------------------------------------------------------------------------------------- the loop
def track(
    robot: Robot,
    trajectory: Trajectory,
    task: TrackingTask | TaskBuilder | None = None,
    *,
    solver: str = DEFAULTS.solver,
    seed: int | np.random.Generator = DEFAULTS.seed,
    tolerance: float = DEFAULTS.tolerance,
    angle_tolerance: float | None = DEFAULTS.angle_tolerance,
    time_budget: float | None = DEFAULTS.time_budget,
    max_iterations: int | None = DEFAULTS.max_iterations,
    population: int = DEFAULTS.population,
    stop_at_tolerance: bool = DEFAULTS.stop_at_tolerance,
    options: Mapping[str, Any] | None = DEFAULTS.options,
    initial: np.ndarray | None = None,
    warm_start: bool = True,
    warm_spread: float = 0.02,
    predict: bool | None = None,
    bounds: str = "resample",
    priorities: bool = True,
    progress: bool | None = None,
    callback: TrackingCallback | None = None,
    velocity_scale: float | None = None,
    acceleration: float | np.ndarray | None = None,
    retime: bool = False,
) -> TrackingResult:
    """Track ``trajectory`` with ``robot``: one :func:`~framework.solve` per waypoint.

    Args:
        robot: any robot.
        trajectory: the waypoints (positions, optional orientations) for the tracking frame.
        task: a :class:`TrackingTask`, a builder ``(k, position, rotation, previous) -> Objective``, or ``None``
            (the first end-effector follows the path, motion weight 0.1 on all joints).
        solver, seed, tolerance, angle_tolerance, stop_at_tolerance, options: as :func:`~framework.solve`, for
            every waypoint (one generator runs through all waypoints, so runs are reproducible).
        time_budget, max_iterations, population: as :func:`~framework.solve`, per waypoint (paper 000 runs 300
            iterations per waypoint, paper 002 500).
        initial: ``(n,)`` configuration before the first waypoint (paper 000's ``q_prev``): the first motion
            reference and warm start. Default: the centre of the search box.
        warm_start: seed each solve with the previous solution (``False``: cold starts, as in the papers).
        warm_spread: for warm-started waypoints after the first, the search starts local: CMA-ES-type solvers
            (those with a ``sigma0`` option) get ``sigma0 = warm_spread``, population solvers get half their
            first population drawn from ``N(previous, warm_spread²)`` [rad / m]; ``0`` seeds only the previous
            solution (CMA-ES mean / one member) with the solver's default spread.
        predict: add the engine's predictor to the warm start (default: for solvers that continue their search
            distribution; local solvers start from the previous solution). ``cmaes_fast`` warm-started with the
            predictor continues from the previous waypoint's distribution: mean at the prediction, its adapted
            covariance (:attr:`~framework.solvers.solve.IKResult.state`, see :func:`continued`) and ``sigma0 =``
            :data:`CONTINUED_SIGMA0`; at the first waypoint, :func:`task_covariance` and :data:`FIRST_SIGMA0`
            (``options`` override both; ``predict=False`` falls back to ``warm_spread``).
        bounds, priorities: as :class:`~framework.costs.problem.Problem`.
        progress: show a progress bar (``None``: only on a terminal).
        callback: ``callback(k, ik_result)`` after each waypoint; returning True stops early.
        velocity_scale, acceleration: joint velocity limits (the robot file's, times ``velocity_scale``) and
            acceleration limits along a timed path (:meth:`Trajectory.timed`): each waypoint at most what they allow
            from the previous one (:func:`~.timing.command`); one held short lags (``result.lagging``, the reason).
        retime: instead, track freely, then give the path the fastest times keeping them (``result.trajectory``).

    A solver with a global phase (the hybrid) runs :data:`FIRST_GLOBAL_ITERATIONS` generations of it at the first
    waypoint unless ``options`` set them.

    Returns:
        A :class:`TrackingResult`. Ctrl-C stops cleanly: the waypoints done are kept
        (``stop_reason == "interrupted"``).

    Raises:
        TaskError: bad task or weights; ConfigurationError: ``initial`` of the wrong shape or not finite;
        SolverError: a bad setting, named.
    """
    if not isinstance(trajectory, Trajectory):
        raise TaskError(f"track() needs a framework.tracking.trajectory.Trajectory; got {type(trajectory).__name__}")
    if not isinstance(warm_spread, (int, float, np.number)) or not np.isfinite(warm_spread) or warm_spread < 0:
        raise TaskError(f"warm_spread must be a number >= 0 [rad / m]; got {warm_spread!r}")
    q0 = robot.middle.copy() if initial is None else robot.check_population(initial, "initial configuration")[0].copy()
    options = dict(options or {})
    if "closed_form" in ik_solver(solver).option_names and "closed_form" not in options:
        # one method along the path: the compiled stretches descend from the previous solution, and so does every
        # waypoint solved alone (solver="closed_form" tracks by the closed form: each waypoint's nearest solution)
        options["closed_form"] = False
    method = ik_solver(solver, options)  # checks the name and the options once
    predict = method.carries_distribution if predict is None else bool(predict)
    limits = _path_limits(robot, trajectory, velocity_scale, acceleration, retime)
    check_settings(seed=seed, tolerance=tolerance, angle_tolerance=angle_tolerance, time_budget=time_budget,
                   max_iterations=max_iterations, population=population)  # every setting checked once, here
    run = _Waypoints(robot, trajectory, task, method, options, bounds, priorities, warm_start, float(warm_spread),
                     predict, dict(seed=seed, tolerance=tolerance, angle_tolerance=angle_tolerance,
                                   time_budget=time_budget, max_iterations=max_iterations, population=population,
                                   stop_at_tolerance=stop_at_tolerance), None if retime else limits)
    start, cpu_start = time.perf_counter(), time.process_time()
    rows, stop_reason = run.all(q0, seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed),
                                progress, callback)
    settings = {"solver": solver, "max_iterations": max_iterations, "population": population,
                "warm_start": warm_start, "warm_spread": warm_spread, "predict": predict, "tolerance": tolerance,
                "angle_tolerance": angle_tolerance, "time_budget": time_budget,
                "stop_at_tolerance": stop_at_tolerance, "bounds": bounds, "priorities": priorities, "options": options,
                "velocity_scale": velocity_scale, "acceleration": acceleration, "retime": retime,
                "task": task if isinstance(task, TrackingTask) else getattr(task, "__name__", repr(task))}
    times = (time.perf_counter() - start, time.process_time() - cpu_start)
    return _result(_retimed(trajectory, q0, rows, limits) if retime else trajectory, q0, rows, stop_reason, solver,
                   settings, times, tolerance, run.lagging)


class _Waypoints:
    """One tracking run's waypoints: each solved by the solver (its problem built, or its targets moved, and its
    warm start made), or a stretch of them answered by the chained engine (:class:`~framework.tracking.chain.Chain`)."""

    def __init__(self, robot: Robot, trajectory: Trajectory, task, method: IKSolver, options: dict, bounds: str,
                 priorities: bool, warm_start: bool, warm_spread: float, predict: bool, asked: dict,
                 limits: JointLimits | None = None) -> None:
        self.robot, self.trajectory, self.method, self.options = robot, trajectory, method, options
        self.builder = _builder(robot, task)
        self.spec = task if isinstance(task, TrackingTask) else (TrackingTask() if task is None else None)
        self.bounds, self.priorities, self.asked = bounds, priorities, asked
        self.warm = (warm_start, warm_spread, predict and warm_start)
        # a task that knows its parameters along the path (``path_parameters``), solved from the previous solution
        # alone: stretches of waypoints run compiled (chain.py); a time budget is each waypoint's own
        self.planner = getattr(self.spec if task is None else task, "path_parameters", None)
        self.chained = self.planner is not None and warm_start and not predict and method.uses_jacobians \
            and asked["time_budget"] is None and limits is None  # (limits act between waypoints: one at a time)
        self.limits, self.lagging = limits, []
        if limits is not None:
            self.intervals = segment_intervals(trajectory.times)
            self.velocity, self.goal = np.zeros(robot.n), None
        self.problem: Problem | None = None
        self.chain: Chain | None = None
        self.state: dict[str, Any] = {}  # the previous solve's search distribution, for solvers that continue it

    def all(self, q0: np.ndarray, rng: np.random.Generator, progress: bool | None,
            callback: TrackingCallback | None) -> tuple[list[tuple[IKResult, tuple[str, ...]]], str]:
        """Every waypoint from ``q0``: the rows ``(result, term kinds)`` and the stop reason."""
        trajectory, rows, previous, stop_reason = self.trajectory, [], q0, "completed"
        with Progress(progress, trajectory.K, f"tracking {trajectory.name} ({self.method.name})") as bar:
            try:
                k, missed = 0, True
                while k < trajectory.K:
                    chained_results = self.chain is not None and not missed
                    if chained_results:
                        results, missed = self.chain.run(k, previous, rng)
                    else:  # the first waypoint, one the engine missed, or no chain: the solver itself
                        result = self.solve(k, previous, rng)
                        if result.stop_reason == "interrupted":
                            stop_reason = "interrupted"
                            break
                        if self.limits is not None:
                            result = self.limited(k, previous, result)
                        results, missed = [result], False
                    kept = 0
                    try:
                        for result in results:
                            rows.append((result, self.problem.program.term_kinds))
                            previous, self.state = result.configuration, result.state
                            bar.advance(result.task_error)
                            k, kept = k + 1, kept + 1
                            if callback is not None and callback(k - 1, result):
                                stop_reason = "callback"
                                break
                            if self.chain is not None and self.chain.changed():  # the callback moved a term: the
                                self.chain = None  # stretch is stale, and the path goes on one solve per waypoint
                                break
                    finally:
                        if chained_results:  # the seeds of the waypoints kept (those past a stop are not the path's)
                            Chain.spend(rng, kept)
                    if stop_reason != "completed":
                        break
            except KeyboardInterrupt:
                stop_reason = "interrupted"
        return rows, stop_reason

    def limited(self, k: int, previous: np.ndarray, result: IKResult) -> IKResult:
        """Waypoint ``k``'s answer within the joint limits from ``previous`` (:func:`~.timing.command`): itself, or
        the configuration the limits allow towards it, evaluated (the waypoint then lags)."""
        goal = result.configuration
        q, velocity, held = np.empty(self.robot.n), np.empty(self.robot.n), np.empty(self.robot.n, dtype=bool)
        count = command(previous, self.velocity, goal, goal if self.goal is None else self.goal,
                        self.limits.velocity, self.limits.acceleration, self.robot.lower, self.robot.upper,
                        float(self.intervals[k]), q, velocity, held)
        self.velocity, self.goal = velocity, goal
        self.lagging.append(count > 0)
        if not count:
            return result
        request = make_request(self.problem, tolerance=self.asked["tolerance"],
                               angle_tolerance=self.asked["angle_tolerance"])
        outcome = Outcome(q, "velocity_limits", result.iterations, result.evaluations, None, result.settings)
        return result_of(self.problem, outcome, self.method.name, request, time.perf_counter() - result.wall_time)

    def solve(self, k: int, previous: np.ndarray, rng: np.random.Generator) -> IKResult:
        """Waypoint ``k`` solved by the solver from ``previous`` (the chain made from its problem the first time)."""
        rotation, position = self.trajectory.rotation(k), self.trajectory.positions[k]
        moved = self.problem is not None and self.spec is not None and self.spec.update(
            self.problem.objective, position, rotation, previous)
        if not moved:
            self.problem = Problem(self.robot, self.builder(k, position, rotation, previous), bounds=self.bounds,
                                   priorities=self.priorities)
        asked = self.asked
        if self.chained:  # once, from the first waypoint's problem (every waypoint's has its layout)
            self.chained, planned = False, self.planner(self.problem, self.trajectory)
            self.chain = None if planned is None else Chain.of(self.problem, planned, self.method, make_request(
                self.problem, tolerance=asked["tolerance"], angle_tolerance=asked["angle_tolerance"],
                max_iterations=asked["max_iterations"], population=asked["population"],
                stop_at_tolerance=asked["stop_at_tolerance"], initial=previous))
        warm_start, warm_spread, predict = self.warm
        seeds, solver_options = _warm_start(self.problem, previous, k, self.method, self.options, warm_start,
                                            warm_spread, predict, asked["population"], rng,
                                            self.method.carries_distribution, self.state)
        result = solve(self.problem, self.method.name, **{**asked, "seed": rng}, initial=seeds,
                       options=solver_options or None)
        if self.chain is not None:
            self.chain.watch()
        return result


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
    :attr:`~framework.solvers.solve.IKResult.state` (empty at the first waypoint)."""
    if not warm_start:  # a local solver would otherwise start from the motion terms' previous configuration
        return None, ({"warm_start": False, **options} if "warm_start" in method.option_names else options)
    seeds = [predictor(problem, previous), previous] if predict else [previous]
    if k == 0:  # the first waypoint may be far from the initial configuration: the solver's own spread
        if "global_iterations" in method.option_names:  # and a global phase where the solver has one
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


def _retimed(trajectory: Trajectory, q0: np.ndarray, rows: list, limits: JointLimits) -> Trajectory:
    """The tracked part of ``trajectory`` with the fastest times that keep ``limits`` along its solutions."""
    if not rows:
        return trajectory
    Q = np.array([r.configuration for r, _ in rows])
    return trajectory[: len(rows)].timed(times=retimed(trajectory.times[: len(rows)], q0, Q, limits))


def _path_limits(robot: Robot, trajectory: Trajectory, velocity_scale, acceleration, retime: bool
                 ) -> JointLimits | None:
    """The joint limits a tracking run keeps (``None``: none asked); they need a timed path."""
    if velocity_scale is None and acceleration is None and not retime:
        return None
    if not trajectory.is_timed:
        raise TaskError(f"joint velocity or acceleration limits need a timed path: {trajectory.name!r} has no times "
                        "(Trajectory.timed(rate=...) or duration=..., a task file's [trajectory] rate or duration)")
    return joint_limits(robot, 1.0 if velocity_scale is None else velocity_scale, acceleration)


def _result(trajectory, q0, rows, stop_reason, solver, settings, times, tolerance, lagging) -> TrackingResult:
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
        reason=path_reason(results, trajectory.K, stop_reason, lagging),
        lagging=np.array(lagging if lagging else [False] * len(results), dtype=bool),
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


