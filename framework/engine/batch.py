"""The local engine over a batch of items: one packed problem, one parameter row per item, one compiled loop.

:func:`descend` runs, for each item in turn, exactly what :func:`~framework.engine.local.solve_local` runs
for one problem: the item's parameters (its targets) are written into the program, :func:`~.reach.reach`
drives the task from the item's start (restarting from draws of the item's stream, if restarts are on) and, when the task
is reached, :func:`~.newton.regularize` minimizes the regularizers on it. The loop releases the GIL, so
threads run chunks of a batch on all cores, each with its own copy of the program's parameters.
*Chained*, the items are the waypoints of a path: each starts at the previous one's answer, which is also the
reference its regularizers measure motion from (a tracking step, :mod:`framework.tracking`).

:func:`descend_items` is its Python side (:func:`follow_items` for a chain); :func:`in_chunks` runs work over chunks
of a batch on threads.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import NamedTuple

import numba
import numpy as np

from ..costs.kernels import NO
from ..costs.program import Program
from . import newton
from .clock import monotonic_ns
from .local import LocalSettings, search_box
from .reach import REACHED, reach

#: Items per compiled call at most (the unit of work a thread takes, and of progress reports).
CHUNK = 256


@numba.njit(cache=True, nogil=True)
def descend(items, X, restarts, streams, P, chained, reference, lower, upper, box_wrap, kin, prog, tol_linear,
            tol_angular, max_iterations, stall, budget_ns, polish, regularize, regularize_iterations, smoothing,
            task_rows, E, V, codes, regularized, counts, spent_ns) -> int:
    """Solve the items ``items`` of a batch in place, one after the other.

    Args:
        items: ``int64 (k,)`` item indices.
        X: ``(B, n)`` starts; on return each solved item's configuration.
        chained: the items are consecutive waypoints of a path: item ``items[t]`` starts at the answer of
            ``items[t - 1]`` (the first at its own row of ``X``), the parameters ``reference`` holds are written from
            that start (``params[reference[0]] = x[reference[1]]``: the motion terms' reference, the previous
            solution), and the loop stops at the first item that misses the task.
        restarts: random restarts allowed per item; streams: ``uint64 (B,)`` each item's restart stream
            (:mod:`~framework.engine.draws`), advanced.
        P: ``(B, p)`` each item's program parameters (written into ``prog[2]`` before its solve).
        max_iterations: ``int64 (B,)`` Levenberg-Marquardt iterations left per item.
        budget_ns: ``int64 (B,)`` nanoseconds left per item (``<= 0`` in the first entry: no budget).
        regularize: minimize the regularizers after reaching the task; task_rows: the task's residual rows.
        E: ``(B, blocks)`` out: task block errors; V: ``(B, terms)`` out: term values.
        codes: ``int64 (B,)`` out: :func:`reach`'s status; regularized: ``int64 (B,)`` out:
            :func:`~.newton.regularize`'s status (``-1``: not run); counts: ``int64 (B, 3)`` iterations, evaluations
            and restarts, added to; spent_ns: ``int64 (B,)`` time spent, added to.

    Returns:
        The number of items solved: all of them, or (chained) the position of the first that missed the task.
    """
    params = prog[2]
    stats = np.empty(3, dtype=np.int64)
    multipliers = np.zeros(task_rows)
    slots, coordinates = reference
    for t in range(items.shape[0]):
        i = items[t]
        params[:] = P[i]
        begin = monotonic_ns()
        deadline = begin + budget_ns[i] if budget_ns[i] > 0 else 0
        x = X[i]
        if chained:
            if t > 0:
                x[:] = X[items[t - 1]]
            for j in range(slots.shape[0]):
                params[slots[j]] = x[coordinates[j]]
        code = reach(x, NO, restarts, streams[i : i + 1], lower, upper, box_wrap, kin, prog, tol_linear, tol_angular,
                     max_iterations[i], stall, deadline, polish, E[i], V[i], stats)
        counts[i, 0] += stats[0]
        counts[i, 1] += stats[1]
        counts[i, 2] += stats[2]
        regularized[i] = -1
        if code == REACHED and regularize:
            multipliers[:] = 0.0
            regularized[i] = newton.regularize(x, lower, upper, box_wrap, kin, prog, smoothing,
                                               regularize_iterations, deadline, multipliers, E[i], V[i], stats)
            counts[i, 1] += stats[1]
        codes[i] = code
        spent_ns[i] += monotonic_ns() - begin
        if chained and code != REACHED:
            return t
    return items.shape[0]


class BatchState(NamedTuple):
    """The arrays :func:`descend` fills: configurations, errors, values, status of both phases, counts and time
    per item."""

    X: np.ndarray
    E: np.ndarray
    V: np.ndarray
    codes: np.ndarray
    regularized: np.ndarray
    counts: np.ndarray
    spent_ns: np.ndarray

    @classmethod
    def start(cls, program: Program, X0: np.ndarray) -> BatchState:
        B = X0.shape[0]
        return cls(np.array(X0, dtype=float, order="C"), np.zeros((B, program.task_block_rows.size)),
                   np.zeros((B, len(program.terms))), np.full(B, -1, dtype=np.int64), np.full(B, -1, np.int64),
                   np.zeros((B, 3), np.int64), np.zeros(B, dtype=np.int64))


def descend_items(program: Program, P: np.ndarray, state: BatchState, items: np.ndarray, settings: LocalSettings,
                  streams: np.ndarray, *, time_budget: float | None = None) -> None:
    """Run :func:`descend` over ``items`` in this thread, with its own copy of the program's parameters.

    ``streams`` ``uint64 (B,)``: each item's restart stream (used when ``settings.restarts``); ``time_budget``:
    seconds per item, counted from its first descent. Threads may run it at once on disjoint items.
    """
    items = np.ascontiguousarray(items, dtype=np.int64)
    if time_budget is None:
        budget = np.zeros(state.X.shape[0], dtype=np.int64)
    else:
        budget = np.maximum(int(time_budget * 1e9) - state.spent_ns, 1).astype(np.int64)
    _descend(program, P, state, items, settings, streams, budget, None)


def follow_items(program: Program, P: np.ndarray, state: BatchState, items: np.ndarray, settings: LocalSettings,
                 streams: np.ndarray, follows: tuple[np.ndarray, np.ndarray]) -> int:
    """Run :func:`descend` chained over ``items``, consecutive waypoints of a path (the first starts at its row of
    ``state.X``), the parameters ``follows`` (slots, coordinates: :meth:`~framework.costs.program._Layout.
    references_of` the motion terms) written from each waypoint's start; returns how many were solved before the
    first that missed the task (all: ``len(items)``)."""
    items = np.ascontiguousarray(items, dtype=np.int64)
    return _descend(program, P, state, items, settings, streams, np.zeros(state.X.shape[0], dtype=np.int64), follows)


_NONE = (np.zeros(0, np.int64), np.zeros(0, np.int64))


def _descend(program: Program, P: np.ndarray, state: BatchState, items: np.ndarray, settings: LocalSettings,
             streams: np.ndarray, budget: np.ndarray, follows: tuple[np.ndarray, np.ndarray] | None) -> int:
    lower, upper, box_wrap = search_box(program)
    left = np.maximum(settings.max_iterations - state.counts[:, 0], 0).astype(np.int64)
    prog = list(program.prog)
    prog[2] = prog[2].copy()  # the items' targets are written into these parameters
    return descend(items, state.X, settings.max_restarts, streams, P, follows is not None, _NONE if follows is None else follows,
                   lower, upper, box_wrap, program.kin, tuple(prog), settings.tolerance, settings.angular, left,
                   settings.stall, budget, settings.polish, bool(settings.regularize and program.has_regularizers),
                   settings.regularize_iterations, settings.smoothing, program.task_rows, state.E, state.V,
                   state.codes, state.regularized, state.counts, state.spent_ns)


def in_chunks(work: Callable[[np.ndarray], None], count: int, *, workers: int | None = None,
              progress: Callable[[int], None] | None = None) -> None:
    """Call ``work(items)`` over chunks of ``range(count)`` (at most :data:`CHUNK` items, at least one chunk per
    thread) on ``workers`` threads (default: every core); ``progress(done)`` after each chunk, in this thread."""
    workers = max(1, workers or os.cpu_count() or 1)
    size = max(1, min(CHUNK, -(-count // workers)))  # small batches still spread over every thread
    chunks = [np.arange(a, min(a + size, count), dtype=np.int64) for a in range(0, count, size)]

    def run(items: np.ndarray) -> int:
        work(items)
        return len(items)

    workers = min(workers, len(chunks))
    if workers <= 1:
        for chunk in chunks:
            done = run(chunk)
            if progress:
                progress(done)
        return
    with ThreadPoolExecutor(workers) as pool:
        for done in pool.map(run, chunks):
            if progress:
                progress(done)
