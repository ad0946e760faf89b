"""``solve(problem, solver=...)``: one IK solve with any registered metaheuristic, or the hybrid.

The hybrid (``solver="hybrid"``) refines with :func:`framework.refine.refine` (a bounded local refinement with
Pinocchio's analytic Jacobians that keeps minimizing the non-task terms, motion, while driving the task error to
machine precision) straight from the warm start: ``initial``, else the configuration the motion terms measure
from. If that misses the task, or there is no warm start, a short global phase of a metaheuristic
(``cmaes_fast`` by default) from a uniform start picks the point to refine.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .errors import SolverError
from .problem import Problem
from .multistart import multistart_lm
from .refine import Refinement, refine
from .solvers import available_solvers, minimize

#: Global-phase generations of the hybrid by default, from a warm start and from a uniform start. From the
#: motion terms' previous configuration the refinement alone finds the optimum that 30 generations from uniform
#: starts find (paper 000's four targets, 100 seeds: all f equal), and 10 warm generations never changed the
#: outcome (120 random pose tasks on three arms): the warm start always stayed the best member. When the
#: refinement from the warm start misses the task, the hybrid escalates to the cold global phase.
WARM_GLOBAL_ITERATIONS, COLD_GLOBAL_ITERATIONS = 0, 30

HYBRID_DEFAULTS: dict[str, Any] = {
    "global_solver": "cmaes_fast",  # metaheuristic of the global phase
    "global_iterations": None,  # its generations: None = refine from the warm start, escalating to 30
    # generations from a uniform start if the task is missed (30 at once without a warm start); an explicit
    # number runs that many from the warm start (or uniformly), without escalation
    "warm_start": True,  # without `initial`, start from the configuration the motion terms measure from
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
        state: what a following solve of a similar problem may start from, as options of the same solver
            (:attr:`framework.solvers.Algorithm.state`; e.g. CMA-ES's adapted covariance along a trajectory).
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
    state: dict[str, Any] = field(default_factory=dict, repr=False)


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
                   {**run.settings, "population": population, "max_iterations": max_iterations}, tolerance,
                   run.state)


def _hybrid(problem, rng, population, tolerance, initial, options, start, callback=None) -> IKResult:
    unknown = set(options) - set(HYBRID_DEFAULTS) - {"global_options"}
    if unknown:
        raise SolverError(f"unknown hybrid option(s) {sorted(unknown)}; known: {sorted(HYBRID_DEFAULTS)}")
    settings = {**HYBRID_DEFAULTS, **options}
    robot = problem.robot
    previous = problem.previous if initial is None and settings["warm_start"] else None
    if previous is not None:
        initial, settings["start"] = previous[None], "previous"  # where the motion terms measure from
    else:
        settings["start"] = "initial" if initial is not None else "uniform"
    escalate = settings["global_iterations"] is None and initial is not None
    if settings["global_iterations"] is None:
        settings["global_iterations"] = WARM_GLOBAL_ITERATIONS if initial is not None else COLD_GLOBAL_ITERATIONS
    refine_tolerance = min(tolerance, 1e-12)

    numbers = itertools.count(1)  # iterations reported to `callback`: global generations and refinement steps

    def report(iteration: int, f: float, x: np.ndarray) -> bool:
        return bool(callback(next(numbers), f, x))

    def phase(initial: np.ndarray | None, generations: int) -> tuple[Refinement, list[float], int, int]:
        """Global phase from ``initial`` (uniform if None), then refinement of its best."""
        if generations > 0:
            run = minimize(problem.cost, (robot.lower, robot.upper), solver=settings["global_solver"], rng=rng,
                           max_iterations=generations, population=population, initial=initial,
                           bounds=problem.repair_mode, options=settings.get("global_options"),
                           callback=report if callback else None)
            x0, history, iterations, evaluations = run.x, list(run.history), run.iterations, run.evaluations
        else:
            x0, history, iterations, evaluations = initial[0] if initial is not None else robot.middle, [], 0, 0
        trace = (lambda x: report(0, float(problem.cost(x[None])[0]), x.copy())) if callback else None
        best = refine(problem, x0, tolerance=refine_tolerance, max_iterations=settings["refine_iterations"],
                      callback=trace)
        return best, history, iterations + 1, evaluations + best.evaluations

    best, history, iterations, evaluations = phase(initial, settings["global_iterations"])
    settings["escalated"] = escalate and best.task_error > tolerance
    if settings["escalated"]:  # the warm start's basin misses the task: the full global phase, uniform start
        cold, more, extra, spent = phase(None, COLD_GLOBAL_ITERATIONS)
        history, iterations, evaluations = history + more, iterations + extra, evaluations + spent
        best = cold if cold.cost < best.cost else best
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
    return _result(problem, best.x, stop, iterations + restarts, evaluations, start, history, "hybrid",
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


def _result(
    problem, x, stop, iterations, evaluations, start, history, solver, settings, tolerance, state=None
) -> IKResult:
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
        state=state or {},
    )
