"""``multistart_lm``: the local engine with random restarts, TRAC-IK's strategy, nothing else.

From the warm start (``initial``, else the configuration the regularizers measure from, else the middle of the
box), Levenberg-Marquardt drives every task term within tolerance, restarting from uniform random
configurations when a descent stalls, until the tolerance, the iteration budget or the time budget; then the
regularizers (motion) are minimized on the task (:func:`framework.engine.solve_local`). Task terms always come
first, whatever the weights.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..engine import LocalSettings, solve_local
from ..engine import prepare as prepare_engine
from .ik import BatchPlan, IKSolver, Outcome, Request
from ..validate import positive_int
from .registry import register_ik
from .analytic.seeding import closed_form_start
from .analytic.seeding import prepare as prepare_closed_form
from .analytic.seeding import settles

#: Levenberg-Marquardt iterations (over all restarts) when ``solve`` is given neither an iteration nor a time budget.
DEFAULT_ITERATIONS = 2000


@dataclass(frozen=True)
class MultistartOptions:
    """Options of ``multistart_lm``.

    Attributes:
        stall: iterations without 10 % progress of ``‖r‖²`` before a restart.
        restarts: restart from random configurations (``False``: one descent from the start).
        polish: Gauss-Newton steps after reaching the tolerance (to machine precision).
        regularize: minimize the regularizers on the task afterwards.
        warm_start: without ``initial``, start where the regularizers measure from (e.g. ``q_prev``).
        closed_form: start from the closed-form solution of least cost where the pose task's arm has one
            (:mod:`framework.solvers.analytic`).
    """

    stall: int = 6
    restarts: bool = True
    polish: int = 3
    regularize: bool = True
    warm_start: bool = True
    closed_form: bool = True

    def __post_init__(self) -> None:
        # stored as the ints they were checked to be (an integral float such as 8.0 is a valid count)
        object.__setattr__(self, "stall", positive_int(self.stall, "multistart_lm option stall"))
        object.__setattr__(self, "polish", positive_int(self.polish, "multistart_lm option polish", minimum=0))


def default_iterations(request: Request) -> int:
    """The engine's iteration budget: as asked, else unlimited under a time budget, else the default."""
    if request.max_iterations is not None:
        return request.max_iterations
    return 10**9 if request.deadline is not None else DEFAULT_ITERATIONS


def start_configuration(problem, request: Request, warm_start: bool, *, closed_form: bool = True
                        ) -> tuple[np.ndarray, str]:
    """The first start and where it came from: ``initial``, the regularizers' reference
    (:attr:`~framework.costs.problem.Problem.previous`), or the box middle (the robot's own, read-only: the engine
    copies its start) — or, where the problem's pose task falls on an arm solved in closed form, that arm's exact
    solution of least cost, nearest that start among equals (:func:`~.analytic.seeding.closed_form_start`; not with
    ``closed_form=False``: a batch's start serves every target)."""
    if request.initial is not None:
        x0, start = request.initial[0].copy(), "initial"
    else:
        previous = problem.previous if warm_start else None
        x0, start = (previous, "previous") if previous is not None else (problem.robot.middle, "middle")
    seeded = closed_form_start(problem, x0) if closed_form else None
    return (x0, start) if seeded is None else (seeded, "closed form")


def local_settings(request: Request, options, max_iterations: int, made: dict) -> LocalSettings:
    """The engine settings of a request for a solver's ``options`` (memoized in ``made``, the solver's own table:
    a solve should not pay for building them)."""
    key = (request.tolerance, request.angle_tolerance, max_iterations)
    cached = made.get(key)
    if cached is None:
        if len(made) > 256:
            made.clear()
        cached = made[key] = LocalSettings(
            tolerance=request.tolerance, angle_tolerance=request.angle_tolerance, max_iterations=max_iterations,
            stall=options.stall, restarts=options.restarts, polish=options.polish, regularize=options.regularize)
    return cached


def stop_reason(reached: bool, request: Request) -> str:
    """``tolerance`` when reached, else ``time_budget`` or ``max_iterations``."""
    if reached:
        return "tolerance"
    return "time_budget" if request.deadline is not None and request.time_left() <= 0 else "max_iterations"


@register_ik("multistart_lm")
class MultistartLM(IKSolver):
    """Levenberg-Marquardt from the warm start with random restarts (compiled), then regularizers on the task."""

    reference = "Beeson & Ames, TRAC-IK, Humanoids 2015 (restarts); Marquardt, SIAM J. Appl. Math. 11 (1963)"
    Options = MultistartOptions
    uses_jacobians = True
    kind = "local engine"

    def __init__(self, options=None):
        super().__init__(options)
        self._settings: dict = {}  # the engine settings of requests (local_settings' table)

    def prepare(self, problem) -> None:
        """The engine's compiled code for ``problem`` (:func:`framework.engine.prepare`), and the closed form's."""
        prepare_engine(problem.program)
        if self.options.closed_form:
            prepare_closed_form(problem)

    def batch_plan(self, problem, request: Request) -> BatchPlan:
        x0, start = start_configuration(problem, request, self.options.warm_start, closed_form=False)
        iterations = default_iterations(request)
        settings = local_settings(request, self.options, iterations, self._settings)
        return BatchPlan(x0, settings, escalates=False, report=self._report(start, iterations, 0, None))

    def solve(self, problem, request: Request) -> Outcome:
        x0, start = start_configuration(problem, request, self.options.warm_start,
                                        closed_form=self.options.closed_form)
        iterations = default_iterations(request)
        if start == "closed form" and settles(problem):  # the exact solution is the answer: no descent
            return Outcome(x0, "tolerance", 0, 0, None, self._report(start, iterations, 0, None))
        settings = local_settings(request, self.options, iterations, self._settings)
        result = solve_local(problem.program, x0, request.seed, settings, deadline=request.deadline)
        if request.callback is not None:
            request.callback(1, float(problem.cost(result.x)[0]), result.x.copy())
        return Outcome(result.x, stop_reason(result.reached, request), result.iterations, result.evaluations,
                       None, self._report(start, iterations, result.restarts, result.regularized),
                       task_errors=result.task_errors, values=result.values)

    def _report(self, start: str, iterations: int, restarts: int, regularized: str | None) -> dict[str, Any]:
        """The settings a result reports: where it started, the budget, how the solve went, the options."""
        return {"start": start, "max_iterations": iterations, "restart_count": restarts, "regularized": regularized,
                **self.options.__dict__}
