"""``solve(problem, solver=...)``: the one entry point of single IK solves.

It validates the request, looks the solver up by name (``"hybrid"`` by default: the compiled local engine from
the warm start, a metaheuristic's global phase when that misses; ``"multistart_lm"``: the engine alone; or any
registered metaheuristic), runs it and reports an :class:`IKResult`. Success is strict: every task term within
its tolerance in its own unit — positions and relative positions within ``tolerance`` [m], orientations within
``angle_tolerance`` [rad] (default: the same number) — and, when the problem has collision terms, no contact on the
exact geometry (that check, not the terms' sphere rows, decides: spheres are fatter than the links).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ..geometry.collision import CollisionReport
from ..engine.draws import seed_of
from ..errors import SolverError
from ..costs.problem import Problem
from .ik import Request
from .registry import ik_solver
from .settings import DEFAULTS
from .why import failure_reason
from ..optimizers.base import MAX_POPULATION
from ..validate import positive_int
from ..validate import float_copy

#: The solver ``solve`` uses when none is named (:data:`~framework.solvers.settings.DEFAULTS`).
DEFAULT_SOLVER = DEFAULTS.solver
#: Default success tolerance: 1e-6 m for positions, 1e-6 rad for orientations.
DEFAULT_TOLERANCE = DEFAULTS.tolerance


class _MadeOnRead:
    """A table of :class:`IKResult` made from the solve's numbers the first time it is read (kept in the slot
    named like it with a leading underscore)."""

    def __set_name__(self, owner: type, name: str) -> None:
        self.slot = "_" + name

    def __get__(self, result: IKResult | None, owner: type | None = None) -> Any:
        if result is None:
            return self
        if result._source is not None:
            result._make()
        return getattr(result, self.slot)


class IKResult:
    """What one IK solve produced.

    Attributes:
        configuration: best joint coordinates ``(n,)`` [rad / m].
        cost: objective value at ``configuration``.
        terms: unweighted value of every term, by name.
        task_error: sum of the unweighted task terms (position [m] + orientation ``sin(φ/2)`` + ...: the papers'
            measure), collision terms left out (``collisions`` reports contacts).
        errors: each task term's error in its own unit, by name: distance [m] for positions and relative
            positions, angle φ [rad] for orientations (a pose gives ``name.distance`` and ``name.angle``; a
            collision term its deepest sphere overlap [m]).
        success: every entry of ``errors`` within its tolerance and, with collision terms, no contact in
            ``collisions`` — the collision terms' own entries (sphere overlaps) are not asked: the exact check
            decides (never after an interruption).
        stop_reason: why the solver stopped (``tolerance``, ``max_iterations``, ``time_budget``, ``stagnation``,
            ``local_minimum``, ``interrupted``, ...).
        iterations, evaluations: solver iterations and cost / residual evaluations.
        wall_time: seconds.
        history: best cost after each iteration (metaheuristics; per phase for the hybrid); the task residual's
            norm at each evaluation (``pinv``, ``dls``).
        solver: solver name; settings: every setting used.
        state: what a following solve of a similar problem may start from, as options of the same solver
            (e.g. CMA-ES's adapted covariance along a trajectory).
        collisions: the exact collision check at ``configuration`` (coal on the URDF's geometry) when the
            problem has collision terms, else ``None``.
        reason: why a failed solve failed, in one line (the task term missed and by how much, with what the term
            knows of why: a target beyond reach, outside the joint bounds; or the contact found); ``""`` on success.

    ``terms``, ``task_error``, ``errors`` and ``history`` are made from the solve's numbers when first read
    (most callers read only the configuration and the success: a solve should not pay for tables nobody reads);
    a pickled result carries them made.
    """

    __slots__ = ("configuration", "cost", "success", "stop_reason", "iterations", "evaluations", "wall_time",
                 "solver", "settings", "state", "collisions", "_terms", "_task_error", "_errors", "_history",
                 "_source", "_why")

    def __init__(self, configuration: np.ndarray, cost: float, terms: dict[str, float], task_error: float,
                 success: bool, stop_reason: str, iterations: int, evaluations: int, wall_time: float,
                 history: np.ndarray, solver: str, settings: dict[str, Any] | None = None,
                 state: dict[str, Any] | None = None, errors: dict[str, float] | None = None,
                 collisions: CollisionReport | None = None) -> None:
        self.configuration, self.cost, self.success, self.stop_reason = configuration, cost, success, stop_reason
        self.iterations, self.evaluations, self.wall_time, self.solver = iterations, evaluations, wall_time, solver
        self.settings = {} if settings is None else settings
        self.state = {} if state is None else state
        self.collisions = collisions
        self._terms, self._task_error, self._history = terms, task_error, history
        self._errors = {} if errors is None else errors
        self._source = None
        self._why = "" if success else f"stopped by {stop_reason}"

    @classmethod
    def _of_solve(cls, configuration: np.ndarray, cost: float, success: bool, stop_reason: str, iterations: int,
                  evaluations: int, wall_time: float, solver: str, settings: dict[str, Any], state: dict[str, Any],
                  collisions: CollisionReport | None, source: tuple, why: str = "") -> IKResult:
        """A result whose tables are made on first read from ``source``: ``(program, term values (list, term
        order), task block errors (list, block order), history or None)``."""
        made = object.__new__(cls)  # (the slots set here: __init__'s defaults cost a call per solve)
        made.configuration, made.cost, made.success, made.stop_reason = configuration, cost, success, stop_reason
        made.iterations, made.evaluations, made.wall_time, made.solver = iterations, evaluations, wall_time, solver
        made.settings, made.state, made.collisions, made._source = settings, state, collisions, source
        made._why = why
        return made

    @property
    def reason(self) -> str:
        """Why the solve failed, in one line (``""`` on success; made at the end of the solve, while its targets are
        the ones it solved for)."""
        return self._why

    def _make(self) -> None:
        program, values, errors, history = self._source
        layout = program.layout
        self._terms = dict(zip(layout.names, values))
        self._task_error = sum([values[k] for k in layout.task_terms])
        self._errors = program.named_errors(errors)
        self._history = np.array([self.cost]) if history is None else np.asarray(history, dtype=float)
        self._source = None

    terms = _MadeOnRead()
    task_error = _MadeOnRead()
    errors = _MadeOnRead()
    history = _MadeOnRead()

    def __getstate__(self) -> dict[str, Any]:
        if self._source is not None:
            self._make()
        return {name: getattr(self, name) for name in self.__slots__}

    def __setstate__(self, state: dict[str, Any]) -> None:
        for name, value in state.items():
            object.__setattr__(self, name, value)

    def __repr__(self) -> str:
        shown = ("configuration", "cost", "terms", "task_error", "success", "stop_reason", "iterations",
                 "evaluations", "wall_time", "solver", "errors", "collisions")
        return f"IKResult({', '.join(f'{name}={getattr(self, name)!r}' for name in shown)})"


def solve(
    problem: Problem,
    solver: str | None = None,
    *,
    seed: int | np.random.Generator = DEFAULTS.seed,
    tolerance: float = DEFAULTS.tolerance,
    angle_tolerance: float | None = DEFAULTS.angle_tolerance,
    time_budget: float | None = DEFAULTS.time_budget,
    max_iterations: int | None = DEFAULTS.max_iterations,
    population: int = DEFAULTS.population,
    stop_at_tolerance: bool = DEFAULTS.stop_at_tolerance,
    initial: np.ndarray | None = None,
    options: dict[str, Any] | None = None,
    progress: bool = False,
    callback: Callable[[int, float, np.ndarray], bool | None] | None = None,
) -> IKResult:
    """Solve an IK problem.

    Args:
        problem: robot + weighted objective + bounds handling.
        solver: ``"hybrid"`` (default), ``"multistart_lm"`` or a registered metaheuristic
            (:func:`framework.solvers.solver_names`).
        seed: seed or generator; the same seed gives the same result.
        tolerance: success threshold of every position-like task term [m].
        angle_tolerance: success threshold of every orientation [rad] (default: ``tolerance``).
        time_budget: seconds for the whole solve (the local engine checks it inside its loops), counted once the
            solver's compiled code is loaded (a process's first solve loads it from numba's disk cache, or
            compiles it: that time is in ``wall_time``, not in the budget).
        max_iterations: iteration budget (metaheuristics: generations, default 1000; local engine:
            Levenberg-Marquardt iterations over all restarts, default 2000).
        population: candidates per iteration (metaheuristics; the hybrid's global phase).
        stop_at_tolerance: metaheuristics stop as soon as the task is within tolerance (the papers run the
            whole budget; the local engine always stops there).
        initial: warm start ``(n,)`` or ``(k, n)`` (e.g. the previous solution along a trajectory).
        options: the solver's options (see ``metaik solvers``).
        progress: print a progress line now and then (metaheuristics).
        callback: ``callback(iteration, best_f, best_x)`` after every iteration (metaheuristics; phases of the
            hybrid); returning True stops. Recordings use it to trace every term.
    """
    start = time.perf_counter()
    method = ik_solver(DEFAULT_SOLVER if solver is None else solver, options)
    method.prepare(problem)  # its compiled code loaded before the time budget starts (a process's first solve)
    request = _request(problem, seed, tolerance, angle_tolerance, time_budget, max_iterations, population, initial,
                       stop_at_tolerance, callback, progress)
    return result_of(problem, method.solve(problem, request), method.name, request, start)


def make_request(
    problem: Problem,
    *,
    seed: int | np.random.Generator = DEFAULTS.seed,
    tolerance: float = DEFAULTS.tolerance,
    angle_tolerance: float | None = DEFAULTS.angle_tolerance,
    time_budget: float | None = DEFAULTS.time_budget,
    max_iterations: int | None = DEFAULTS.max_iterations,
    population: int = DEFAULTS.population,
    initial: np.ndarray | None = None,
    stop_at_tolerance: bool = DEFAULTS.stop_at_tolerance,
    callback: Callable[[int, float, np.ndarray], bool | None] | None = None,
    progress: bool = False,
) -> Request:
    """The validated :class:`~framework.solvers.Request` of :func:`solve`'s arguments (the time budget's
    deadline counts from now); bad values raise :class:`SolverError` naming them."""
    return _request(problem, seed, tolerance, angle_tolerance, time_budget, max_iterations, population, initial,
                    stop_at_tolerance, callback, progress)


def check_settings(*, seed: int | np.random.Generator = 0, tolerance: float = DEFAULTS.tolerance,
                   angle_tolerance: float | None = DEFAULTS.angle_tolerance,
                   time_budget: float | None = DEFAULTS.time_budget, max_iterations: int | None = DEFAULTS.max_iterations,
                   population: int = DEFAULTS.population, stop_at_tolerance: bool = DEFAULTS.stop_at_tolerance) -> None:
    """Check the settings a solve takes, as :func:`solve` checks them, before any problem exists (an entry point
    that solves many problems checks them once, where they enter); a bad one raises :class:`SolverError`. A
    generator given as the seed is not drawn from."""
    _request(None, 0 if isinstance(seed, np.random.Generator) else seed, tolerance, angle_tolerance, time_budget, max_iterations, population, None,
             stop_at_tolerance, None, False)


def _request(problem: Problem | None, seed, tolerance, angle_tolerance, time_budget, max_iterations, population, initial,
             stop_at_tolerance, callback, progress) -> Request:
    """:func:`make_request` with its arguments in order (a solve's Python is most of a pose solve's time: the
    common cases are tested first, each check once)."""
    deadline = None
    if time_budget is not None:
        if not _positive(time_budget):
            raise SolverError(f"time_budget must be a positive number of seconds; got {time_budget!r}")
        deadline = time.monotonic() + float(time_budget)
    if not _positive(tolerance):
        raise SolverError(f"tolerance must be a positive number; got {tolerance!r}")
    tolerance = float(tolerance)
    if angle_tolerance is None:
        angle_tolerance = tolerance
    elif _positive(angle_tolerance):
        angle_tolerance = float(angle_tolerance)
    else:
        raise SolverError(f"angle_tolerance must be a positive number [rad]; got {angle_tolerance!r}")
    if max_iterations is not None:
        max_iterations = positive_int(max_iterations, "max_iterations")
    population = positive_int(population, "population", maximum=MAX_POPULATION)
    if initial is not None:
        initial = problem.robot.check_population(initial, "initial configuration")
    if type(seed) is int and seed >= 0:  # the common case
        rng = _LazyGenerator(seed)
    elif isinstance(seed, np.random.Generator):
        rng, seed = _given(seed), seed_of(seed)
    else:
        seed = seed_of(seed)  # (raises for anything but an integer >= 0)
        rng = _LazyGenerator(seed)
    # (positionally: a named tuple's keywords cost 0.5 µs per solve)
    return Request(rng, seed, tolerance, angle_tolerance, max_iterations, population, initial, deadline,
                   stop_at_tolerance, callback, progress)


def _positive(value: Any) -> bool:
    if type(value) is float:  # the common case
        return 0.0 < value < math.inf
    return isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool) \
        and math.isfinite(value) and value > 0


def _given(generator: np.random.Generator) -> Callable[[], np.random.Generator]:
    return lambda: generator


class _LazyGenerator:
    """The generator of an integer seed, created on the first call (a seed costs ~9 µs: most solves need none)."""

    __slots__ = ("seed", "made")

    def __init__(self, seed: int) -> None:
        self.seed, self.made = seed, None

    def __call__(self) -> np.random.Generator:
        if self.made is None:
            self.made = np.random.default_rng(self.seed)
        return self.made


def result_of(problem: Problem, outcome, solver: str, request: Request, start: float) -> IKResult:
    """The :class:`IKResult` of a solver's :class:`~framework.solvers.Outcome` for ``request`` (success: every task
    block within its tolerance and, with collision terms, no contact by the exact check); ``start``: the
    ``time.perf_counter()`` its wall time counts from."""
    x, stop, iterations, evaluations, history, settings, state, errors, values, collisions = outcome
    x = float_copy(x)  # the result's own
    program = problem.program
    if values is None and errors is None:
        values, errors = program.values_and_errors(x)
    if values is None:
        values = program.values(x[None])[0]
    value_list = values.tolist()
    cost = 0.0
    for w, v in zip(program.weight_list, value_list):
        cost += w * v
    if errors is None:
        errors = program.task_errors(x)
    error_list = errors.tolist()
    # an interrupted solve is never a success, whatever its last point (the user stopped it before its end);
    # with collision terms the exact check has the last word, not their sphere rows
    if collisions is None and problem.checks_collisions:
        collisions = problem.collisions(x)
    success = stop != "interrupted" and program.within(
        error_list, request.tolerance, request.angle_tolerance, exact_checked=collisions is not None) \
        and (collisions is None or not collisions.colliding)
    return IKResult._of_solve(x, cost, success, stop, int(iterations), int(evaluations),
                              time.perf_counter() - start, solver, settings, state, collisions,
                              (program, value_list, error_list, history),
                              "" if success else failure_reason(program, error_list, request.tolerance,
                                                                request.angle_tolerance, collisions, stop, x))
