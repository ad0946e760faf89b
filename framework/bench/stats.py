"""Statistics of benchmark runs: summary of a sample, the paired sign test (papers 001 and 002), and the tables
of a set of runs (per group and solver) with their Markdown rendering.

No I/O. The sign test is computed exactly from binomial coefficients, so it agrees with
``scipy.stats.binomtest(k, n, 0.5)`` (two-sided) to the last bits without depending on scipy.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Protocol

import numpy as np

from ..errors import MetaikError


@dataclass(frozen=True)
class Summary:
    """Statistics of a sample (papers 000-002 report mean, STD, best and worst).

    Attributes:
        count: sample size.
        mean, std: mean and sample standard deviation (``ddof=1``, as Matlab's ``std``; 0 for one value).
        best, worst, median: minimum, maximum and median.
    """

    count: int
    mean: float
    std: float
    best: float
    worst: float
    median: float


def summarize(values: np.ndarray | list[float]) -> Summary:
    """Mean, sample STD, best (min), worst (max) and median of the finite-or-not values ``(k,)``.

    NaN values propagate (a failed measurement is never silently dropped); an empty sample raises.
    """
    x = np.asarray(values, dtype=float).reshape(-1)
    if x.size == 0:
        raise MetaikError("cannot summarize an empty sample")
    std = float(np.std(x, ddof=1)) if x.size > 1 else 0.0
    return Summary(
        int(x.size), float(np.mean(x)), std, float(np.min(x)), float(np.max(x)), float(np.median(x))
    )


@dataclass(frozen=True)
class SignTest:
    """Paired sign test of a reference against another solver on one metric (lower is better).

    Attributes:
        wins: pairs where the reference is lower (better).
        losses: pairs where the other is lower.
        ties: pairs within the tie tolerance (discarded, as usual for the sign test).
        p_value: two-sided exact binomial p-value of ``wins`` in ``wins + losses`` trials at probability 1/2.
    """

    wins: int
    losses: int
    ties: int
    p_value: float

    @property
    def n(self) -> int:
        """Number of untied pairs."""
        return self.wins + self.losses


def binomial_two_sided(k: int, n: int) -> float:
    """Exact two-sided p-value of ``k`` successes in ``n`` fair Bernoulli trials.

    For ``p = 1/2`` the distribution is symmetric, so the two-sided p-value (sum of the probabilities of every
    outcome no more likely than ``k``, scipy's definition) is twice the smaller tail, capped at 1.
    """
    if n < 0 or not 0 <= k <= n:
        raise MetaikError(f"binomial test needs 0 <= k <= n; got k={k}, n={n}")
    if n == 0:
        return 1.0
    tail = min(k, n - k)
    if 2 * tail == n:
        return 1.0
    count = sum(math.comb(n, i) for i in range(tail + 1))
    return float(min(Fraction(1), Fraction(2 * count, 2**n)))


def sign_test(
    reference: np.ndarray | list[float], other: np.ndarray | list[float], *, atol: float = 0.0
) -> SignTest:
    """Sign test of paired samples ``reference`` and ``other`` ``(k,)`` (lower values are better).

    A pair is a win when ``reference < other - atol``, a loss when ``other < reference - atol``, a tie otherwise.
    NaN pairs raise: a failed run must be dealt with before testing.
    """
    a = np.asarray(reference, dtype=float).reshape(-1)
    b = np.asarray(other, dtype=float).reshape(-1)
    if a.shape != b.shape:
        raise MetaikError(f"sign test needs paired samples of equal length; got {a.size} and {b.size}")
    if np.isnan(a).any() or np.isnan(b).any():
        raise MetaikError("sign test samples hold NaN")
    if atol < 0:
        raise MetaikError(f"tie tolerance must be >= 0; got {atol}")
    wins = int(np.sum(a < b - atol))
    losses = int(np.sum(b < a - atol))
    return SignTest(wins, losses, int(a.size) - wins - losses, binomial_two_sided(wins, wins + losses))


# ---------------------------------------------------------------------------------------------- tables of runs
#: Metrics of a run (attributes of a run record), in table order; per-term values follow.
METRICS = (
    "task_error",
    "position_error",
    "orientation_error",
    "motion_error",
    "cost",
    "wall_time",
    "cpu_time",
    "evaluations",
    "iterations",
)
#: Metrics the sign test compares by default (lower is better for each; CPU rather than wall time: robust to load).
SIGN_METRICS = ("task_error", "motion_error", "cost", "cpu_time")


class Run(Protocol):
    """What the tables need of a run (:class:`framework.bench.RunRecord` is one)."""

    task: str
    system: str
    case: str
    solver: str
    seed: int
    task_error: float
    cost: float
    terms: dict[str, float]
    history_at: list[int]
    history: list[float]

    def metric(self, name: str) -> float: ...


@dataclass(frozen=True)
class SummaryRow:
    """Statistics of the runs of one solver in one group (a case, or a system with its cases pooled)."""

    group: str
    solver: str
    runs: int
    successes: int
    stats: dict[str, Summary]

    @property
    def success_rate(self) -> float:
        return self.successes / self.runs


@dataclass(frozen=True)
class SignRow:
    """Sign test of the reference solver against ``other`` on ``metric`` in one group."""

    group: str
    metric: str
    reference: str
    other: str
    test: SignTest


def group_label(record: Run, group_by: str, *, tasks: int = 1, systems: int = 1) -> str:
    """The label a record is grouped under: ``[task /] [system /] case`` (the case only for ``"case"``)."""
    parts = [record.task] if tasks > 1 else []
    if group_by == "system" or systems > 1:
        parts.append(record.system)
    if group_by == "case":
        parts.append(record.case)
    return " / ".join(parts)


def group_records(records: Iterable[Run], group_by: str = "case") -> dict[str, list[Run]]:
    """Records by group label, in first-seen order."""
    records = list(records)
    tasks = len({r.task for r in records})
    systems = len({(r.task, r.system) for r in records})
    groups: dict[str, list[Run]] = {}
    for r in records:
        groups.setdefault(group_label(r, group_by, tasks=tasks, systems=systems), []).append(r)
    return groups


def by_solver(records: Iterable[Run]) -> dict[str, list[Run]]:
    out: dict[str, list[Run]] = {}
    for r in records:
        out.setdefault(r.solver, []).append(r)
    return out


def summary_rows(
    records: Iterable[Run], *, group_by: str = "case", tolerance: float = 1e-4
) -> list[SummaryRow]:
    """Mean / STD / best / worst / median of every metric and term per (group, solver).

    Success: ``task_error <= tolerance``.
    """
    rows = []
    for group, members in group_records(records, group_by).items():
        for solver, runs in by_solver(members).items():
            names = [m for m in METRICS if any(getattr(r, m) is not None for r in runs)]
            names += [t for t in runs[0].terms if t not in names]
            stats = {m: summarize([r.metric(m) for r in runs]) for m in names}
            successes = sum(r.task_error <= tolerance for r in runs)
            rows.append(SummaryRow(group, solver, len(runs), int(successes), stats))
    return rows


def sign_rows(
    records: Iterable[Run], reference: str, *, group_by: str = "case", metrics: Sequence[str] = SIGN_METRICS
) -> list[SignRow]:
    """Sign tests of ``reference`` against every other solver per group and metric (lower is better).

    Runs are paired by (task, system, case, seed): paper 001 pairs the random points, paper 002 the path points;
    for one case with many runs the pairs are runs with the same seed.
    """
    rows = []
    for group, members in group_records(records, group_by).items():
        solvers = by_solver(members)
        if reference not in solvers:
            continue
        ref = {(r.task, r.system, r.case, r.seed): r for r in solvers[reference]}
        for metric in metrics:
            if any(math.isnan(r.metric(metric)) for r in solvers[reference]):
                continue
            for other, runs in solvers.items():
                if other == reference:
                    continue
                pairs = [
                    (ref[k].metric(metric), r.metric(metric))
                    for r in runs
                    if (k := (r.task, r.system, r.case, r.seed)) in ref
                ]
                if pairs:
                    a, b = np.array(pairs).T
                    rows.append(SignRow(group, metric, reference, other, sign_test(a, b)))
    return rows


def best_runs(records: Iterable[Run], group_by: str = "case") -> dict[str, dict[str, Run]]:
    """Per group and solver, the run with the lowest task error (then cost): the one whose curve is drawn."""
    return {
        g: {s: min(runs, key=lambda r: (r.task_error, r.cost)) for s, runs in by_solver(members).items()}
        for g, members in group_records(records, group_by).items()
    }


def convergence_curves(records: Sequence[Run], group_by: str = "case") -> dict[str, dict[str, tuple]]:
    """Per group and solver: (iterations, best cost − f*) of the best run; f* = the lowest final cost of its case.

    The subtraction makes convergence visible on a log axis when the optimum has a non-zero motion cost.
    """
    floor: dict[tuple, float] = {}
    for r in records:
        k = (r.task, r.system, r.case)
        floor[k] = min(floor.get(k, math.inf), r.cost, *r.history)
    curves: dict[str, dict[str, tuple]] = {}
    for group, by_solver in best_runs(records, group_by).items():
        curves[group] = {}
        for solver, r in by_solver.items():
            f_star = floor[(r.task, r.system, r.case)]
            values = np.maximum(np.asarray(r.history) - f_star, np.finfo(float).eps * max(1.0, abs(f_star)))
            curves[group][solver] = (np.asarray(r.history_at), values)
    return curves


def sci(x: float) -> str:
    """``x`` in the tables' scientific notation (3 decimals)."""
    return "nan" if math.isnan(x) else f"{x:.3e}"


def summary_markdown(rows: Sequence[SummaryRow], tolerance: float) -> str:
    """Markdown: per group, one line per solver with the task-error statistics, success, time and evaluations."""
    lines = []
    for group in dict.fromkeys(r.group for r in rows):
        lines += [
            f"### {group}",
            "",
            (
                f"| solver | runs | mean | std | best | worst | median | success (≤ {tolerance:g}) "
                "| median wall time [s] | median CPU time [s] | median evaluations |"
            ),
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
        ]
        for r in (r for r in rows if r.group == group):
            e = r.stats["task_error"]
            cpu = f"{r.stats['cpu_time'].median:.3f}" if "cpu_time" in r.stats else "–"
            lines.append(
                f"| {r.solver} | {r.runs} | {sci(e.mean)} | {sci(e.std)} | {sci(e.best)} | {sci(e.worst)} | "
                f"{sci(e.median)} | {r.successes}/{r.runs} | {r.stats['wall_time'].median:.3f} | {cpu} | "
                f"{r.stats['evaluations'].median:.0f} |"
            )
        lines.append("")
    return "\n".join(lines)


def terms_markdown(rows: Sequence[SummaryRow]) -> str:
    """Markdown: mean ± std of every term and the cost, per group and solver."""
    lines = []
    for group in dict.fromkeys(r.group for r in rows):
        members = [r for r in rows if r.group == group]
        names = [
            n for n in members[0].stats if n not in ("wall_time", "cpu_time", "evaluations", "iterations")
        ]
        lines += [
            f"### {group}",
            "",
            "| solver | " + " | ".join(names) + " |",
            "|---|" + "---:|" * len(names),
        ]
        for r in members:
            cells = [f"{sci(r.stats[n].mean)} ± {sci(r.stats[n].std)}" if n in r.stats else "" for n in names]
            lines.append(f"| {r.solver} | " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines)


def sign_markdown(rows: Sequence[SignRow]) -> str:
    """Markdown: per group and metric, wins / losses / ties / p of the reference against each solver."""
    lines = []
    for group in dict.fromkeys(r.group for r in rows):
        for metric in dict.fromkeys(r.metric for r in rows if r.group == group):
            members = [r for r in rows if r.group == group and r.metric == metric]
            lines += [
                f"### {group}: {metric} ({members[0].reference} against each; lower is better)",
                "",
                "| vs | wins (+) | losses (−) | ties | p (two-sided) |",
                "|---|---:|---:|---:|---:|",
            ]
            lines += [
                f"| {r.other} | {r.test.wins} | {r.test.losses} | {r.test.ties} | {r.test.p_value:.4g} |"
                for r in members
            ]
            lines.append("")
    return "\n".join(lines)
