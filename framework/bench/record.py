"""One run of a grid: :func:`execute` solves a spec into a :class:`RunRecord` (one line of the results file)."""


from __future__ import annotations

import json
import time
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from ..costs.problem import Problem
from .stats import (
    METRICS,
)
from .grid import RunSpec, jsonable


# ---------------------------------------------------------------------------------------------- one run
@dataclass(frozen=True)
class RunRecord:
    """One finished run, as stored in the results file (one JSON object per line).

    Attributes:
        task, system, case, solver, seed, budget, problem: the run's identity (``budget``: canonical JSON string).
        settings: every solver setting used (from :class:`~framework.solvers.solve.IKResult`).
        terms: unweighted value of every cost term, by name.
        task_error: sum of the unweighted task terms (position [m], orientation, relative position [m]).
        position_error, orientation_error, motion_error: sums of the terms measuring positions (Position,
            RelativePosition, ...), orientations and motion (their ``category``;
            ``None`` when the objective has no such term).
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
        return json.dumps(jsonable(asdict(self)), separators=(",", ":"), allow_nan=False)

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
    """The terms' values summed by what they measure (:attr:`~framework.costs.Term.category`)."""
    sums: dict[str, float | None] = {}
    for category in ("position", "orientation", "motion"):
        names = [n for n, (_, t) in zip(problem.names, problem.objective) if t.category == category]
        sums[f"{category}_error"] = float(sum(terms[n] for n in names)) if names else None
    return sums


def execute(spec: RunSpec, problem: Problem) -> RunRecord:
    """Solve one run of the grid and build its record."""
    from ..solvers.solve import solve

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
        settings=jsonable(result.settings),
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


