"""Running a grid: serially, on worker processes (which die with the bench) or on a Dask cluster; each finished
run appended to the locked results file at once; Ctrl-C finishes the runs in flight (:func:`run_grid`)."""


from __future__ import annotations

import math
import multiprocessing as mp
import os
import signal
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from queue import Empty
from typing import Any

from ..interrupts import graceful_interrupt
from ..costs.problem import Problem
from .grid import BenchTask, Grid, RunSpec, expand_task
from .record import execute
from .store import drop_torn_tail, exclusive, read_results


# ---------------------------------------------------------------------------------------------- running
@dataclass(frozen=True)
class RunReport:
    """What :func:`run_grid` did: runs in the grid, already in the file, completed now; and whether it stopped early."""

    planned: int
    skipped: int
    completed: int
    interrupted: bool
    wall_time: float
    results: Path


def run_grid(
    grid: Grid | Sequence[RunSpec],
    results: str | Path,
    *,
    jobs: int | None = None,
    max_runs: int | None = None,
    chunk_size: int | None = None,
    progress: bool = True,
    console=None,
    stop: Callable[[], bool] | None = None,
    scheduler: str | None = None,
) -> RunReport:
    """Run every run of ``grid`` not yet in ``results``, appending each record as soon as it is done.

    Args:
        grid: a :class:`Grid` or its run specs.
        results: the JSON-lines results file (created; resumed if it exists).
        jobs: worker processes (default: all cores); 1 runs in this process.
        max_runs: stop after this many new runs (e.g. a time-boxed partial grid; re-run to continue).
        chunk_size: runs per worker task (default: a few per worker and at most 16).
        progress: show a progress bar (rich) on ``console``.
        stop: polled between runs; returning True stops like Ctrl-C (the runs in flight are finished and kept).
        scheduler: run on a Dask cluster instead (``"tcp://HOST:PORT"``, or ``"local"``: ``jobs`` worker
            processes); this process still writes every record, as each chunk of runs comes back.

    Ctrl-C finishes the runs in flight, writes them and returns with ``interrupted=True``; a second Ctrl-C aborts.
    """
    specs = list(grid.specs if isinstance(grid, Grid) else grid)
    results = Path(results)
    results.parent.mkdir(parents=True, exist_ok=True)
    with exclusive(results):
        return _run_locked(specs, results, jobs, max_runs, chunk_size, progress, console, stop, scheduler)


def _run_locked(specs, results: Path, jobs, max_runs, chunk_size, progress, console, stop, scheduler) -> RunReport:
    drop_torn_tail(results)
    done = {r.key for r in read_results(results)}
    pending = [s for s in specs if s.key not in done]
    skipped = len(specs) - len(pending)
    if max_runs is not None:
        pending = pending[: max(0, int(max_runs))]
    jobs = max(1, int(jobs or os.cpu_count() or 1))
    start = time.perf_counter()
    with (
        results.open("a") as out,
        _progress(progress, console, len(pending)) as advance,
        graceful_interrupt() as interrupt,
    ):

        def write(line: str) -> None:
            out.write(line + "\n")
            out.flush()
            advance()

        def should_stop() -> bool:
            return interrupt.requested or bool(stop and stop())

        if scheduler is not None:
            completed = _run_cluster(pending, write, should_stop, scheduler, jobs, chunk_size)
        elif jobs == 1 or len(pending) <= 1:
            completed = _run_serial(pending, write, should_stop)
        else:
            completed = _run_parallel(pending, write, should_stop, jobs, chunk_size)
    interrupted = completed < len(pending)
    return RunReport(len(specs), skipped, completed, interrupted, time.perf_counter() - start, results)


@contextmanager
def _progress(enabled: bool, console, total: int) -> Iterator[Callable[[], None]]:
    if not enabled or total == 0:
        yield lambda: None
        return
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    columns = (
        TextColumn("bench"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        TextColumn("eta"),
        TimeRemainingColumn(),
    )
    with Progress(*columns, console=console) as bar:
        task = bar.add_task("runs", total=total)
        yield lambda: bar.advance(task)


class _TaskCache:
    """Expanded task files by path, loaded once per process."""

    def __init__(self) -> None:
        self._tasks: dict[str, BenchTask] = {}

    def problem(self, spec: RunSpec) -> Problem:
        if spec.path not in self._tasks:
            self._tasks[spec.path] = expand_task(spec.path)
        return self._tasks[spec.path].case(spec.system, spec.case).problem


def _run_serial(
    pending: Sequence[RunSpec], write: Callable[[str], None], should_stop: Callable[[], bool]
) -> int:
    cache = _TaskCache()
    completed = 0
    for spec in pending:
        if should_stop():
            break
        record = execute(spec, cache.problem(spec))
        if should_stop() and record.stop_reason == "interrupted":
            break  # a solve cut short by Ctrl-C is not a finished run
        write(record.to_json())
        completed += 1
    return completed


# Worker-process state, set by _init_worker.
_WORKER: dict[str, Any] = {}


def _init_worker(queue, stop_event, parent: int) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent decides when to stop
    _die_with_parent(parent)
    _WORKER.update(queue=queue, stop=stop_event, cache=_TaskCache())


def _die_with_parent(parent: int) -> None:
    """Have the kernel end this worker when the bench process dies (Linux ``PR_SET_PDEATHSIG``), so a killed
    bench leaves no worker running (nor holding its stdout); elsewhere the pool's own shutdown is relied on."""
    if not sys.platform.startswith("linux"):
        return
    import ctypes

    try:
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # 1 = PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        return
    if os.getppid() != parent:  # the parent died before the request: nobody is left to collect the runs
        os._exit(1)


def _run_chunk(chunk: Sequence[RunSpec]) -> int:
    """Run a chunk in a worker; each record is sent to the parent as soon as it is done. Returns how many."""
    sent = 0
    for spec in chunk:
        if _WORKER["stop"].is_set():
            break
        record = execute(spec, _WORKER["cache"].problem(spec))
        _WORKER["queue"].put(record.to_json())
        sent += 1
    return sent


def _chunks(pending: Sequence[RunSpec], jobs: int, size: int | None) -> list[list[RunSpec]]:
    size = size or max(1, min(16, math.ceil(len(pending) / (8 * jobs))))
    return [list(pending[i : i + size]) for i in range(0, len(pending), size)]


def _run_parallel(
    pending: Sequence[RunSpec],
    write: Callable[[str], None],
    should_stop: Callable[[], bool],
    jobs: int,
    chunk_size: int | None,
) -> int:
    ctx = mp.get_context("spawn")  # fresh interpreters: no forked numba/BLAS threads
    queue, stop_event = ctx.Queue(), ctx.Event()
    received = 0
    sent = 0
    failure: BaseException | None = None
    with ProcessPoolExecutor(
        jobs, mp_context=ctx, initializer=_init_worker, initargs=(queue, stop_event, os.getpid())
    ) as pool:
        futures: set[Future] = {pool.submit(_run_chunk, c) for c in _chunks(pending, jobs, chunk_size)}
        while futures or received < sent:
            if not stop_event.is_set() and (should_stop() or failure is not None):
                stop_event.set()
                for f in futures:
                    f.cancel()
            try:
                write(queue.get(timeout=0.1))
                received += 1
                continue
            except Empty:
                pass
            finished, futures = wait(futures, timeout=0, return_when=FIRST_COMPLETED)
            for f in finished:
                if f.cancelled():
                    continue
                if f.exception() is not None:
                    failure = failure or f.exception()
                else:
                    sent += f.result()
    if failure is not None:
        raise failure
    return received


_CLUSTER_TASKS: dict[str, _TaskCache] = {}  # one task cache per cluster worker process


def _cluster_chunk(chunk: Sequence[RunSpec]) -> list[str]:
    """Run a chunk on a cluster worker; the records as JSON lines."""
    cache = _CLUSTER_TASKS.setdefault("tasks", _TaskCache())
    return [execute(spec, cache.problem(spec)).to_json() for spec in chunk]


def _run_cluster(
    pending: Sequence[RunSpec],
    write: Callable[[str], None],
    should_stop: Callable[[], bool],
    scheduler: str,
    jobs: int,
    chunk_size: int | None,
) -> int:
    from ..solvers.cluster import cluster_client, completed

    received = 0
    with cluster_client(scheduler, jobs) as client:
        workers = max(1, len(client.scheduler_info()["workers"]))
        for _, lines in completed(client, _cluster_chunk, _chunks(pending, workers, chunk_size), stop=should_stop):
            for line in lines:
                write(line)
                received += 1
    return received


