"""``solve_batch(problem, targets)``: one problem, a batch of targets, each item as ``solve`` would solve it.

Item ``i`` is the problem with its targets moved to ``targets[i]``, solved with seed ``seed + i``: the result
is the one :func:`framework.solve` returns for it (the same configuration, bit for bit, when no time budget
binds). The speed comes from where the work runs. A solver whose solve begins with the local engine alone
(its :meth:`~framework.solvers.ik.IKSolver.batch_plan`: ``hybrid``, ``multistart_lm``) has that beginning run
for every item in one compiled loop (:mod:`framework.engine.batch`) on every core: the first descent, then for
the items that stall, the same random restarts ``solve`` draws from the same seed. The few items still
unsolved (and every item of other solvers) go through ``solve`` itself.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..costs.base import Term
from ..engine.batch import BatchState, descend_items, in_chunks
from ..engine.reach import DEADLINE, REACHED
from ..errors import SolverError, TaskError
from ..costs.problem import Problem
from .settings import DEFAULTS
from .solve import DEFAULT_SOLVER, make_request, solve
from .registry import ik_solver
from .ik import BatchPlan


@dataclass(frozen=True)
class BatchResult:
    """What :func:`solve_batch` produced, one row per item.

    Attributes:
        configurations: ``(B, n)`` joint coordinates [rad / m].
        success: ``(B,)`` every task block of the item within its tolerance (and, with collision terms, no contact
            on the exact geometry).
        errors: ``(B, blocks)`` each task block's error [m or rad], named by ``error_names``.
        costs: ``(B,)`` the weighted objective at each configuration.
        iterations: ``(B,)`` solver iterations.
        compiled: ``(B,)`` solved in the compiled batch loop (``False``: by ``solve``, one at a time).
        wall_time: seconds for the whole batch; solver: the solver's name.
    """

    configurations: np.ndarray
    success: np.ndarray
    errors: np.ndarray
    error_names: tuple[str, ...]
    costs: np.ndarray
    iterations: np.ndarray
    compiled: np.ndarray
    wall_time: float
    solver: str

    def __len__(self) -> int:
        return int(self.success.shape[0])

    @property
    def success_rate(self) -> float:
        """Fraction of items solved within tolerance."""
        return float(np.mean(self.success)) if len(self) else 0.0

    @property
    def throughput(self) -> float:
        """Items per second of wall time."""
        return len(self) / self.wall_time if self.wall_time > 0 else float("inf")


def solve_batch(
    problem: Problem,
    targets: Sequence | np.ndarray | Mapping[str, Sequence | np.ndarray],
    solver: str | None = None,
    *,
    seed: int | Sequence[int] = DEFAULTS.seed,
    tolerance: float = DEFAULTS.tolerance,
    angle_tolerance: float | None = DEFAULTS.angle_tolerance,
    time_budget: float | None = DEFAULTS.time_budget,
    max_iterations: int | None = DEFAULTS.max_iterations,
    population: int = DEFAULTS.population,
    stop_at_tolerance: bool = DEFAULTS.stop_at_tolerance,
    initial: np.ndarray | None = None,
    options: Mapping[str, Any] | None = None,
    workers: int | None = None,
    progress: bool | None = None,
    scheduler: str | None = None,
) -> BatchResult:
    """Solve ``problem`` for every target of a batch.

    Args:
        problem: the problem; its targeted terms are left as they were.
        targets: one target per item for the problem's one task term with a target — ``(B, 3)`` points for a
            :class:`~framework.costs.Position`, ``(B, 4, 4)`` matrices or ``B`` ``pinocchio.SE3`` for a
            :class:`~framework.costs.Pose`, anything its ``set_target`` takes — or ``{term name: targets}``.
        solver: as :func:`framework.solve` (default ``"hybrid"``).
        seed: item ``i`` is solved with ``seed + i``, or with ``seed[i]`` for a sequence of ``B`` seeds.
        tolerance, angle_tolerance, max_iterations, population, stop_at_tolerance, options: as
            :func:`framework.solve`, per item.
        time_budget: seconds per item.
        initial: ``(B, n)`` a warm start per item (default: the problem's own start, as ``solve``).
        workers: threads of the compiled loop (default: every core); with ``scheduler``: a local cluster's
            worker processes.
        progress: a progress bar (default: when stderr is a terminal).
        scheduler: split the batch over a Dask cluster (``"tcp://HOST:PORT"`` or ``"local"``, see
            :mod:`framework.solvers.cluster`); the result is the same.
    """
    started = time.perf_counter()
    P, B = item_parameters(problem, targets)
    seeds = _seeds(seed, B)
    if initial is not None:
        initial = problem.robot.check_population(initial, "initial configurations")
        if initial.shape[0] != B:
            raise SolverError(f"initial holds {initial.shape[0]} configurations for {B} targets")
    kwargs = dict(tolerance=tolerance, angle_tolerance=angle_tolerance, time_budget=time_budget,
                  max_iterations=max_iterations, population=population, stop_at_tolerance=stop_at_tolerance)
    if scheduler is not None:
        return _on_cluster(problem, targets, solver, seeds, initial, options, kwargs, scheduler, workers, started,
                           progress)
    template = make_request(problem, initial=None if initial is None else initial[:1], **kwargs)
    method = ik_solver(DEFAULT_SOLVER if solver is None else solver, options)
    program = problem.program
    plan = method.batch_plan(problem, template) if B else None
    n = problem.robot.n
    state = BatchState.start(program, np.tile(plan.x0 if plan else np.zeros(n), (B, 1)) if initial is None
                             else initial)
    clear = np.zeros(B, dtype=bool)  # items the exact check found clear on the way (not checked again below)
    with _Bar(progress, B, f"batch IK ({method.name})") as bar:
        if plan is not None and plan.clear_first:
            done = _clear_first(problem, targets, state, plan, seeds, time_budget, workers, bar)
            clear = done.copy()
        elif plan is not None and program.task_rows:
            done = _engine(problem, P, state, plan, seeds, time_budget, workers, bar)
        else:
            done = np.zeros(B, dtype=bool)
        bar.compiled_done(int(done.sum()))
        costs = state.V @ program.weights
        iterations = state.counts[:, 0].copy()
        rest = np.flatnonzero(~done)
        if rest.size:
            clear[rest] = _solve_each(problem, targets, rest, seeds, initial, state, costs, iterations, method.name,
                                      options, kwargs, bar)
    angular = np.array(program.task_angular, dtype=bool)
    limits = np.where(angular, template.angle_tolerance, template.tolerance)
    if problem.checks_collisions:  # as solve does: the exact check has the last word, not the sphere rows
        limits[np.array(program.task_checked_exactly, dtype=bool)] = np.inf
    success = np.all(state.E <= limits, axis=1) if B else np.zeros(0, dtype=bool)
    if problem.checks_collisions:  # no contact on the exact geometry
        for i in np.flatnonzero(success & ~clear):
            success[i] = not problem.collisions(state.X[i]).colliding
    return BatchResult(state.X, success, state.E, program.task_blocks, costs, iterations, done,
                       time.perf_counter() - started, method.name)


def _engine(problem: Problem, P: np.ndarray, state: BatchState, plan: BatchPlan, seeds: np.ndarray,
            time_budget: float | None, workers: int | None, bar: _Bar) -> np.ndarray:
    """Run the plan's engine phase over every item, as :func:`~framework.engine.solve_local` runs it for one (the
    first descent and, when the plan restarts, the random restarts from the item's seeded stream), on every core.
    Returns ``(B,)`` which items are finished (the others need the solver itself)."""
    program = problem.program
    program.refresh()
    streams = np.array(seeds, dtype=np.uint64)  # one restart stream per item, as ``solve`` makes from the seed

    def chunk(items: np.ndarray) -> None:
        descend_items(program, P, state, items, plan.first, streams, time_budget=time_budget)

    in_chunks(chunk, len(seeds), workers=workers, progress=bar.advance_compiled)
    missed = np.flatnonzero((state.codes != REACHED) & (state.codes != DEADLINE))
    if plan.then is not None and missed.size:  # a drawn start, the item's stream going on; its own iterations
        spent = state.counts[missed].copy()
        state.counts[missed] = 0

        def drawn(part: np.ndarray) -> None:
            descend_items(program, P, state, missed[part], plan.then, streams, time_budget=time_budget, drawn=True)

        in_chunks(drawn, missed.size, workers=workers)
        state.counts[missed] += spent
    return (state.codes == REACHED) | (state.codes == DEADLINE) | (not plan.escalates)


def _clear_first(problem: Problem, targets, state: BatchState, plan: BatchPlan, seeds: np.ndarray,
                 time_budget: float | None, workers: int | None, bar: _Bar) -> np.ndarray:
    """The plan's engine phase on the problem without its collision terms (the same terms: their targets move
    on both), an item finished when coal finds its answer clear by the terms' margins — as the solver's first
    step takes it, with the whole problem's errors and values there. Returns ``(B,)`` which items are finished."""
    free = problem.without_collision_terms
    P, _ = item_parameters(free, targets)
    first = BatchState.start(free.program, state.X)
    _engine(free, P, first, plan, seeds, time_budget, workers, bar)
    done = np.zeros(len(seeds), dtype=bool)
    for i in np.flatnonzero(first.codes == REACHED):
        done[i] = not problem.collisions(first.X[i], margins=True).colliding
    if done.any():  # the collision blocks' errors and terms' values at x (no target); the others as the engine's
        X = state.X[done] = first.X[done]
        state.E[done] = _by_name(problem.program.task_errors(X), problem.program.task_blocks, first.E[done],
                                 free.program.task_blocks)
        state.V[done] = _by_name(problem.values(X), problem.names, first.V[done], free.names)
        state.counts[done], state.codes[done] = first.counts[done], REACHED
    return done


def _by_name(whole: np.ndarray, names, part: np.ndarray, part_names) -> np.ndarray:
    """``whole`` ``(k, len(names))`` with the columns ``part`` ``(k, len(part_names))`` names in their place."""
    at = {name: c for c, name in enumerate(names)}
    for c, name in enumerate(part_names):
        whole[:, at[name]] = part[:, c]
    return whole


def _on_cluster(problem: Problem, targets, solver, seeds: np.ndarray, initial, options, kwargs: dict,
                scheduler: str, workers: int | None, started: float, progress: bool | None) -> BatchResult:
    """:func:`solve_batch` with the items split into chunks over a Dask cluster's workers (the progress bar
    advances as chunks come back)."""
    from .cluster import cluster_client, completed

    columns = {name: column for name, (_, column) in _targeted(problem, targets).items()}
    B = len(seeds)
    parts = {}
    with cluster_client(scheduler, workers) as client, _Bar(progress, B, "batch IK on the cluster") as bar:
        count = max(1, len(client.scheduler_info()["workers"]))
        size = max(1, -(-B // (4 * count)))
        chunks = [np.arange(a, min(a + size, B)) for a in range(0, B, size)]
        for k, part in completed(client, _cluster_chunk, chunks, problem, columns, solver, seeds, initial, options,
                                 kwargs):
            parts[k] = part
            bar.advance(len(chunks[k]))
    merged = [np.concatenate([getattr(parts[k], field) for k in range(len(chunks))])
              for field in ("configurations", "success", "errors", "costs", "iterations", "compiled")]
    first = parts[0] if parts else None
    return BatchResult(merged[0], merged[1], merged[2], first.error_names if first else problem.program.task_blocks,
                       merged[3], merged[4], merged[5], time.perf_counter() - started,
                       first.solver if first else str(solver))


def _cluster_chunk(items: np.ndarray, problem: Problem, columns: dict, solver, seeds: np.ndarray, initial,
                   options, kwargs: dict) -> BatchResult:
    """The items ``items`` of a batch, solved on a cluster worker (one thread)."""
    part = {name: column[items] if isinstance(column, np.ndarray) else [column[i] for i in items]
            for name, column in columns.items()}
    return solve_batch(problem, part, solver, seed=seeds[items], initial=None if initial is None else initial[items],
                       options=options, workers=1, progress=False, **kwargs)


def _solve_each(problem: Problem, targets, items: np.ndarray, seeds: np.ndarray, initial, state: BatchState,
                costs: np.ndarray, iterations: np.ndarray, solver: str, options, kwargs: dict, bar: _Bar
                ) -> np.ndarray:
    """Solve ``items`` one at a time with :func:`solve`, on a copy of the problem whose targeted terms are its own
    (the user's problem and terms are left as they are); returns ``(len(items),)`` whether each answer was found
    clear by the exact check (with collision terms: the solve's success checked it)."""
    moved = _targeted(problem, targets)
    own = problem.with_own_terms(moved)
    terms = dict(zip(own.names, own.program.terms))
    clear = np.zeros(len(items), dtype=bool)
    for k, i in enumerate(items):
        for name, (_, column) in moved.items():
            terms[name].set_target(column[i])
        result = solve(own, solver, seed=int(seeds[i]), options=options,
                       initial=None if initial is None else initial[i], **kwargs)
        state.X[i] = result.configuration
        state.E[i] = [result.errors[name] for name in own.program.task_blocks]
        costs[i], iterations[i] = result.cost, result.iterations
        clear[k] = result.collisions is not None and not result.collisions.colliding
        bar.advance(1)
    return clear


def _targeted(problem: Problem, targets) -> dict[str, tuple[Term, Sequence]]:
    """``{term name: (term, its targets)}`` for the terms ``targets`` moves."""
    terms = dict(zip(problem.names, problem.program.terms))
    if isinstance(targets, Mapping):
        unknown = sorted(set(targets) - set(terms))
        if unknown:
            raise TaskError(f"targets name terms the problem does not have: {unknown}; its terms are "
                            f"{list(terms)}")
        return {name: (terms[name], column) for name, column in targets.items()}
    movable = [name for name, term in terms.items() if term.is_task and term.has_target]
    if len(movable) != 1:
        raise TaskError(f"the problem has {len(movable)} task terms with a target ({movable}); give targets as "
                        "{term name: targets}")
    return {movable[0]: (terms[movable[0]], targets)}


def item_parameters(problem: Problem, targets) -> tuple[np.ndarray, int]:
    """``(B, p)`` the program's parameters of every item (``targets`` as :func:`solve_batch` takes them: the
    other terms' parameters as they stand), and ``B``."""
    program = problem.program
    program.refresh()
    columns = {}
    for name, (term, column) in _targeted(problem, targets).items():
        columns[name] = term.target_parameters(problem.robot, column)
    sizes = {len(c) for c in columns.values()}
    if len(sizes) != 1:
        raise TaskError(f"every term needs one target per item; got {dict((k, len(v)) for k, v in columns.items())}")
    B = sizes.pop()
    P = np.tile(program.packed.params, (B, 1))
    for k, name in enumerate(problem.names):
        if name in columns:
            start, stop = program.layout.param_spans[k]
            P[:, start:stop] = columns[name]
    return P, B


def _seeds(seed: int | Sequence[int], B: int) -> np.ndarray:
    """Item seeds: ``seed + i``, or the ``B`` given ones."""
    if isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
        if seed < 0:
            raise SolverError(f"seed must be an integer >= 0; got {seed!r}")
        return int(seed) + np.arange(B, dtype=np.int64)
    seeds = np.asarray(seed)
    if seeds.shape != (B,) or seeds.dtype.kind not in "iu" or (seeds < 0).any():
        raise SolverError(f"seed must be an integer >= 0 or {B} of them (one per item); got {seed!r}")
    return seeds.astype(np.int64)


class _Bar:
    """A rich progress bar over a batch's items, or nothing (not a terminal, or ``enabled=False``)."""

    def __init__(self, enabled: bool | None, total: int, description: str):
        self.enabled, self.total, self.description = enabled, total, description
        self._bar = None

    def __enter__(self) -> _Bar:  # noqa: PYI034
        from rich.console import Console

        console = Console(stderr=True)
        if (console.is_terminal if self.enabled is None else self.enabled) and self.total:
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

            self._bar = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                                 TimeRemainingColumn(), console=console, transient=True)
            self._bar.__enter__()
            self._task = self._bar.add_task(self.description, total=self.total)
        return self

    def advance_compiled(self, done: int) -> None:
        """Items through the first compiled pass (shown as done; the few it leaves are taken back later)."""
        self.advance(done)

    def compiled_done(self, finished: int) -> None:
        """The compiled passes finished ``finished`` items: the bar shows those."""
        if self._bar is not None:
            self._bar.update(self._task, completed=finished)

    def advance(self, count: int) -> None:
        if self._bar is not None:
            self._bar.update(self._task, advance=count)

    def __exit__(self, *exc) -> None:
        if self._bar is not None:
            self._bar.__exit__(*exc)
