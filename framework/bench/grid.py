"""The grid of a benchmark: task files expanded into cases (systems, generated cases), sized and planned
into run specs made when read (:func:`plan`)."""


from __future__ import annotations

import copy
import hashlib
import json
import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import MetaikError, TaskError
from ..model.loading import load_robot
from ..costs.problem import Problem
from ..validate import check_table

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
    from ..io.taskfile import TaskFile, load_task

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
    text = json.dumps(jsonable(content), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _parse(path: Path, raw: dict[str, Any]):
    """A task from the (rewritten) TOML dict of ``path``; errors name the file."""
    from ..io.taskfile import task_from_dict

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
    from ..solvers.solve import DEFAULT_SOLVER
    from ..solvers import solver_names
    from ..optimizers.base import MAX_POPULATION
    from ..validate import positive_int

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
        history = option(None, b.get("history_points", HISTORY_POINTS), "history_points", where, minimum=0)
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


def jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None if math.isnan(value) else (1e308 if value > 0 else -1e308)
    return value
