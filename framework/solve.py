"""``solve(problem, solver=...)``: one IK solve with any registered metaheuristic, or the hybrid.

The hybrid (``solver="hybrid"``) runs a short global phase of a metaheuristic (``cmaes_fast`` by default)
and then :func:`framework.refine.refine`: a bounded local refinement with Pinocchio's analytic Jacobians that
keeps minimizing the non-task terms (motion) while driving the task error to machine precision.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .errors import SolverError
from .problem import Problem
from .multistart import multistart_lm
from .refine import refine
from .solvers import available_solvers, minimize

HYBRID_DEFAULTS: dict[str, Any] = {
    "global_solver": "cmaes_fast",  # metaheuristic of the global phase
    "global_iterations": 30,  # its iterations; 0 refines straight from `initial` (or the box centre)
    "refine_iterations": 100,  # SLSQP / Levenberg-Marquardt iterations per refinement
    "time_budget": None,  # seconds: restart the refinement from random configurations until success or budget
}


@dataclass(frozen=True)
class IKResult:
    """What one IK solve produced.

    Attributes:
        configuration: best joint coordinates ``(n,)`` [rad / m].
        cost: objective value at ``configuration``.
        terms: unweighted value of every term, by name.
        task_error: sum of the unweighted task terms (position [m], orientation, relative position [m]).
        success: ``task_error <= tolerance``.
        stop_reason: why the solver stopped (``max_iterations``, ``tolerance``, ``stagnation``, ...).
        iterations, evaluations: solver iterations and cost evaluations (population members; for the hybrid
            plus one per Jacobian evaluation of the refinement).
        wall_time: seconds.
        history: ``(iterations,)`` best cost after each iteration.
        solver: solver name; settings: every setting used.
    """

    configuration: np.ndarray
    cost: float
    terms: dict[str, float]
    task_error: float
    success: bool
    stop_reason: str
    iterations: int
    evaluations: int
    wall_time: float
    history: np.ndarray = field(repr=False)
    solver: str
    settings: dict[str, Any] = field(default_factory=dict, repr=False)


def solve(
    problem: Problem,
    solver: str = "cmaes",
    *,
    seed: int | np.random.Generator = 0,
    max_iterations: int = 1000,
    population: int = 30,
    tolerance: float = 1e-4,
    stop_at_tolerance: bool = False,
    initial: np.ndarray | None = None,
    options: dict[str, Any] | None = None,
    progress: bool = False,
    callback: Callable[[int, float, np.ndarray], bool | None] | None = None,
) -> IKResult:
    """Solve an IK problem.

    Args:
        problem: robot + weighted objective + bounds handling.
        solver: a registered metaheuristic (see :func:`framework.solvers.available_solvers`), ``"hybrid"``, or
            ``"multistart_lm"`` (population Levenberg-Marquardt, for problems of task terms only: pose IK).
        seed: seed or generator; the same seed gives the same result.
        max_iterations: iteration budget (the hybrid: of its refinement; its global phase has its own).
        population: candidates per iteration.
        tolerance: success threshold on the task error.
        stop_at_tolerance: stop as soon as the best member's task error is within ``tolerance`` (the papers run
            the whole budget; the hybrid always stops at tolerance after refinement).
        initial: warm start ``(n,)`` or ``(k, n)`` (e.g. the previous solution along a trajectory).
        options: solver parameters (for the hybrid: ``global_solver``, ``global_iterations``,
            ``refine_iterations``, ``time_budget`` and ``global_options``).
        progress: print a progress line now and then (metaheuristics).
        callback: ``callback(iteration, best_f, best_x)`` after every iteration of a metaheuristic (for the
            hybrid: of its global phase); returning True stops. Recordings use it to trace every term.
    """
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    if not np.isfinite(tolerance) or tolerance <= 0:
        raise SolverError(f"tolerance must be a positive number; got {tolerance!r}")
    if initial is not None:
        initial = problem.robot.check_population(initial, "initial configuration")
    start = time.perf_counter()
    if solver == "hybrid":
        return _hybrid(problem, rng, population, tolerance, initial, dict(options or {}), start, callback)
    if solver == "multistart_lm":
        return _multistart(problem, rng, population, max_iterations, tolerance, initial, dict(options or {}), start)
    if solver not in available_solvers():
        known = ", ".join(["hybrid", "multistart_lm", *available_solvers()])
        raise SolverError(f"unknown solver {solver!r}; available: {known}")

    user_callback = callback
    if stop_at_tolerance:

        def callback(iteration: int, best_f: float, best_x: np.ndarray) -> bool:
            stop = bool(user_callback(iteration, best_f, best_x)) if user_callback else False
            return stop or bool(problem.evaluate(best_x).task_error[0] <= tolerance)

    run = minimize(
        problem.cost,
        (problem.robot.lower, problem.robot.upper),
        solver=solver,
        rng=rng,
        max_iterations=max_iterations,
        population=population,
        initial=initial,
        bounds=problem.repair_mode,
        options=options,
        callback=callback,
        progress=progress,
    )
    stop = run.stop_reason
    if stop == "callback" and stop_at_tolerance and problem.evaluate(run.x).task_error[0] <= tolerance:
        stop = "tolerance"
    return _result(problem, run.x, stop, run.iterations, run.evaluations, start, run.history, solver,
                   {**run.settings, "population": population, "max_iterations": max_iterations}, tolerance)


def _hybrid(problem, rng, population, tolerance, initial, options, start, callback=None) -> IKResult:
    unknown = set(options) - set(HYBRID_DEFAULTS) - {"global_options"}
    if unknown:
        raise SolverError(f"unknown hybrid option(s) {sorted(unknown)}; known: {sorted(HYBRID_DEFAULTS)}")
    settings = {**HYBRID_DEFAULTS, **options}
    robot = problem.robot
    if settings["global_iterations"] > 0:
        run = minimize(
            problem.cost,
            (robot.lower, robot.upper),
            solver=settings["global_solver"],
            rng=rng,
            max_iterations=settings["global_iterations"],
            population=population,
            initial=initial,
            bounds=problem.repair_mode,
            options=settings.get("global_options"),
            callback=callback,
        )
        x0, history, iterations, evaluations = run.x, list(run.history), run.iterations, run.evaluations
    else:
        x0 = initial[0] if initial is not None else robot.middle
        history, iterations, evaluations = [], 0, 0
    refine_tolerance = min(tolerance, 1e-12)
    best = refine(problem, x0, tolerance=refine_tolerance, max_iterations=settings["refine_iterations"])
    evaluations += best.evaluations
    restarts, budget = 0, settings["time_budget"]
    while budget is not None and best.task_error > tolerance and time.perf_counter() - start < budget:
        restarts += 1
        x0 = robot.random_configurations(rng, 1)[0]
        attempt = refine(problem, x0, tolerance=refine_tolerance, max_iterations=settings["refine_iterations"])
        evaluations += attempt.evaluations
        if attempt.cost < best.cost:
            best = attempt
    history.append(best.cost)
    stop = "tolerance" if best.task_error <= tolerance else ("time_budget" if budget else "refinement_stalled")
    settings.update(refinement=best.method, restarts=restarts)
    return _result(problem, best.x, stop, iterations + 1 + restarts, evaluations, start, history, "hybrid",
                   {**settings, "population": population}, tolerance)


def _multistart(problem, rng, population, max_iterations, tolerance, initial, options, start) -> IKResult:
    unknown = set(options) - {"time_budget", "stall"}
    if unknown:
        raise SolverError(f"unknown multistart_lm option(s) {sorted(unknown)}; known: ['stall', 'time_budget']")
    run = multistart_lm(problem, rng, starts=population, initial=initial, tolerance=tolerance,
                        max_iterations=max_iterations, **options)
    stop = "tolerance" if run.task_error <= tolerance else "max_iterations"
    settings = {"starts": population, "max_iterations": max_iterations, "restarts": run.restarts, **options}
    return _result(problem, run.x, stop, run.iterations, run.evaluations, start, np.array([run.cost]),
                   "multistart_lm", settings, tolerance)


def _result(problem, x, stop, iterations, evaluations, start, history, solver, settings, tolerance) -> IKResult:
    evaluation = problem.evaluate(x)
    task_error = float(evaluation.task_error[0])
    return IKResult(
        configuration=np.asarray(x, dtype=float).copy(),
        cost=float(evaluation.cost[0]),
        terms=evaluation.as_dict(0),
        task_error=task_error,
        success=bool(task_error <= tolerance),
        stop_reason=stop,
        iterations=int(iterations),
        evaluations=int(evaluations),
        wall_time=time.perf_counter() - start,
        history=np.asarray(history, dtype=float),
        solver=solver,
        settings=settings,
    )
