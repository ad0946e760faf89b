"""Every registered metaheuristic as an IK solver: the shared ask/tell loop on the problem's population cost."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np


from .base import Box, OptimizeResult, minimize
from .ik import IKSolver, Outcome, Request
from .registry import get_solver

#: Generations of a metaheuristic when ``solve`` is not given a budget (the papers' 1000).
DEFAULT_ITERATIONS = 1000


class Metaheuristic(IKSolver):
    """A registered population algorithm (:class:`~framework.solvers.base.Algorithm`) minimizing the problem's
    weighted cost over the search box. Its options are the algorithm's ``DEFAULTS`` (a mapping)."""

    algorithm: str = ""

    def __init__(self, name: str, options: dict[str, Any] | None = None):
        cls = get_solver(name)
        self.name, self.algorithm = name, name
        self.reference = getattr(cls, "reference", "")
        self.carries_distribution = "covariance" in cls.DEFAULTS
        self.step_option = "sigma0" if "sigma0" in cls.DEFAULTS else None
        self.options = dict(options or {})

    def defaults(self) -> dict[str, Any]:  # type: ignore[override]
        return dict(get_solver(self.algorithm).DEFAULTS)

    def solve(self, problem, request: Request) -> Outcome:
        callback = request.callback
        if request.stop_at_tolerance or request.deadline is not None:
            user = request.callback

            def callback(iteration: int, best_f: float, best_x: np.ndarray) -> bool:
                stop = bool(user(iteration, best_f, best_x)) if user else False
                if request.deadline is not None and request.time_left() <= 0:
                    return True
                return stop or (request.stop_at_tolerance and within(problem, best_x, request))

        iterations = DEFAULT_ITERATIONS if request.max_iterations is None else request.max_iterations
        if callback is None and not request.progress:
            run = compiled_or_loop(self.algorithm, problem, request, iterations, self.options)
        else:
            run = shared_loop(self.algorithm, problem, request, iterations, self.options, callback=callback,
                              progress=request.progress)
        stop = run.stop_reason
        if stop == "callback":
            if request.stop_at_tolerance and within(problem, run.x, request):
                stop = "tolerance"
            elif request.deadline is not None and request.time_left() <= 0:
                stop = "time_budget"
        settings = {**run.settings, "population": request.population, "max_iterations": iterations}
        return Outcome(run.x, stop, run.iterations, run.evaluations, run.history, settings, run.state)


def within(problem, x: np.ndarray, request: Request) -> bool:
    """Whether every task term of ``problem`` is within the request's tolerances at ``x``."""
    from ..engine import task_errors

    return problem.program.within(task_errors(problem.program, x).tolist(), request.tolerance,
                                  request.angle_tolerance)


def shared_loop(name: str, problem, request: Request, iterations: int, options: Mapping[str, Any] | None, *,
                callback: Callable | None = None, progress: bool = False) -> OptimizeResult:
    """``iterations`` generations of the metaheuristic ``name`` on the problem's population cost, in the
    shared ask/tell loop (:func:`~framework.solvers.base.minimize`), from the request's warm starts and
    generator."""
    return minimize(problem.cost, (problem.robot.lower, problem.robot.upper), solver=name, rng=request.rng(),
                    max_iterations=iterations, population=request.population, initial=request.initial,
                    bounds=problem.repair_mode, options=options, callback=callback, progress=progress)


def compiled_or_loop(name: str, problem, request: Request, iterations: int, options: dict) -> OptimizeResult:
    """``iterations`` generations of the metaheuristic ``name`` on the problem, with nothing to call between
    them: its compiled loop on the problem's packed terms if it has one (the same generations as
    :func:`~framework.solvers.base.minimize`), else the shared loop."""
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
