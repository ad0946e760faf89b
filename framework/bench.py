"""Benchmark harness: a grid of (task file, system, case, solver, seed) IK runs, in parallel, resumable.

The grid comes from task files (a top-level ``[bench]`` table) and command-line overrides::

    [bench]
    solvers = ["cmaes", "de", "sde"]     # default: [solver].name
    runs = 100                           # independent runs per (case, solver); seeds seed .. seed + runs - 1
    seed = 0
    reference = "de"                     # the sign test compares it against every other solver
    group_by = "case"                    # tables and figures per "case" or per "system" (cases pooled)
    random_reachable = 50                # optional: generated cases, targets = FK of random configurations
    case_seed = 1                        #   drawn uniformly within the limits by default_rng([case_seed, system])
    history_points = 200                 # best cost per iteration kept per run (downsampled); 0 keeps all
    [bench.options.de]                   # optional solver parameters by solver
    F = 0.6
    [[bench.systems]]                    # optional: the same task on other robots (default: the task's robot)
    robot = "baxter_dual"                # end-effector frames and joint groups of the task's robot are mapped
                                         # by position onto this robot's (index order)
    cases = [{ name = "p", t = [0.6, 0.6, 0.8] }]   # optional: this system's own cases

Generated cases (``random_reachable``) define, for every end-effector ``i`` (1-based, index order), the variables
``t_ee{i}`` (world position [m]) and ``R_ee{i}`` (world rotation), and ``q_ref`` (the sampled configuration).

Every finished run is appended to a JSON-lines results file as soon as it ends (so Ctrl-C or a crash loses at
most the runs in flight); re-running the same grid skips the runs already in the file. :func:`write_report`
then writes the summary tables (Markdown, CSV), the sign tests, boxplots and convergence curves.
"""

from __future__ import annotations

import copy
import csv
import hashlib
import json
import math
import multiprocessing as mp
import os
import shlex
import signal
import sys
import time
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from pathlib import Path
from queue import Empty
from typing import Any

import numpy as np

from .costs import Motion, Orientation, Position, RelativePosition
from .errors import EXIT_INTERRUPTED, EXIT_OK, MetaikError, TaskError
from .interrupts import graceful_interrupt
from .loading import load_robot
from .problem import Problem
from .stats import (
    METRICS,
    group_records,
    sci,
    sign_markdown,
    sign_rows,
    summary_markdown,
    summary_rows,
    terms_markdown,
)
from .taskfile import resolve_task
from .validate import check_table

HISTORY_POINTS = 200
#: ``[bench]`` keys and the kind of their values (:data:`framework.validate.KINDS`).
BENCH_KEYS = {"solvers": "names", "runs": "integer", "seed": "integer", "reference": "text", "group_by": "text",
              "random_reachable": "integer", "case_seed": "integer", "history_points": "integer",
              "options": "table", "systems": "list"}
SYSTEM_KEYS = {"robot", "name", "cases"}
GROUP_BY = ("case", "system")
#: Robot options of [task] that belong to the task's own robot and are dropped for other systems.
ROBOT_OPTIONS = ("joints", "locked", "end_effectors", "xacro_args", "bounds", "floating_base")


# ---------------------------------------------------------------------------------------------- the grid
@dataclass(frozen=True)
class BenchCase:
    """One IK problem of a benchmark: its system (robot variant), case name, problem and case variables.

    ``fingerprint`` hashes everything that defines the problem (robot, terms, previous configuration, bounds
    handling, the case's variables), so a results file never mixes runs of an edited task with new ones.
    """

    system: str
    name: str
    problem: Problem
    variables: dict[str, Any] = field(default_factory=dict, repr=False)
    fingerprint: str = ""


@dataclass(frozen=True)
class BenchTask:
    """A task file expanded for benchmarking: its ``[bench]`` settings and every (system, case)."""

    path: Path
    name: str
    solver: dict[str, Any]
    bench: dict[str, Any]
    cases: tuple[BenchCase, ...]

    def case(self, system: str, name: str) -> BenchCase:
        for c in self.cases:
            if c.system == system and c.name == name:
                return c
        raise TaskError(f"{self.path}: no case {name!r} of system {system!r}")


@dataclass(frozen=True)
class RunSpec:
    """One run of the grid. ``budget`` is a canonical JSON string (population, iterations, tolerance, options),
    ``problem`` the case's :attr:`BenchCase.fingerprint`."""

    path: str
    task: str
    system: str
    case: str
    solver: str
    seed: int
    budget: str
    problem: str = ""
    history_points: int = HISTORY_POINTS

    @property
    def key(self) -> tuple[str, str, str, str, int, str, str]:
        """Identity of the run in a results file (``problem``: the case's fingerprint)."""
        return (self.task, self.system, self.case, self.solver, self.seed, self.budget, self.problem)


@dataclass(frozen=True)
class Grid:
    """Every run of a benchmark, in execution order (seed-major, so a partial grid covers every solver)."""

    tasks: tuple[BenchTask, ...]
    specs: Sequence[RunSpec]
    tolerance: float
    reference: str | None
    group_by: str

    @property
    def name(self) -> str:
        return "+".join(t.name for t in self.tasks)

    @property
    def keys(self) -> set[tuple]:
        return {s.key for s in self.specs}


def bench_table(raw: Mapping[str, Any], path: Path) -> dict[str, Any]:
    """The validated ``[bench]`` table of a task file (empty if absent)."""
    bench = raw.get("bench", {})
    if not isinstance(bench, dict):
        raise TaskError(f"{path}: [bench] must be a table")
    check_table(bench, BENCH_KEYS, f"{path}: [bench]")
    for i, system in enumerate(bench.get("systems", [])):
        if not isinstance(system, dict) or "robot" not in system:
            raise TaskError(f"{path}: [[bench.systems]] #{i + 1} needs a robot")
        if set(system) - SYSTEM_KEYS:
            raise TaskError(
                f"{path}: [[bench.systems]] #{i + 1} has unknown keys {sorted(set(system) - SYSTEM_KEYS)}"
            )
    if bench.get("group_by", "case") not in GROUP_BY:
        raise TaskError(f"{path}: [bench] group_by must be one of {GROUP_BY}")
    return dict(bench)


def expand_task(path: str | Path) -> BenchTask:
    """Load a task file and expand its systems and generated cases into :class:`BenchCase` s (deterministic)."""
    from .taskfile import TaskFile, load_task

    path = Path(path).resolve()
    task = load_task(path)
    if not isinstance(task, TaskFile) or task.is_tracking:
        kind = "a tracking" if isinstance(task, TaskFile) else f"a {type(task).__name__}"
        raise TaskError(f"{path}: metaik bench compares solvers on IK cases; this is {kind} task (metaik run it)")
    bench = bench_table(task.raw, path)
    systems = bench.get("systems") or [{"robot": None}]
    cases: list[BenchCase] = []
    for index, system in enumerate(systems):
        raw = task.raw if system["robot"] is None else _system_raw(task.raw, task.robot, system, path)
        name = system.get("name") or (task.robot.name if system["robot"] is None else str(system["robot"]))
        parsed = _parse(path, raw)
        if bench.get("random_reachable"):
            rng = np.random.default_rng([int(bench.get("case_seed", 0)), index])
            raw = {**raw, "cases": random_reachable_cases(parsed.robot, int(bench["random_reachable"]), rng)}
            parsed = _parse(path, raw)
        cases.extend(
            BenchCase(
                name, c.name, c.problem, dict(c.variables), problem_fingerprint(raw, task.solver, c.variables)
            )
            for c in parsed.cases
        )
    keys = [(c.system, c.name) for c in cases]
    if len(set(keys)) != len(keys):
        raise TaskError(f"{path}: (system, case) names must be unique; name the systems or the cases")
    return BenchTask(path, task.name, dict(task.solver), bench, tuple(cases))


def problem_fingerprint(
    raw: Mapping[str, Any], solver: Mapping[str, Any], variables: Mapping[str, Any]
) -> str:
    """16 hex digits of a hash of what defines one case's problem (not its name, description or solver budget)."""
    task = {k: v for k, v in raw["task"].items() if k not in ("name", "description")}
    content = {
        "task": task,
        "terms": raw.get("terms"),
        "previous": raw.get("previous"),
        "bounds": solver.get("bounds", "resample"),
        "variables": variables,
    }
    text = json.dumps(_jsonable(content), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _parse(path: Path, raw: dict[str, Any]):
    """A task from the (rewritten) TOML dict of ``path``; errors name the file."""
    from .taskfile import task_from_dict

    try:
        return task_from_dict(raw, path)
    except MetaikError as err:
        raise type(err)(err if str(path) in str(err) else f"{path}: {err}") from err


def _system_raw(raw: Mapping[str, Any], base, system: Mapping[str, Any], path: Path) -> dict[str, Any]:
    """The task's TOML dict rewritten for another robot: frames and groups mapped by position."""
    source = str(system["robot"])
    local = path.parent / source
    robot = load_robot(local if local.is_file() else source)
    if len(robot.end_effectors) != len(base.end_effectors) or len(robot.groups) != len(base.groups):
        raise TaskError(
            f"{path}: system {source!r} has end-effectors {list(robot.end_effectors)} and groups "
            f"{list(robot.groups)}; the task's robot has {list(base.end_effectors)} and {list(base.groups)}"
        )
    frames = dict(zip(base.end_effectors, robot.end_effectors))
    groups = dict(zip(base.groups, robot.groups))
    out = copy.deepcopy(dict(raw))
    out["task"] = {k: v for k, v in out["task"].items() if k not in ROBOT_OPTIONS}
    out["task"]["robot"] = str(local) if local.is_file() else source
    for term in out.get("terms", []):
        for key in ("frame", "frame_a", "frame_b"):
            if key in term:
                term[key] = frames.get(term[key], term[key])
        if "group" in term:
            term["group"] = groups.get(term["group"], term["group"])
    if "previous" in out:
        out["previous"] = {groups.get(k, k): v for k, v in out["previous"].items()}
    if "cases" in system:
        out["cases"] = copy.deepcopy(list(system["cases"]))
    return out


def random_reachable_cases(robot, count: int, rng: np.random.Generator) -> list[dict[str, Any]]:
    """``count`` cases whose targets are the FK of configurations drawn uniformly within the robot's box.

    Each case defines ``t_ee{i}`` [m] and ``R_ee{i}`` (world frame) for every end-effector ``i`` (1-based) and
    ``q_ref`` (the configuration), as plain lists for the task-file expressions.
    """
    if count < 1:
        raise TaskError(f"random_reachable must be a positive number of cases; got {count}")
    Q = robot.random_configurations(rng, count)
    poses = robot.frame_poses(Q)
    cases = []
    for j in range(count):
        case: dict[str, Any] = {"name": f"point {j + 1:0{len(str(count))}d}", "q_ref": Q[j].tolist()}
        for i, frame in enumerate(poses.frames, start=1):
            case[f"t_ee{i}"] = poses.position(frame)[j].tolist()
            case[f"R_ee{i}"] = poses.rotation(frame)[j].tolist()
        cases.append(case)
    return cases


#: Largest grid :func:`plan` builds unless told otherwise (``grid_limit=`` / ``metaik bench --grid-limit``).
GRID_LIMIT = 100_000


@dataclass(frozen=True)
class _TaskRuns:
    """One task's block of the grid: ``runs`` seeds x ``cases`` x ``solvers``, seed-major."""

    task: BenchTask
    solvers: tuple[str, ...]
    cases: tuple[BenchCase, ...]
    first_seed: int
    runs: int
    budgets: tuple[str, ...]  # per solver
    history_points: int

    def __len__(self) -> int:
        return self.runs * len(self.cases) * len(self.solvers)

    def spec(self, i: int) -> RunSpec:
        r, rest = divmod(i, len(self.cases) * len(self.solvers))
        c, s = divmod(rest, len(self.solvers))
        case = self.cases[c]
        return RunSpec(str(self.task.path), self.task.name, case.system, case.name, self.solvers[s],
                       self.first_seed + r, self.budgets[s], case.fingerprint, self.history_points)


class RunSpecs(Sequence):
    """The runs of a grid, made when read (a grid is sized before any of its runs exists)."""

    def __init__(self, blocks: Sequence[_TaskRuns]) -> None:
        self._blocks = tuple(blocks)
        self._ends = np.cumsum([len(b) for b in self._blocks]).tolist()

    def __len__(self) -> int:
        return self._ends[-1] if self._ends else 0

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(len(self)))]
        if not -len(self) <= i < len(self):
            raise IndexError(i)
        i %= len(self)
        b = int(np.searchsorted(self._ends, i, side="right"))
        return self._blocks[b].spec(i - (self._ends[b - 1] if b else 0))

    def __iter__(self) -> Iterator[RunSpec]:
        for block in self._blocks:
            for i in range(len(block)):
                yield block.spec(i)


def plan(
    paths: Sequence[str | Path],
    *,
    solvers: Sequence[str] | None = None,
    runs: int | None = None,
    seed: int | None = None,
    population: int | None = None,
    max_iterations: int | None = None,
    tolerance: float | None = None,
    cases: Sequence[str] | None = None,
    reference: str | None = None,
    group_by: str | None = None,
    grid_limit: int = GRID_LIMIT,
) -> Grid:
    """The grid of runs for task files; keyword arguments override the files' ``[bench]`` / ``[solver]`` values.

    ``cases`` keeps only cases (or systems) with these names. The grid is sized first: more than ``grid_limit``
    runs raise :class:`TaskError` (raise the limit to run it); its :class:`RunSpec` s are made as they are read.
    """
    from .solve import DEFAULT_SOLVER
    from .solvers import solver_names
    from .solvers.base import MAX_POPULATION
    from .solvers.ik import positive_int

    def option(value, task_value, what: str, where: str, **limits) -> int:
        try:
            return positive_int(value if value is not None else task_value, what, **limits)
        except MetaikError as err:
            raise TaskError(f"{where}: {err}") from None

    tasks = tuple(expand_task(p) for p in paths)
    if not tasks:
        raise TaskError("a benchmark needs at least one task file")
    if tolerance is not None and not (isinstance(tolerance, (int, float)) and math.isfinite(tolerance)
                                      and tolerance > 0):
        raise TaskError(f"tolerance must be a positive number; got {tolerance!r}")
    known = set(solver_names())
    blocks: list[_TaskRuns] = []
    for task in tasks:
        b, s = task.bench, task.solver
        names = tuple(solvers or b.get("solvers") or [s.get("name", DEFAULT_SOLVER)])
        bad = [n for n in names if n not in known]
        if bad:
            raise TaskError(f"{task.path}: unknown solver(s) {bad}; available: {sorted(known)}")
        where = f"{task.path}"
        n_runs = option(runs, b.get("runs", 1), "runs", where)
        first = option(seed, b.get("seed", s.get("seed", 0)), "seed", where, minimum=0)
        selected = tuple(c for c in task.cases if not cases or c.name in cases or c.system in cases)
        if not selected:
            raise TaskError(f"{task.path}: no case named {list(cases or [])}")
        options = b.get("options", {})
        budgets = tuple(
            json.dumps({
                "population": option(population, s.get("population", 30), "population", where,
                                     maximum=MAX_POPULATION),
                "max_iterations": option(max_iterations, s.get("max_iterations", 1000), "max_iterations", where),
                "tolerance": float(tolerance or s.get("tolerance", 1e-4)),
                "stop_at_tolerance": bool(s.get("stop_at_tolerance", False)),
                "options": options.get(name, s.get("options") if name == s.get("name") else None),
            }, sort_keys=True)
            for name in names
        )
        history = option(None, b.get("history_points", HISTORY_POINTS), "history_points", where)
        blocks.append(_TaskRuns(task, names, selected, first, n_runs, budgets, history))
    size = sum(len(block) for block in blocks)
    if size > grid_limit:
        raise TaskError(
            f"the grid has {size:,} runs, more than the limit of {grid_limit:,}: lower runs / cases / solvers, "
            f"or raise the limit (--grid-limit, plan(grid_limit=...)); --max-runs runs part of a grid"
        )
    first_task = tasks[0]
    every = {n for block in blocks for n in block.solvers}
    if reference is not None and reference not in every:
        raise TaskError(f"reference solver {reference!r} is not in the grid; its solvers: {sorted(every)}")
    ref = reference or first_task.bench.get("reference")
    ref = ref if ref in every else None  # the file's reference, unless --solvers left it out
    return Grid(
        tasks,
        RunSpecs(blocks),
        float(tolerance or first_task.solver.get("tolerance", 1e-4)),
        ref,
        group_by or first_task.bench.get("group_by", "case"),
    )


# ---------------------------------------------------------------------------------------------- one run
@dataclass(frozen=True)
class RunRecord:
    """One finished run, as stored in the results file (one JSON object per line).

    Attributes:
        task, system, case, solver, seed, budget, problem: the run's identity (``budget``: canonical JSON string).
        settings: every solver setting used (from :class:`~framework.solve.IKResult`).
        terms: unweighted value of every cost term, by name.
        task_error: sum of the unweighted task terms (position [m], orientation, relative position [m]).
        position_error, orientation_error, motion_error: sums of the Position + RelativePosition, Orientation and
            Motion terms (``None`` when the objective has no such term).
        cost, success, stop_reason, iterations, evaluations, wall_time [s]: as in ``IKResult``.
        configuration: the solution ``(n,)``.
        history_at, history: 1-based iterations and the best cost after them (downsampled).
        cpu_time: CPU seconds of the solving process (robust to other load on the machine, unlike ``wall_time``).
        problem: fingerprint of the case's problem (part of the identity, see :class:`BenchCase`).
    """

    task: str
    system: str
    case: str
    solver: str
    seed: int
    budget: str
    settings: dict[str, Any]
    terms: dict[str, float]
    task_error: float
    position_error: float | None
    orientation_error: float | None
    motion_error: float | None
    cost: float
    success: bool
    stop_reason: str
    iterations: int
    evaluations: int
    wall_time: float
    configuration: list[float] = field(repr=False)
    history_at: list[int] = field(repr=False)
    history: list[float] = field(repr=False)
    cpu_time: float | None = None
    problem: str = ""

    @property
    def key(self) -> tuple[str, str, str, str, int, str, str]:
        return (self.task, self.system, self.case, self.solver, self.seed, self.budget, self.problem)

    def metric(self, name: str) -> float:
        """A metric of :data:`METRICS` or a term value; ``nan`` if the run has none."""
        value = getattr(self, name) if name in METRICS else self.terms.get(name)
        return float("nan") if value is None else float(value)

    def to_json(self) -> str:
        return json.dumps(_jsonable(asdict(self)), separators=(",", ":"), allow_nan=False)

    @classmethod
    def from_json(cls, line: str) -> RunRecord:
        return cls(**json.loads(line))


def downsample(history: np.ndarray, points: int) -> tuple[list[int], list[float]]:
    """Iterations (1-based) and values of a best-cost history kept for the results file.

    All of the first ``points // 4`` iterations, then ``points`` evenly spaced ones and the last; ``points <= 0``
    keeps everything. Values are stored exactly (JSON floats round-trip).
    """
    h = np.asarray(history, dtype=float)
    n = h.size
    if points <= 0 or n <= points:
        at = np.arange(1, n + 1)
    else:
        head = np.arange(1, points // 4 + 1)
        at = np.unique(np.concatenate([head, np.round(np.linspace(1, n, points)).astype(int)]))
    return at.tolist(), h[at - 1].tolist()


def _error_sums(problem: Problem, terms: Mapping[str, float]) -> dict[str, float | None]:
    kinds = {
        "position_error": (Position, RelativePosition),
        "orientation_error": (Orientation,),
        "motion_error": (Motion,),
    }
    sums: dict[str, float | None] = {}
    for key, classes in kinds.items():
        names = [n for n, (_, t) in zip(problem.names, problem.objective) if isinstance(t, classes)]
        sums[key] = float(sum(terms[n] for n in names)) if names else None
    return sums


def execute(spec: RunSpec, problem: Problem) -> RunRecord:
    """Solve one run of the grid and build its record."""
    from .solve import solve

    budget = json.loads(spec.budget)
    cpu = time.process_time()
    result = solve(
        problem,
        spec.solver,
        seed=spec.seed,
        max_iterations=budget["max_iterations"],
        population=budget["population"],
        tolerance=budget["tolerance"],
        stop_at_tolerance=budget["stop_at_tolerance"],
        options=budget["options"],
    )
    cpu = time.process_time() - cpu
    at, history = downsample(result.history, spec.history_points)
    return RunRecord(
        task=spec.task,
        system=spec.system,
        case=spec.case,
        solver=spec.solver,
        seed=spec.seed,
        budget=spec.budget,
        settings=_jsonable(result.settings),
        terms=dict(result.terms),
        task_error=result.task_error,
        **_error_sums(problem, result.terms),
        cost=result.cost,
        success=result.success,
        stop_reason=result.stop_reason,
        iterations=result.iterations,
        evaluations=result.evaluations,
        wall_time=result.wall_time,
        configuration=result.configuration.tolist(),
        history_at=at,
        history=history,
        cpu_time=cpu,
        problem=spec.problem,
    )


def _jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None if math.isnan(value) else (1e308 if value > 0 else -1e308)
    return value


# ---------------------------------------------------------------------------------------------- the results file
def read_results(path: str | Path, keys: set[tuple] | None = None) -> list[RunRecord]:
    """Records of a results file (only those whose key is in ``keys``, if given); a torn last line is skipped."""
    path = Path(path)
    if not path.is_file():
        return []
    records, seen = [], set()
    with path.open() as f:
        for line in f:
            try:
                record = RunRecord.from_json(line)
            except (json.JSONDecodeError, TypeError):
                continue  # a line torn by a crash: that run is simply run again
            if (keys is None or record.key in keys) and record.key not in seen:
                seen.add(record.key)  # a run written twice (by a bench of an older version) counts once
                records.append(record)
    return records


def grid_records(grid: Grid, results: str | Path) -> list[RunRecord]:
    """The records of ``grid``'s runs found in ``results``, in grid order (so tables list solvers as given)."""
    order = {spec.key: i for i, spec in enumerate(grid.specs)}
    return sorted(read_results(results, set(order)), key=lambda r: order[r.key])


def drop_runs(results: str | Path, keys: set[tuple]) -> int:
    """Remove the records with these keys from a results file (e.g. to re-run them after a code change).

    Returns how many were removed; the file is rewritten through a temporary file and an atomic rename, under
    the file's lock (no bench may be writing it meanwhile).
    """
    results = Path(results)
    if not results.is_file():
        return 0
    with _exclusive(results):
        return _drop_runs(results, keys)


def _drop_runs(results: Path, keys: set[tuple]) -> int:
    kept, removed = [], 0
    for line in results.read_text().splitlines(keepends=True):
        try:
            drop = RunRecord.from_json(line).key in keys
        except (json.JSONDecodeError, TypeError):
            drop = False
        removed += drop
        if not drop:
            kept.append(line)
    tmp = results.with_name(results.name + ".tmp")
    tmp.write_text("".join(kept))
    os.replace(tmp, results)
    return removed


def _drop_torn_tail(path: Path) -> None:
    """Cut a results file after its last complete line (a crash may have torn the last one)."""
    if not path.is_file() or path.stat().st_size == 0:
        return
    data = path.read_bytes()
    if not data.endswith(b"\n"):
        path.write_bytes(data[: data.rfind(b"\n") + 1])


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
    with _exclusive(results):
        return _run_locked(specs, results, jobs, max_runs, chunk_size, progress, console, stop, scheduler)


@contextmanager
def _exclusive(results: Path) -> Iterator[None]:
    """Hold the results file's lock (``<file>.lock``) for the whole run: a second bench on the same file is an
    error, not a second writer of the same runs."""
    import fcntl

    lock = results.with_name(results.name + ".lock").open("a")
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        lock.close()
        raise MetaikError(f"another bench is writing {results}; wait for it, or give another --out") from None
    try:
        yield
    finally:
        fcntl.flock(lock, fcntl.LOCK_UN)
        lock.close()


def _run_locked(specs, results: Path, jobs, max_runs, chunk_size, progress, console, stop, scheduler) -> RunReport:
    _drop_torn_tail(results)
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
    from .cluster import cluster_client, completed

    received = 0
    with cluster_client(scheduler, jobs) as client:
        workers = max(1, len(client.scheduler_info()["workers"]))
        for _, lines in completed(client, _cluster_chunk, _chunks(pending, workers, chunk_size), stop=should_stop):
            for line in lines:
                write(line)
                received += 1
    return received


# ---------------------------------------------------------------------------------------------- report
def _write_csv(path: Path, header: Sequence[str], rows: Iterable[Sequence[Any]]) -> Path:
    with path.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(header)
        writer.writerows(rows)
    return path


def write_report(
    records: Sequence[RunRecord],
    out_dir: str | Path,
    *,
    tolerance: float = 1e-4,
    reference: str | None = None,
    group_by: str = "case",
    figures: bool = True,
    max_iteration: int | None = None,
) -> list[Path]:
    """Write summary tables (``summary.md``, ``summary.csv``), sign tests (``sign_test.md``/``.csv``, if a
    reference solver is given) and figures (``figures/boxplots_<group>.png``, ``figures/convergence_<group>.png``).

    Returns the written paths.
    """
    from . import plots

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if not records:
        raise MetaikError(f"no results to report in {out}")
    rows = summary_rows(records, group_by=group_by, tolerance=tolerance)
    written = []
    md = [
        "# Benchmark summary",
        "",
        (
            f"Task error (sum of unweighted task terms): mean, sample std (ddof = 1), best, "
            f"worst, median; success = task error ≤ {tolerance:g}."
        ),
        "",
        summary_markdown(rows, tolerance),
        "## Every term (mean ± std)",
        "",
        terms_markdown(rows),
    ]
    (out / "summary.md").write_text("\n".join(md))
    written.append(out / "summary.md")
    metrics = list(dict.fromkeys(m for r in rows for m in r.stats))
    header = ["group", "solver", "runs", "success_rate"] + [
        f"{m}_{s}" for m in metrics for s in ("mean", "std", "best", "worst", "median")
    ]
    written.append(
        _write_csv(
            out / "summary.csv",
            header,
            (
                [r.group, r.solver, r.runs, r.success_rate]
                + [
                    getattr(r.stats[m], s) if m in r.stats else ""
                    for m in metrics
                    for s in ("mean", "std", "best", "worst", "median")
                ]
                for r in rows
            ),
        )
    )
    if reference:
        signs = sign_rows(records, reference, group_by=group_by)
        (out / "sign_test.md").write_text("# Sign tests\n\n" + sign_markdown(signs))
        written.append(out / "sign_test.md")
        written.append(
            _write_csv(
                out / "sign_test.csv",
                ["group", "metric", "reference", "other", "wins", "losses", "ties", "p_value"],
                (
                    [
                        s.group,
                        s.metric,
                        s.reference,
                        s.other,
                        s.test.wins,
                        s.test.losses,
                        s.test.ties,
                        s.test.p_value,
                    ]
                    for s in signs
                ),
            )
        )
    if figures:
        written += plots.report_figures(
            records, out / "figures", group_by=group_by, max_iteration=max_iteration
        )
    return written


NOTES_MARKER = "<!-- notes: hand-written text below this line is kept when this file is regenerated -->"


def machine() -> str:
    """One line about the machine: cores, CPU model, Python and the load average when the report was written."""
    cpu = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    load = (
        ", load average {:.1f} / {:.1f} / {:.1f} (1 / 5 / 15 min)".format(*os.getloadavg())
        if hasattr(os, "getloadavg")
        else ""
    )
    return f"{os.cpu_count()} cores{f' ({cpu})' if cpu else ''}, Python {sys.version.split()[0]}{load}"


def grid_markdown(grid: Grid) -> str:
    """Markdown list of a grid's settings: solvers, runs, budget, cases."""
    lines = []
    for task in grid.tasks:
        specs = [s for s in grid.specs if s.task == task.name]
        budget = json.loads(specs[0].budget)
        systems = list(dict.fromkeys(s.system for s in specs))
        lines += [
            (
                f"- task `{task.name}` ({task.path.name}): {len({(s.system, s.case) for s in specs})} case(s) on "
                f"{', '.join(systems)}"
            ),
            (
                f"- solvers: {', '.join(dict.fromkeys(s.solver for s in specs))}; "
                f"{len({s.seed for s in specs})} run(s) per case and solver (seeds {min(s.seed for s in specs)}.."
                f"{max(s.seed for s in specs)})"
            ),
            (
                f"- population {budget['population']}, {budget['max_iterations']} iterations, tolerance "
                f"{budget['tolerance']:g}, stop at tolerance: {budget['stop_at_tolerance']}"
            ),
        ]
    return "\n".join(lines)


def report_markdown(
    records: Sequence[RunRecord],
    *,
    tolerance: float,
    reference: str | None,
    group_by: str,
    figures: Mapping[str, Sequence[Path]] | None = None,
    relative_to: Path | None = None,
) -> str:
    """The body of a results document: per group the task-error table and its figures, then every term and the
    sign tests. ``figures``: group -> PNG paths, linked relative to ``relative_to``."""
    rows = summary_rows(records, group_by=group_by, tolerance=tolerance)
    parts = [
        (
            f"Task error = sum of the unweighted task terms; mean, sample std (ddof = 1), best, worst, median over the "
            f"runs; success = task error ≤ {tolerance:g}; time = wall time of one solve."
        ),
        "",
    ]
    for block in summary_markdown(rows, tolerance).split("### ")[1:]:
        group = block.split("\n", 1)[0]
        parts.append("### " + block.rstrip("\n") + "\n")
        for png in (figures or {}).get(group, ()):
            link = os.path.relpath(png, relative_to) if relative_to else str(png)
            parts.append(f"![{png.stem}]({Path(link).as_posix()})\n")
    parts += ["## Every term (mean ± std)", "", terms_markdown(rows)]
    if reference:
        parts += ["## Sign tests", "", sign_markdown(sign_rows(records, reference, group_by=group_by))]
    return "\n".join(parts)


def write_doc(path: str | Path, title: str, command: str, body: str) -> Path:
    """Write a generated results document: title, the command that made it, the machine, then ``body``.

    Text after :data:`NOTES_MARKER` in an existing file is kept (the hand-written analysis).
    """
    path = Path(path)
    notes = ""
    if path.is_file() and NOTES_MARKER in path.read_text():
        notes = path.read_text().split(NOTES_MARKER, 1)[1]
    header = [
        f"# {title}",
        "",
        f"Generated by `{command}` on {time.strftime('%Y-%m-%d')}; machine: {machine()}.",
        "",
    ]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(header) + "\n" + body.rstrip("\n") + "\n\n" + NOTES_MARKER + (notes or "\n"))
    return path


def doc_figures(records: Sequence[RunRecord], doc: Path, *, group_by: str, max_iteration: int | None = None):
    """Figures of a results document, in ``<doc folder>/figures/bench/<doc name>_*.png``; group -> paths."""
    from . import plots

    out = doc.parent / "figures" / "bench"
    prefix = doc.stem + "_"
    plots.report_figures(records, out, group_by=group_by, max_iteration=max_iteration, prefix=prefix)
    return {
        group: [out / f"{prefix}{kind}_{plots.slug(group)}.png" for kind in ("boxplots", "convergence")]
        for group in group_records(records, group_by)
    }


# ---------------------------------------------------------------------------------------------- command line
def add_bench_command(subparsers) -> None:
    """Add ``metaik bench`` to an argparse subparsers object (its handler is :func:`bench_command`)."""
    p = subparsers.add_parser(
        "bench", help="benchmark solvers on task files: parallel, resumable, tables + figures"
    )
    p.add_argument("tasks", nargs="+", help="task files (.toml) or shipped task names")
    p.add_argument("--solvers", help="comma-separated solvers (default: the task's [bench] solvers)")
    p.add_argument("--runs", type=int, help="independent runs per (case, solver)")
    p.add_argument("--seed", type=int, help="first seed (runs use seed .. seed + runs - 1)")
    p.add_argument("--iterations", type=int, help="override max_iterations")
    p.add_argument("--population", type=int, help="override the population size")
    p.add_argument("--tolerance", type=float, help="success threshold on the task error")
    p.add_argument("--case", action="append", help="only these cases or systems (by name); repeatable")
    p.add_argument("--reference", help="solver compared against every other by the sign test")
    p.add_argument("--group-by", choices=GROUP_BY, help="tables and figures per case or per system")
    p.add_argument("--jobs", "-j", type=int, help="worker processes (default: all cores)")
    p.add_argument("--scheduler", metavar="tcp://HOST:PORT|local",
                   help="run on a Dask cluster (an address, or 'local': a local cluster of --jobs processes)")
    p.add_argument("--out", help="output folder (default: results/bench/<task name>, git-ignored)")
    p.add_argument("--max-runs", type=int, help="stop after this many new runs (re-run to continue)")
    p.add_argument("--grid-limit", type=int, default=GRID_LIMIT,
                   help=f"refuse grids of more runs than this (default {GRID_LIMIT:,})")
    p.add_argument("--report-only", action="store_true", help="do not run; report the results file")
    p.add_argument(
        "--rerun", action="store_true", help="drop this grid's runs from the results file, run them again"
    )
    p.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    p.add_argument(
        "--doc", help="also write one Markdown results document here (figures in <its folder>/figures/bench)"
    )
    p.add_argument("--title", help="title of the --doc document")
    p.set_defaults(handler=bench_command)


def bench_command(args, console) -> int:
    """Handler of ``metaik bench``: plan, run (resuming), then write and print the report. Exit code 0 or 130."""
    from rich.table import Table

    paths = [resolve_task(t) for t in args.tasks]
    grid = plan(
        paths,
        solvers=[s.strip() for s in args.solvers.split(",") if s.strip()] if args.solvers else None,
        runs=args.runs,
        seed=args.seed,
        population=args.population,
        max_iterations=args.iterations,
        tolerance=args.tolerance,
        cases=args.case,
        reference=args.reference,
        group_by=args.group_by,
        grid_limit=args.grid_limit,
    )
    for flag, value in (("--jobs", args.jobs), ("--max-runs", args.max_runs)):
        if value is not None and value < 1:
            raise TaskError(f"{flag} must be an integer >= 1; got {value}")
    out = Path(args.out) if args.out else Path("results") / "bench" / grid.name
    results = out / "results.jsonl"
    console.print(f"[bold]{grid.name}[/]: {len(grid.specs)} runs → {results}")
    if args.rerun and not args.report_only:
        console.print(f"dropped {drop_runs(results, grid.keys)} earlier runs of this grid")
    if not args.report_only:
        report = run_grid(grid, results, jobs=args.jobs, max_runs=args.max_runs, console=console,
                          scheduler=args.scheduler)
        console.print(
            f"{report.completed} runs done in {report.wall_time:.1f} s, {report.skipped} already in the "
            f"results file"
        )
        if report.interrupted and args.max_runs is None:
            console.print("interrupted: re-run the same command to resume")
            return EXIT_INTERRUPTED
    records = grid_records(grid, results)
    if not records:
        raise MetaikError(f"{results} holds no run of this grid yet")
    written = write_report(
        records,
        out,
        tolerance=grid.tolerance,
        reference=grid.reference,
        group_by=grid.group_by,
        figures=not args.no_figures,
    )
    if args.doc:
        doc = Path(args.doc)
        figures = None if args.no_figures else doc_figures(records, doc, group_by=grid.group_by)
        body = "## Settings\n\n" + grid_markdown(grid) + f"\n\n## Results ({len(records)} runs)\n\n"
        body += report_markdown(
            records,
            tolerance=grid.tolerance,
            reference=grid.reference,
            group_by=grid.group_by,
            figures=figures,
            relative_to=doc.parent,
        )
        written.append(write_doc(doc, args.title or f"Benchmark: {grid.name}", command_line(args), body))
    table = Table(title=f"{grid.name}: task error over {len(records)}/{len(grid.specs)} runs")
    for column in ("group", "solver", "runs", "mean", "std", "best", "worst", "success", "median time (s)"):
        table.add_column(column, justify="left" if column in ("group", "solver") else "right")
    for r in summary_rows(records, group_by=grid.group_by, tolerance=grid.tolerance):
        e = r.stats["task_error"]
        table.add_row(
            r.group,
            r.solver,
            str(r.runs),
            sci(e.mean),
            sci(e.std),
            sci(e.best),
            sci(e.worst),
            f"{r.successes}/{r.runs}",
            f"{r.stats['wall_time'].median:.3f}",
        )
    console.print(table)
    console.print(
        "wrote "
        + ", ".join(str(p) for p in written[:4])
        + (f" and {len(written) - 4} more" if len(written) > 4 else "")
    )
    return EXIT_OK


def command_line(args) -> str:
    """The ``metaik bench`` command line of parsed arguments (for the header of generated documents)."""
    words = ["metaik", "bench", *args.tasks]
    for key, value in sorted(vars(args).items()):
        if key in ("tasks", "command", "handler") or value in (None, False):
            continue
        flag = "--" + key.replace("_", "-")
        values = value if isinstance(value, list) else [value]
        for v in values:
            words += [flag] if v is True else [flag, str(v)]
    return shlex.join(words)
