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

import numpy as np

from ..costs.program import Program
from ..compiled.native import compiled
from . import regularize as newton_phase
from .clock import monotonic_ns
from .local import LocalSettings, search_box
from .reach import REACHED, reach
from .settings import NewtonSettings, ReachSettings, Report
from .steps import copy

#: Items per compiled call at most (the unit of work a thread takes, and of progress reports).
CHUNK = 256


class BatchSettings(NamedTuple):
    """What every item of a batch is solved with (see :class:`~framework.engine.local.LocalSettings`)."""

    restarts: int  # random restarts allowed per item
    drawn: bool  # each item's first start drawn from its stream, as a restart draws one (its row of X is not read)
    chained: bool  # the items are consecutive waypoints of a path (see :func:`descend`)
    tol_linear: float
    tol_angular: float
    stall: int
    polish: int
    regularize: bool  # minimize the regularizers after reaching the task
    regularize_iterations: int
    smoothing: float
    task_rows: int


class Items(NamedTuple):
    """A batch's inputs per item: starts ``X (B, n)`` (on return each solved item's configuration), program
    parameters ``P (B, p)``, restart streams ``uint64 (B,)``, Levenberg-Marquardt iterations left ``int64 (B,)``,
    nanoseconds left ``int64 (B,)`` (``<= 0`` in the first entry: no budget)."""

    X: np.ndarray
    P: np.ndarray
    streams: np.ndarray
    max_iterations: np.ndarray
    budget_ns: np.ndarray


@compiled(nogil=True)
def descend(items, inputs, reference, box, packed, settings, state) -> int:
    """Solve the items ``items`` (``int64 (k,)`` indices) of a batch in place, one after the other.

    ``inputs``: :class:`Items`; ``packed``: the problem, its parameters this thread's own (each item's ``P`` row is
    written into them before its solve); ``settings``: :class:`BatchSettings`; ``state``: :class:`BatchState`, the
    outputs. Chained, the items are consecutive waypoints of a path: item ``items[t]`` starts at the answer of
    ``items[t - 1]`` (the first at its own row of ``X``), the parameters ``reference`` holds are written from that
    start (``params[reference[0]] = x[reference[1]]``: the motion terms' reference, the previous solution), and
    the loop stops at the first item that misses the task.

    Returns the number of items solved: all of them, or (chained) the position of the first that missed the task.
    """
    params = packed.params
    stats = np.empty(3, dtype=np.int64)
    multipliers = np.zeros(settings.task_rows)
    slots, coordinates = reference
    for t in range(items.shape[0]):
        i = items[t]
        copy(params, inputs.P[i])
        begin = monotonic_ns()
        deadline = begin + inputs.budget_ns[i] if inputs.budget_ns[i] > 0 else 0
        x = inputs.X[i]
        if settings.chained:
            if t > 0:
                copy(x, inputs.X[items[t - 1]])
            for j in range(slots.shape[0]):
                params[slots[j]] = x[coordinates[j]]
        report = Report(state.E[i], state.V[i], stats)
        code = reach(x, settings.drawn, inputs.streams[i : i + 1], box, packed,
                     ReachSettings(settings.tol_linear, settings.tol_angular, inputs.max_iterations[i], settings.stall,
                                   settings.polish, settings.restarts, deadline), report)
        for k in range(3):
            state.counts[i, k] += stats[k]
        state.regularized[i] = -1
        if code == REACHED and settings.regularize:
            multipliers[:] = 0.0
            state.regularized[i] = newton_phase.regularize(
                x, box, packed, NewtonSettings(settings.smoothing, settings.regularize_iterations, deadline),
                multipliers, report)
            state.counts[i, 1] += stats[1]
        state.codes[i] = code
        state.spent_ns[i] += monotonic_ns() - begin
        if settings.chained and code != REACHED:
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
                  streams: np.ndarray, *, time_budget: float | None = None, drawn: bool = False) -> None:
    """Run :func:`descend` over ``items`` in this thread, with its own copy of the program's parameters.

    ``streams`` ``uint64 (B,)``: each item's restart stream (used when ``settings.restarts``, and by a ``drawn``
    start); ``time_budget``: seconds per item, counted from its first descent. Threads may run it at once on
    disjoint items.
    """
    items = np.ascontiguousarray(items, dtype=np.int64)
    if time_budget is None:
        budget = np.zeros(state.X.shape[0], dtype=np.int64)
    else:
        budget = np.maximum(int(time_budget * 1e9) - state.spent_ns, 1).astype(np.int64)
    _descend(program, P, state, items, settings, streams, budget, None, drawn)


def follow_items(program: Program, P: np.ndarray, state: BatchState, items: np.ndarray, settings: LocalSettings,
                 streams: np.ndarray, follows: tuple[np.ndarray, np.ndarray]) -> int:
    """Run :func:`descend` chained over ``items``, consecutive waypoints of a path (the first starts at its row of
    ``state.X``), the parameters ``follows`` (slots, coordinates: :meth:`~framework.costs.program._Layout.
    references_of` the motion terms) written from each waypoint's start; returns how many were solved before the
    first that missed the task (all: ``len(items)``)."""
    items = np.ascontiguousarray(items, dtype=np.int64)
    return _descend(program, P, state, items, settings, streams, np.zeros(state.X.shape[0], dtype=np.int64), follows,
                    False)


_NONE = (np.zeros(0, np.int64), np.zeros(0, np.int64))


def _descend(program: Program, P: np.ndarray, state: BatchState, items: np.ndarray, settings: LocalSettings,
             streams: np.ndarray, budget: np.ndarray, follows: tuple[np.ndarray, np.ndarray] | None,
             drawn: bool) -> int:
    left = np.maximum(settings.max_iterations - state.counts[:, 0], 0).astype(np.int64)
    packed = program.packed._replace(params=program.packed.params.copy())  # the items' targets are written there
    batch = BatchSettings(settings.max_restarts, drawn, follows is not None, settings.tolerance, settings.angular,
                          settings.stall, settings.polish, bool(settings.regularize and program.has_regularizers),
                          settings.regularize_iterations, settings.smoothing, program.task_rows)
    return descend(items, Items(state.X, P, streams, left, budget), _NONE if follows is None else follows,
                   search_box(program), packed, batch, state)


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
