"""Every registered metaheuristic as an IK solver: the shared ask/tell loop on the problem's population cost.

Candidates are ranked by Deb's rules when the problem has levels — ``Problem.priorities`` on (the default) and
regularizers beside the task: a candidate meeting every task tolerance (and inside the limits of a joint-limit
penalty) beats one that does not; among those that do, the lower regularizer cost wins; among those that do not,
the lower constraint violation (K. Deb, "An efficient constraint handling method for genetic algorithms", Comput.
Methods Appl. Mech. Eng. 186 (2000) 311-338). The rules are one scalar per candidate, so every algorithm ranks by
them unchanged: the regularizer cost for feasible candidates, and an upper bound of it plus the task and penalty
cost for the others (the history is then in those units). Otherwise — ``priorities=False`` (the papers' sums) or
a task alone — candidates are ranked by the weighted sum. ``options={"ranking": "weighted"}`` asks for the
weighted sum on a problem with levels too.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from ..errors import SolverError
from ..optimizers.base import Box, OptimizeResult, minimize, resolve_options
from .ik import IKSolver, Outcome, Request
from ..optimizers.registry import get_solver

#: Generations of a metaheuristic when ``solve`` is not given a budget (the papers' 1000).
DEFAULT_ITERATIONS = 1000
#: How candidates are ranked: by the problem (``"auto"``: Deb's rules when it has levels, else the weighted sum),
#: the weighted sum, or Deb's feasibility rules on the priority levels.
RANKINGS = ("auto", "weighted", "feasibility")


class Metaheuristic(IKSolver):
    """A registered population algorithm (:class:`~framework.optimizers.base.Algorithm`) minimizing the problem's
    weighted cost over the search box. Its options are the algorithm's ``DEFAULTS`` (a mapping)."""

    kind = "metaheuristic"

    algorithm: str = ""

    def __init__(self, name: str, options: dict[str, Any] | None = None):
        cls = get_solver(name)
        self.name, self.algorithm = name, name
        self.reference = getattr(cls, "reference", "")
        self.carries_distribution = "covariance" in cls.DEFAULTS
        self.step_option = "sigma0" if "sigma0" in cls.DEFAULTS else None
        self.options = dict(options or {})
        resolve_options(name, self.defaults(), self.options)  # names and kinds checked once, here

    def defaults(self) -> dict[str, Any]:  # type: ignore[override]
        return {**get_solver(self.algorithm).DEFAULTS, "ranking": "auto"}

    def solve(self, problem, request: Request) -> Outcome:
        options = dict(self.options)
        cost = feasibility_cost(problem, request) if ranks_by_feasibility(self.name, problem, options) else None
        callback = request.callback
        if request.stop_at_tolerance or request.deadline is not None:
            user = request.callback

            def callback(iteration: int, best_f: float, best_x: np.ndarray) -> bool:
                stop = bool(user(iteration, best_f, best_x)) if user else False
                if request.deadline is not None and request.time_left() <= 0:
                    return True
                return stop or (request.stop_at_tolerance and within(problem, best_x, request))

        iterations = DEFAULT_ITERATIONS if request.max_iterations is None else request.max_iterations
        if callback is None and not request.progress and cost is None:
            run = compiled_or_loop(self.algorithm, problem, request, iterations, options)
        else:
            run = shared_loop(self.algorithm, problem, request, iterations, options, callback=callback,
                              progress=request.progress, cost=cost)
        stop = run.stop_reason
        if stop == "callback":
            if request.stop_at_tolerance and within(problem, run.x, request):
                stop = "tolerance"
            elif request.deadline is not None and request.time_left() <= 0:
                stop = "time_budget"
        settings = {**run.settings, "population": request.population, "max_iterations": iterations}
        return Outcome(run.x, stop, run.iterations, run.evaluations, run.history, settings, run.state)


def ranks_by_feasibility(name: str, problem, options: dict[str, Any]) -> bool:
    """Whether the solver ``name`` ranks by Deb's rules on ``problem``; pops ``"ranking"`` from ``options``.
    Raises :class:`SolverError` for an unknown ranking, or Deb's rules asked on a problem without priorities."""
    ranking = options.pop("ranking", "auto")
    if ranking not in RANKINGS:
        raise SolverError(f"{name}: ranking must be one of {RANKINGS}; got {ranking!r}")
    if ranking == "feasibility" and not problem.priorities:
        raise SolverError(f"{name}: ranking 'feasibility' needs a problem with priorities (Problem(..., "
                          "priorities=True)); this one is a weighted sum")
    if ranking == "auto":
        return bool(problem.priorities and problem.program.has_regularizers)
    return ranking == "feasibility"


def within(problem, x: np.ndarray, request: Request) -> bool:
    """Whether every task term of ``problem`` is within the request's tolerances at ``x``."""
    return problem.program.within(problem.program.task_errors(x).tolist(), request.tolerance,
                                  request.angle_tolerance)


def feasibility_cost(problem, request: Request) -> Callable[[np.ndarray], np.ndarray]:
    """Deb's rules as a population cost ``(pop, n) -> (pop,)``: the weighted regularizers where every task block
    is within the request's tolerances and every value term (a joint-limit penalty) is zero, else ``bound + `` the
    weighted task and value terms (the constraint violation), with ``bound`` above any regularizer cost in the box
    (every regularizer value is at most its value's scale times the box diagonal)."""
    levels = np.array([term.level for _, term in problem.objective])
    regular, penalties = levels == "regularizer", levels == "value"
    weights = problem.weights
    diagonal = float(np.linalg.norm(problem.robot.upper - problem.robot.lower))
    bound = 10.0 * (1.0 + weights[regular].sum() * (1.0 + diagonal))
    program = problem.program
    limits = program.limits(request.tolerance, request.angle_tolerance)

    def cost(X: np.ndarray) -> np.ndarray:
        values = problem.values(X)
        feasible = np.all(program.task_errors(X) <= limits, axis=1) & np.all(values[:, penalties] <= 0, axis=1)
        return np.where(feasible, values[:, regular] @ weights[regular],
                        bound + values[:, ~regular] @ weights[~regular])

    return cost


def shared_loop(name: str, problem, request: Request, iterations: int, options: Mapping[str, Any] | None, *,
                callback: Callable | None = None, progress: bool = False,
                cost: Callable[[np.ndarray], np.ndarray] | None = None) -> OptimizeResult:
    """``iterations`` generations of the metaheuristic ``name`` on the problem's population cost (or ``cost``),
    in the shared ask/tell loop (:func:`~framework.optimizers.base.minimize`), from the request's warm starts and
    generator."""
    return minimize(cost or problem.cost, (problem.robot.lower, problem.robot.upper), solver=name, rng=request.rng(),
                    max_iterations=iterations, population=request.population, initial=request.initial,
                    bounds=problem.repair_mode, options=options, callback=callback, progress=progress)


def compiled_or_loop(name: str, problem, request: Request, iterations: int, options: dict) -> OptimizeResult:
    """``iterations`` generations of the metaheuristic ``name`` on the problem, with nothing to call between
    them: its compiled loop on the problem's packed terms if it has one (the same generations as
    :func:`~framework.optimizers.base.minimize`), else the shared loop."""
    cls = get_solver(name)
    if not hasattr(cls, "run_compiled") or problem.program.layout.generic:
        return shared_loop(name, problem, request, iterations, options)
    start = time.perf_counter()
    box = Box(problem.robot.lower, problem.robot.upper)
    algorithm = cls(box.n, box, request.population, request.rng(), options, request.initial,
                    max_iterations=int(iterations))
    x, f, history, evaluations = algorithm.run_compiled(problem.program, problem.repair_mode, int(iterations))
    settings = {"solver": cls.name, "population": algorithm.population, "max_iterations": int(iterations),
                "bounds": problem.repair_mode, "f_target": None, "max_evaluations": None, "stagnation": None,
                **algorithm.settings}
    return OptimizeResult(x=x, f=float(f), iterations=len(history), evaluations=int(evaluations), history=history,
                          stop_reason="max_iterations", wall_time=time.perf_counter() - start, solver=cls.name,
                          settings=settings, state=algorithm.state)
