"""``hybrid``: the local engine first, a metaheuristic's global phase when that is not enough — the default.

1. The local engine (:func:`framework.engine.solve_local`) from the warm start — ``initial``, else the
   configuration the regularizers measure from (motion's ``q_prev``), else the middle of the box:
   Levenberg-Marquardt reaches the task, Newton steps minimize the regularizers on it. From a warm start the
   engine first stays in its basin (no restart; along a path a restart would jump to another branch), then
   restarts from random configurations if that basin misses (the first of them drawn too: the warm start's
   basin was searched; the report's ``restart_count`` counts every descent from a drawn configuration); from
   the middle it restarts at once.
2. If that misses the task, a short global phase of a metaheuristic (``cmaes_fast``, 30 generations) from a
   uniform start picks another point for the engine (the better of the two is kept). An explicit
   ``global_iterations`` runs the global phase first instead.
   With collision terms whose spheres cover meshes, boxes or cylinders (a loose cover, fatter than the links;
   with priorities), each descent first solves the problem without them (in the warm start's basin, then with
   restarts from a drawn start); if coal's exact check finds that answer clear (by the terms' margins), it is
   the answer: the terms' inequalities are inactive there, so it meets the whole problem (and its regularizers
   are at their optimum on the task). Most answers are clear, and the sphere rows would have spent iterations on
   near misses the exact geometry does not have. Otherwise the engine solves the whole problem from the same
   start; from drawn starts, up to :data:`CLEAR_TRIES` of them are solved without the terms first (another
   branch of the task is often clear; each reaches the task, then is regularized from there, and where the
   regularized answer is in contact the point that reached the task is the answer if it is clear). (Where every
   geometry is a sphere of the cover, the engine's own lazy contact rows, :mod:`~framework.engine.reach`, are as
   exact and cheaper.)
   Whenever the engine ends short of the task with a collision term's sphere rows active, its last steps are
   taken again on the links' convex hulls (:func:`framework.engine.hull_reach.hull_reach`): the spheres are
   fatter than the links, the hulls hold them tightly, and the exact check decides success anyway.
3. For a weighted objective (``Problem.priorities`` false, the papers' sums), a point on the task is kept only
   if it also minimizes the weighted sum: when the task's multipliers say that leaving the task lowers the sum
   (weights too small for reaching to pay), the task terms that do not pay for themselves are released into
   the objective (:func:`framework.engine.minimize_weighted`), damped Newton steps on the whole sum from the
   start look into another basin, and the best point by the objective is returned.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..engine import LocalResult, LocalSettings, minimize_sum, minimize_weighted, reaching_is_optimal, solve_local
from ..engine import prepare as prepare_engine
from ..engine.hull_reach import blocked_by_spheres, hull_reach
from ..engine.draws import stream
from .ik import BatchPlan, IKSolver, Outcome, Request
from ..errors import SolverError
from ..optimizers.base import resolve_options
from ..optimizers.registry import get_solver
from ..validate import positive_int
from .metaheuristic import compiled_or_loop, shared_loop, within
from .analytic.seeding import prepare as prepare_closed_form
from .analytic.seeding import settles
from .multistart import default_iterations, local_settings, start_configuration, stop_reason
from .registry import register_ik

#: Generations of the global phase when the engine misses the task from the warm start.
GLOBAL_ITERATIONS = 30
#: Iterations without progress before the engine gives up the warm start's basin (and restarts at random).
WARM_STALL = 40
#: Drawn starts of the problem without its collision terms (a loose cover) tried for an answer coal finds clear
#: before the engine with the sphere rows, whose spheres (fatter than the links) may not fit where the links do:
#: PR2 over a table (benchmarks/collisions.py), one target of 100 that none of the sphere rows' 1,700 restarts met
#: has a clear answer without the terms from 4 of 5 drawn starts.
CLEAR_TRIES = 8


@dataclass(frozen=True)
class HybridOptions:
    """Options of ``hybrid``.

    Attributes:
        global_solver: metaheuristic of the global phase.
        global_iterations: its generations: ``None`` runs it only when the engine misses the task (30
            generations from a uniform start); a number runs that many first, from the warm start.
        global_options: options of the global solver.
        warm_start: without ``initial``, start where the regularizers measure from (e.g. ``q_prev``).
        restarts: random restarts of the engine within its budget.
        stall: engine iterations without progress before a restart.
        polish: Gauss-Newton steps after reaching the tolerance.
        closed_form: start from the closed-form solution of least cost where the pose task's arm has one
            (:mod:`framework.solvers.analytic`).
    """

    global_solver: str = "cmaes_fast"
    global_iterations: int | None = None
    global_options: Mapping[str, Any] | None = None
    warm_start: bool = True
    restarts: bool = True
    stall: int = 6
    polish: int = 3
    regularize: bool = True
    closed_form: bool = True

    def __post_init__(self) -> None:
        if self.global_iterations is not None:
            object.__setattr__(self, "global_iterations",
                               positive_int(self.global_iterations, "hybrid option global_iterations", minimum=0))
        # stored as the ints they were checked to be (an integral float such as 8.0 is a valid count)
        object.__setattr__(self, "stall", positive_int(self.stall, "hybrid option stall"))
        object.__setattr__(self, "polish", positive_int(self.polish, "hybrid option polish", minimum=0))
        for flag in ("warm_start", "restarts", "regularize", "closed_form"):
            if not isinstance(getattr(self, flag), bool):
                raise SolverError(f"hybrid option {flag} must be true or false; got {getattr(self, flag)!r}")
        if not isinstance(self.global_solver, str):
            raise SolverError(f"hybrid option global_solver must be a metaheuristic's name; got {self.global_solver!r}")
        if self.global_options is not None and not isinstance(self.global_options, Mapping):
            raise SolverError(f"hybrid option global_options must be a table of options; got {self.global_options!r}")
        algorithm = get_solver(self.global_solver)  # an unknown name raises, listing the known ones
        resolve_options(self.global_solver, algorithm.DEFAULTS, self.global_options)


@register_ik("hybrid")
class Hybrid(IKSolver):
    """Compiled local engine from the warm start; a short metaheuristic phase when it misses (see module)."""

    reference = "ours: Levenberg-Marquardt + task-constrained Newton, CMA-ES (Hansen, arXiv:1604.00772)"
    Options = HybridOptions
    uses_jacobians = True
    kind = "local engine + global phase"

    def __init__(self, options=None):
        super().__init__(options)
        # what every report holds, in its order: the options, then how the solve went (a solve copies it and sets
        # its own entries: cheaper than a merge)
        self._blank_report = {k: v for k, v in self.options.__dict__.items() if k != "global_options"}
        self._blank_report.update(start=None, max_iterations=None, escalated=False, restart_count=0, regularized=None,
                                  weighted=False, hull_runs=0, on_hulls=False, clear_first=False, population=None)
        self._settings: dict = {}  # the engine settings of requests (local_settings' table)
        self._basin: dict = {}  # their warm-start and reach-only variants (_in_basin's, _unregularized's table)

    def prepare(self, problem) -> None:
        """The engine's compiled code for ``problem`` (:func:`framework.engine.prepare`), and the closed form's."""
        prepare_engine(problem.program)
        if self.options.closed_form:
            prepare_closed_form(problem)

    def batch_plan(self, problem, request: Request) -> BatchPlan | None:
        """The engine from the warm start in its basin, then (where that misses) from a drawn start with restarts,
        as :meth:`solve` takes them; on the problem without its collision terms when it is first solved so
        (:meth:`clears_first`: the first of its clear tries); none when a global phase comes first or the weighted
        sum decides (``priorities`` off with regularizers)."""
        o = self.options
        if o.global_iterations or not (problem.priorities or not problem.program.has_regularizers):
            return None
        x0, start = start_configuration(problem, request, o.warm_start, closed_form=False)
        budget = default_iterations(request)
        settings = local_settings(request, o, budget, self._settings)
        report = self._report(start, budget, 0, None, request)
        first = settings if start == "middle" or not o.restarts else self._in_basin(settings)
        then = settings if first is not settings else None  # _search: the warm basin, then a drawn start
        return BatchPlan(x0, first, report=report, clear_first=self.clears_first(problem), then=then)

    def solve(self, problem, request: Request) -> Outcome:
        o = self.options
        x0, start = start_configuration(problem, request, o.warm_start, closed_form=o.closed_form)
        budget = default_iterations(request)
        if start == "closed form" and settles(problem):  # the exact solution is the answer: no descent
            return Outcome(x0, "tolerance", 0, 0, None, self._report(start, budget, 0, None, request))
        settings = local_settings(request, o, budget, self._settings)
        draws = stream(request.seed)  # the engine's restarts, one stream through every phase
        first = settings if start == "middle" or not o.restarts else self._in_basin(settings)
        opening = None
        if o.global_iterations or request.callback:
            return self._search(problem, request, x0, start, budget, settings, first, draws, opening)
        if not problem.checks_collisions:
            # the common case: the engine from the start; it is the answer when it reaches the task and the
            # weighted sum does not decide (priorities, or no regularizers: no multipliers to weigh), or decides
            # for it (the point on the task also minimizes the weighted sum: see _search, 3.)
            opening = solve_local(problem.program, x0, draws, first, deadline=request.deadline)
            if opening.reached and (problem.priorities  # (no multipliers: optimal, nothing was regularized)
                                    or reaching_is_optimal(problem.program, opening.x, opening.multipliers)):
                report = self._report(start, budget, opening.restarts, opening.regularized, request)
                # (tuple.__new__: the named tuple's own __new__ is a Python call more per solve)
                return tuple.__new__(Outcome, (opening.x, "tolerance", opening.iterations, opening.evaluations, None,
                                               report, {}, opening.task_errors, opening.values, None))
        elif self.clears_first(problem):  # likewise without the collision terms, the answer when coal finds it clear
            opening = solve_local(problem.without_collision_terms.program, x0, draws, first, deadline=request.deadline)
            whole, check = _clear_answer(problem, opening) if opening.reached else (None, None)
            if whole is not None:  # (_search's clear_first, its first call)
                report = self._report(start, budget, whole.restarts, whole.regularized, request, clear_first=True)
                return tuple.__new__(Outcome, (whole.x, "tolerance", whole.iterations, whole.evaluations, None, report,
                                               {}, whole.task_errors, whole.values, check))
        return self._search(problem, request, x0, start, budget, settings, first, draws, opening)

    def _unregularized(self, settings: LocalSettings) -> LocalSettings:
        """``settings`` without the regularizer phase (cached as :meth:`_in_basin`'s)."""
        cached = self._basin.get((settings, "reach"))
        if cached is None:
            cached = self._basin[(settings, "reach")] = replace(settings, regularize=False)
        return cached

    def _in_basin(self, settings: LocalSettings) -> LocalSettings:
        """The settings of a descent that stays in the warm start's basin (no restart, a patient stall rule)."""
        cached = self._basin.get(settings)
        if cached is None:
            if len(self._basin) > 256:
                self._basin.clear()
            cached = self._basin[settings] = replace(settings, restarts=False, stall=WARM_STALL)
        return cached

    def clears_first(self, problem) -> bool:
        """Whether each descent first solves the problem without its collision terms (see module, 2.: collision
        terms with a loose sphere cover, priorities, no global phase first)."""
        return problem.checks_collisions and not self.options.global_iterations and problem.priorities \
            and problem.program.loose_hulls and problem.without_collision_terms is not None

    def _report(self, start: str, budget: int, restarts: int, regularized: str | None, request: Request, *,
                escalated: bool = False, weighted: bool = False, hull_runs: int = 0, on_hulls: bool = False,
                clear_first: bool = False) -> dict[str, Any]:
        """The settings a result reports: the options and how the solve went."""
        report = self._blank_report.copy()
        report["start"], report["max_iterations"], report["restart_count"] = start, budget, restarts
        report["regularized"], report["population"] = regularized, request.population
        if escalated or weighted or hull_runs or on_hulls or clear_first:
            report.update(escalated=escalated, weighted=weighted, hull_runs=hull_runs, on_hulls=on_hulls,
                          clear_first=clear_first)
        return report

    def _search(self, problem, request: Request, x0: np.ndarray, start: str, budget: int, settings: LocalSettings,
                first: LocalSettings, draws: np.ndarray, opening: LocalResult | None) -> Outcome:
        """Every phase of the module's list; ``opening``: the engine's run from ``x0`` with ``first`` when
        :meth:`solve` made it already (the whole solve when no collision term, global phase or callback; for a loose
        cover, :meth:`clears_first`, the run without the collision terms, whose answer was short or in contact)."""
        o = self.options
        counter = _Counter(problem, request)
        iterations = evaluations = restarts = 0
        history: list[float] = []

        def engine(x: np.ndarray | None, settings: LocalSettings = settings, program=problem.program):
            nonlocal iterations, evaluations, restarts
            result = solve_local(program, x, draws, settings, deadline=request.deadline)
            iterations, evaluations = iterations + result.iterations, evaluations + result.evaluations
            restarts += result.restarts + (x is None)  # a descent from a drawn start is a restart too
            counter.report(result.x)
            return result

        def global_phase(initial: np.ndarray | None, generations: int) -> np.ndarray:
            nonlocal iterations, evaluations
            asked = request._replace(initial=initial)
            if request.callback is None and request.deadline is None:  # nothing to call between generations
                run = compiled_or_loop(o.global_solver, problem, asked, generations, dict(o.global_options or {}))
            else:
                run = shared_loop(o.global_solver, problem, asked, generations, o.global_options,
                                  callback=counter.global_callback)
            iterations, evaluations = iterations + run.iterations, evaluations + run.evaluations
            history.extend(run.history.tolist())
            return run.x

        hull_runs: list = []  # each run of the hull steps (its LocalResult)

        def hulls(result):  # the sphere rows kept it from the task: the last steps on the links' convex hulls
            nonlocal iterations, evaluations
            if result.reached or not blocked_by_spheres(problem.program, result.task_errors) \
                    or request.time_left() <= 0:
                return result
            hulled = hull_reach(problem.program, result.x, settings, deadline=request.deadline)
            if hulled is None:
                return result
            iterations, evaluations = iterations + hulled.iterations, evaluations + hulled.evaluations
            hull_runs.append(hulled)
            counter.report(hulled.x)
            clear = hulled.reached and not problem.collisions(hulled.x).colliding  # nested pairs have no rows
            return hulled if clear else result

        def clear_first(x: np.ndarray | None, settings: LocalSettings):  # (see _clear_first)
            return _clear_first(problem, engine, x, settings, self._unregularized(settings))

        escalated, check, best = False, None, None
        if o.global_iterations:
            x0 = global_phase(x0[None] if start != "middle" else None, o.global_iterations)
        loose = self.clears_first(problem)
        met = True  # whether the warm start's basin met the task without the collision terms
        if loose and opening is not None:  # solve() made clear_first's first call: short of the task, or in contact
            iterations, evaluations, restarts = opening.iterations, opening.evaluations, opening.restarts
            counter.report(opening.x)
            met, opening = opening.reached, None
        elif loose:  # in the warm start's basin first (along a path, a restart would jump to another branch)
            best, check, met = clear_first(x0, first)
        if best is None:  # from the warm start: its basin first (a slow descent near a singularity is no reason
            # to leave it), then random restarts (that basin was searched: the first is drawn too). A basin that
            # misses the task without the collision terms misses it with them: then straight to the restarts
            skip = not met and first is not settings and request.time_left() > 0
            if opening is not None:  # made by solve(): counted as engine() counts its runs
                iterations, evaluations, restarts = opening.iterations, opening.evaluations, opening.restarts
                counter.report(opening.x)
            best = None if skip else hulls(engine(x0, first) if opening is None else opening)
            if best is None or (not best.reached and first is not settings and request.time_left() > 0):
                found = None
                for _ in range(CLEAR_TRIES if loose else 0):  # drawn starts without the terms, for a clear answer
                    found, check, reached = clear_first(None, settings)
                    if found is not None or not reached or request.time_left() <= 0:
                        break
                best = found if found is not None else _better(problem, best, hulls(engine(None)))  # a drawn start
        if not best.reached and o.global_iterations is None and request.time_left() > 0:
            escalated = True  # the warm start's basin misses the task: the global phase from a uniform start
            cold = hulls(engine(global_phase(None, GLOBAL_ITERATIONS)))
            best = _better(problem, best, cold)
        x, errors, values, weighted = best.x, best.task_errors, best.values, False
        if not problem.priorities and (not best.reached or not reaching_is_optimal(problem.program, x,
                                                                                  best.multipliers)):
            weighted = True  # the weighted sum decides: reaching costs more than it gains, or the task is out of reach
            x, spent = _weighted_answer(problem, best, x0, settings, request.deadline)
            errors, values, evaluations = None, None, evaluations + spent
            counter.report(x)
        stop = stop_reason(within(problem, x, request) if errors is None else best.reached, request)
        report = self._report(start, budget, restarts, best.regularized, request, escalated=escalated,
                              weighted=weighted, hull_runs=len(hull_runs),
                              on_hulls=any(best is r for r in hull_runs), clear_first=check is not None)
        return Outcome(x, stop, iterations, evaluations, np.array(history) if history else None, report,
                       task_errors=errors, values=values, collisions=check)  # check: made at x, when made


def _clear_first(problem, engine, x: np.ndarray | None, settings: LocalSettings, reach_only: LocalSettings):
    """The problem without its collision terms from ``x`` (``None``: a drawn start; ``engine(x, settings, program)``
    runs the engine and counts its work): its answer as the whole problem's, and the check, when coal finds it
    clear by the terms' margins (the terms' inequalities are inactive there), and True; else ``(None, None, met)``:
    whether that answer met the task (in contact). From a drawn start the task is reached first (``reach_only``:
    ``settings`` without the regularizers) and regularized from there: where the regularizers pull the answer into
    contact, the point that reached the task is the answer when it is clear (PR2's regularized answers put its left
    fingers into its right forearm on one target from every drawn start, where half the points reaching the task
    are clear)."""
    plain = problem.without_collision_terms.program
    if x is not None:
        result = engine(x, settings, plain)
        return (*_clear_answer(problem, result), True) if result.reached else (None, None, False)
    reached = engine(None, reach_only, plain)
    if not reached.reached:
        return None, None, False
    result = engine(reached.x, settings, plain)
    whole, check = _clear_answer(problem, result) if result.reached else (None, None)
    return (whole, check, True) if whole is not None else (*_clear_answer(problem, reached), True)


def _clear_answer(problem, result: LocalResult) -> tuple[LocalResult | None, Any]:
    """``result`` (the engine on the problem without its collision terms, on the task) as the whole problem's answer,
    and the exact check at it, when coal finds it clear by the terms' margins (their inequalities are inactive
    there); else ``(None, None)``."""
    check = problem.collisions(result.x, margins=True)
    if check.colliding:
        return None, None
    values, errors = problem.program.values_and_errors(result.x)
    return result._replace(task_errors=errors, values=values, multipliers=None), check


def _better(problem, a: LocalResult | None, b: LocalResult) -> LocalResult:
    """The engine result that reaches the task, else the one of lower cost (``a`` may be None)."""
    if a is None:
        return b
    if a.reached != b.reached:
        return a if a.reached else b
    return min((a, b), key=lambda c: float(problem.cost(c.x)[0]))


def _weighted_answer(problem, best: LocalResult, x0: np.ndarray, settings: LocalSettings,
                     deadline: float | None) -> tuple[np.ndarray, int]:
    """When the weighted sum decides: the lowest cost among the engine's answer, that answer with the task terms
    that do not pay for themselves released, and damped Newton on the whole sum (from the answer when it missed
    the task, and from ``x0``); with the evaluations spent."""
    points, spent = [best.x], 0
    if best.reached:  # release the task terms that do not pay for themselves
        y, more = minimize_weighted(problem.program, best.x, best.multipliers, settings, deadline=deadline)
        spent += more
        points.append(y)
    for origin in (best.x, x0) if not best.reached else (x0,):  # damped Newton on the whole sum
        z, _, more = minimize_sum(problem.program, origin, settings, deadline=deadline)
        z, last = minimize_weighted(problem.program, z, None, settings, deadline=deadline)
        spent += more + last
        points.append(z)
    return points[int(np.argmin(problem.cost(np.array(points))))], spent


class _Counter:
    """Numbers the iterations reported to ``solve``'s callback across the phases (engine results included)."""

    def __init__(self, problem, request: Request):
        self.problem, self.request, self.count = problem, request, 0

    def report(self, x: np.ndarray) -> None:
        self.count += 1
        if self.request.callback is not None:
            self.request.callback(self.count, float(self.problem.cost(x)[0]), x.copy())

    def global_callback(self, iteration: int, best_f: float, best_x: np.ndarray) -> bool:
        self.count += 1
        stop = bool(self.request.callback(self.count, best_f, best_x)) if self.request.callback else False
        return stop or (self.request.deadline is not None and time.monotonic() >= self.request.deadline)
