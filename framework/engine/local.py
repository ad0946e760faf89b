"""The local engine's Python face: one call runs reach → regularize on a packed problem.

:func:`solve_local` is the one local solver of the framework. It reaches the task (level-1 terms) by
Levenberg-Marquardt with random restarts (:mod:`~framework.engine.reach`), then, when the problem has
regularizers (level-2 terms, e.g. motion), minimizes them without leaving the task
(:func:`~framework.engine.regularize.regularize`). Everything runs in compiled code, the random restarts included
(drawn from a seeded stream, :mod:`~framework.engine.draws`); this module converts the time budget into a
deadline and names the outcome. :func:`residuals` gives the stacked residuals and Jacobians at one
configuration (for predictors, task covariances and tests).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ..costs.blocks import LEVEL_REGULARIZER, LEVEL_TASK
from ..costs.kernels import residuals_at
from ..costs.program import Program
from ..errors import SolverError
from ..compiled.native import compiled_entry
from ..compiled.parallel import entry_points
from ..validate import float_copy
from . import regularize as newton_phase
from .derivatives import derivatives_at
from .draws import draws, stream
from .reach import DEADLINE, ITERATIONS, REACHED, STARTS, reach
from .settings import Box, NewtonSettings, ReachSettings, Report
from .weighted import exact_penalty, released_penalties, weighted_newton

_REGULARIZE_STATUS = {newton_phase.CONVERGED: "converged", newton_phase.STALLED: "stalled", newton_phase.DEADLINE: "time_budget",
                      newton_phase.ITERATIONS: "max_iterations", newton_phase.NOT_APPLICABLE: "not_applicable"}


@dataclass(frozen=True)
class LocalSettings:
    """Settings of :func:`solve_local`.

    Attributes:
        tolerance: every position-like task block (position, relative position) within this [m].
        angle_tolerance: every orientation block within this [rad] (default: ``tolerance``).
        max_iterations: Levenberg-Marquardt iterations over all restarts.
        stall: iterations without 2 % progress of ``‖r‖²`` before a restart from a random configuration.
        restarts: whether to restart at all (``False``: one descent from the start).
        time_budget: seconds for the whole solve (checked inside the compiled loops), or ``None``.
        polish: Gauss-Newton steps after reaching the tolerance, kept while they lower ``‖r‖``.
        regularize: minimize the level-2 terms on the task after reaching it.
        regularize_iterations: Newton iterations of that phase.
        smoothing: ``ε`` of the norm-like ρ at zero during the Newton phase (see ``rho_derivatives``).
    """

    tolerance: float = 1e-9
    angle_tolerance: float | None = None
    max_iterations: int = 1000
    stall: int = 12
    restarts: bool = True
    time_budget: float | None = None
    polish: int = 2
    regularize: bool = True
    regularize_iterations: int = 60
    smoothing: float = 1e-10

    def __post_init__(self) -> None:
        for name in ("tolerance", "smoothing"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and np.isfinite(value) and value > 0):
                raise SolverError(f"local engine: {name} must be a positive number; got {value!r}")
        if self.angle_tolerance is not None and not (np.isfinite(self.angle_tolerance) and self.angle_tolerance > 0):
            raise SolverError(f"local engine: angle_tolerance must be a positive number; got {self.angle_tolerance!r}")
        for name in ("max_iterations", "stall", "polish", "regularize_iterations"):
            value = getattr(self, name)
            if not (isinstance(value, (int, np.integer)) and not isinstance(value, bool) and value >= 0):
                raise SolverError(f"local engine: {name} must be an integer >= 0; got {value!r}")
        if self.time_budget is not None and not (np.isfinite(self.time_budget) and self.time_budget > 0):
            raise SolverError(f"local engine: time_budget must be a positive number of seconds; got {self.time_budget!r}")
        # plain Python numbers: the compiled calls take them through entry points resolved for these types
        for name in ("tolerance", "smoothing"):
            object.__setattr__(self, name, float(getattr(self, name)))
        if self.angle_tolerance is not None:
            object.__setattr__(self, "angle_tolerance", float(self.angle_tolerance))
        for name in ("max_iterations", "stall", "polish", "regularize_iterations"):
            object.__setattr__(self, name, int(getattr(self, name)))
        object.__setattr__(self, "restarts", bool(self.restarts))
        object.__setattr__(self, "regularize", bool(self.regularize))

    @property
    def angular(self) -> float:
        return self.tolerance if self.angle_tolerance is None else self.angle_tolerance

    @property
    def max_restarts(self) -> int:
        """Random restarts a descent may take: as many as its iteration and time budgets allow, or none."""
        return _RESTARTS if self.restarts else 0

    def reach_settings(self, deadline_ns: int) -> ReachSettings:
        """The settings :func:`~.reach.reach` takes, with a ``monotonic_ns()`` deadline (0: none)."""
        return ReachSettings(self.tolerance, self.angular, self.max_iterations, self.stall, self.polish,
                             self.max_restarts, deadline_ns)

    def newton_settings(self, deadline_ns: int) -> NewtonSettings:
        """The settings of the Newton phases, with a ``monotonic_ns()`` deadline (0: none)."""
        return NewtonSettings(self.smoothing, self.regularize_iterations, deadline_ns)


class LocalResult(NamedTuple):
    """Outcome of :func:`solve_local`.

    Attributes:
        x: ``(n,)`` the configuration (the reached one, else the closest to the task seen).
        reached: every task block within its tolerance.
        status: ``"reached"``, ``"max_iterations"``, ``"time_budget"``, or ``"no_task"``.
        task_errors: ``(blocks,)`` each task block's error ``‖r‖`` [m or rad] at ``x``.
        iterations, evaluations, restarts: Levenberg-Marquardt iterations, residual evaluations (both phases),
            restarts from random configurations.
        regularized: status of the regularizer phase (``"converged"``, ``"stalled"``, ...; ``None`` if not run).
        multipliers: ``(rows,)`` the task's Lagrange multipliers after that phase (``None`` if not run).
        values: ``(terms,)`` each term's value at ``x`` (``None`` when the problem has terms without blocks).
    """

    x: np.ndarray
    reached: bool
    status: str
    task_errors: np.ndarray
    iterations: int
    evaluations: int
    restarts: int
    regularized: str | None = None
    multipliers: np.ndarray | None = None
    values: np.ndarray | None = None


def search_box(program: Program) -> Box:
    """The robot's box and which coordinates wrap around instead of stopping (:class:`~.settings.Box`)."""
    return Box(program.robot.lower, program.robot.upper, program.layout.box_wrap)


def project_into_box(x: np.ndarray, box: Box) -> None:
    """``x`` into the box in place (numpy; :func:`~.steps.project` in compiled code): clipped, or wrapped into
    ``[lower, lower + 2π)`` on full-turn axes."""
    wrapped = box.lower + np.mod(x - box.lower, 2.0 * np.pi)
    np.copyto(x, np.where(box.wraps, wrapped, np.clip(x, box.lower, box.upper)))


def _nanoseconds(deadline: float | None) -> int:
    """A ``time.monotonic()`` deadline [s] as the compiled loops' ``deadline_ns`` (``0``: none)."""
    return 0 if deadline is None else int(deadline * 1e9)


def solve_local(
    program: Program,
    x0: np.ndarray | None,
    rng: int | np.ndarray | np.random.Generator,
    settings: LocalSettings = LocalSettings(),
    *,
    deadline: float | None = None,
) -> LocalResult:
    """Reach the task from ``x0`` (restarting from uniform random configurations), then regularize on it.

    Args:
        program: the packed problem (:attr:`framework.costs.problem.Problem.program`).
        x0: ``(n,)`` first start (float64); ``None``: drawn from ``rng`` as the restarts draw theirs (uniformly in
            the box, again while in contact, up to :data:`~framework.engine.reach.CLEAR_DRAWS` draws).
        rng: the restart configurations' stream (:func:`~framework.engine.draws.stream`, advanced in place, so
            successive calls draw new configurations), or a seed to make one from.
        settings: tolerances, budgets and phases.
        deadline: ``time.monotonic()`` at which to stop (overrides ``settings.time_budget``).
    """
    program.refresh()
    layout = program.layout
    box = Box(program.robot.lower, program.robot.upper, layout.box_wrap)
    n = box.lower.shape[0]
    if type(rng) is not np.ndarray:
        rng = stream(rng)
    elif rng.dtype != _STREAM or rng.shape != (1,) or not rng.flags.writeable:
        raise SolverError(f"local engine: a restart stream is a writeable uint64 array of shape (1,) (see "
                          f"framework.engine.draws.stream); got {rng.dtype} {rng.shape}")
    drawn = x0 is None
    task_rows = program.task_rows
    if drawn and not task_rows:  # no descent to draw it
        x = draws(rng, box.lower, box.upper, 1)[0]
    else:
        x = np.empty(n) if drawn else float_copy(x0)
        if x.shape != (n,):
            raise SolverError(f"local engine: the start must be {n} joint coordinates; got shape {x.shape}")
    if deadline is None and settings.time_budget is not None:
        deadline = time.monotonic() + settings.time_budget
    deadline_ns = 0 if deadline is None else int(deadline * 1e9)  # (_nanoseconds, written out)
    report = Report(np.empty(layout.task_tolerances.size), np.zeros(len(program.terms)), np.zeros(3, dtype=np.int64))
    code = REACHED
    if task_rows:
        args = (x, drawn, rng, box, program.packed, settings.reach_settings(deadline_ns), report)
        code = _entry(program, reach, args)(*args)
    iterations, evaluations, restarts = report.stats.tolist()
    reached = code == REACHED
    regularized = multipliers = None
    if reached and settings.regularize and program.has_regularizers:
        multipliers = np.zeros(task_rows)
        args = (x, box, program.packed, settings.newton_settings(deadline_ns), multipliers, report)
        code = _entry(program, newton_phase.regularize, args)(*args)
        regularized = regularized_status(code)
        evaluations += int(report.stats[1])
    status = "reached" if reached else _STATUS[int(code)] if task_rows else "no_task"
    values = report.values
    if not task_rows and not regularized:  # nothing ran: the values at the start
        values = program.values(x[None])[0]
    # (tuple.__new__: a named tuple's own __new__ is a Python call more per solve)
    return tuple.__new__(LocalResult, (x, reached, status, report.errors, iterations, evaluations, restarts,
                                       regularized, multipliers, values if not layout.generic else None))


#: The settings :func:`prepare` resolves the entry points with (their types are those of any settings).
_LOADING = LocalSettings(max_iterations=0, regularize=False)


def prepare(program: Program) -> None:
    """Load the engine's compiled code for ``program``'s layout, so that a time budget that starts after this is
    not spent on it: numba loads the code from its disk cache (about half a second for the engine) or compiles it
    (seconds, once per install: the reach loop here, the Newton phase beside it in a helper process,
    :mod:`framework.compiled.parallel`) on a process's first call. Once per layout; then a dictionary lookup."""
    entries = program.layout.entries
    if prepare in entries:
        return
    program.refresh()
    report = Report(np.empty(program.layout.task_tolerances.size), np.zeros(len(program.terms)),
                    np.zeros(3, dtype=np.int64))
    box, x = search_box(program), np.array(program.robot.middle)
    jobs, callees = [], []  # the longest compile first (here, while the helper process takes the others)
    if program.has_regularizers:  # the Newton phase
        arguments = (x, box, program.packed, _LOADING.newton_settings(0), np.zeros(program.task_rows), report)
        jobs.append((newton_phase.regularize, arguments))
        callees = newton_phase.parts(*arguments)
    if program.task_rows:  # the reach loop
        jobs.append((reach, (x, False, stream(0), box, program.packed, _LOADING.reach_settings(0), report)))
    for (kernel, _), point in zip(jobs, entry_points(jobs, callees)):  # those not cached compiled side by side
        entries[kernel] = point
    entries[prepare] = None


#: The stream's dtype (a restart stream is checked against it).
_STREAM = np.dtype(np.uint64)
#: Random restarts of a descent that may restart (:attr:`LocalSettings.max_restarts`).
_RESTARTS = 2**62
_STATUS = {ITERATIONS: "max_iterations", DEADLINE: "time_budget", STARTS: "max_iterations"}


def _entry(program: Program, kernel, args: tuple):
    """``kernel``'s compiled entry point for :func:`solve_local`'s ``args`` on ``program``, resolved once per layout
    (:func:`~framework.compiled.native.compiled_entry`): the types of those arguments are fixed by the layout (its
    robot's box, its packed arrays) and by :func:`solve_local` itself (a float start of shape ``(n,)``, a stream,
    the outputs it makes, :class:`LocalSettings`' plain numbers)."""
    entries = program.layout.entries
    entry = entries.get(kernel)
    if entry is None:
        entry = entries[kernel] = compiled_entry(kernel, args)
    return entry


def regularized_status(code: int) -> str | None:
    """The name of :func:`~.regularize.regularize`'s status ``code`` (``LocalResult.regularized``; ``None`` for
    ``-1``: the phase did not run)."""
    return None if code < 0 else _REGULARIZE_STATUS[int(code)]


def residuals(program: Program, x: np.ndarray, level: int = LEVEL_TASK, *,
              out: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Stacked residuals ``(m,)`` and Jacobians ``(m, n)`` of the blocks of ``level`` at ``x`` (``-1``: levels
    1 and 2), in block order; ``out``: arrays ``(rows,)``, ``(rows, n)`` to write into (a loop's own, made once by
    :func:`residual_arrays`), of which the leading ``m`` rows are returned."""
    program.refresh()
    x = np.ascontiguousarray(x, dtype=float)
    r, J = residual_arrays(program) if out is None else out
    m = residuals_at(x, np.int64(level), program.packed, r, J)
    return r[:m], J[:m]


def residual_arrays(program: Program) -> tuple[np.ndarray, np.ndarray]:
    """Arrays ``(rows,)`` and ``(rows, n)`` holding every block's residual rows (:func:`residuals`' ``out``)."""
    rows = int(program.packed.blocks["rows"].sum())
    return np.empty(rows), np.empty((rows, program.robot.n))


def reaching_is_optimal(program: Program, x: np.ndarray, multipliers: np.ndarray | None) -> bool:
    """Whether ``x`` — on the task, regularizers minimized there — also minimizes the weighted sum locally
    (every task block an exact penalty for the task's multipliers; see :func:`~framework.engine.weighted.
    exact_penalty`). ``True`` without multipliers (nothing was regularized)."""
    if multipliers is None:
        return True
    return bool(exact_penalty(np.ascontiguousarray(x, dtype=float), search_box(program), program.packed.blocks,
                              np.ascontiguousarray(multipliers, dtype=float)))


def minimize_weighted(program: Program, x0: np.ndarray, multipliers: np.ndarray | None,
                      settings: LocalSettings = LocalSettings(), *, deadline: float | None = None,
                      near: float = 1e-6) -> tuple[np.ndarray, int]:
    """The weighted sum of every task and regularizer term minimized from ``x0``, by active sets of task blocks.

    Task blocks are *held* (kept exactly on their targets) or *released* into the objective. From a point on the
    task with its ``multipliers`` every block starts held; without multipliers (any other start) the blocks
    within ``near`` of their targets are held and the others released. Each round releases the held blocks that
    are no exact penalty for their multipliers (leaving them lowers the sum: :func:`~framework.engine.weighted.
    exact_penalty`) and minimizes again on the blocks still held (:func:`~framework.engine.regularize.regularize`
    with those levels), until every held block is an exact penalty. Blocks that pay for themselves stay exactly
    on their targets (no kink to smooth over).

    Returns ``(x, evaluations)``.
    """
    program.refresh()
    box = search_box(program)
    table = program.packed.blocks.copy()  # the held task blocks at level 1, the released ones at level 2
    packed = program.packed._replace(blocks=table)
    x = np.array(x0, dtype=float)
    report = Report(np.zeros(0), np.zeros(len(program.terms)), np.zeros(3, dtype=np.int64))
    newton_settings = settings.newton_settings(_nanoseconds(deadline))
    evaluations = 0
    task = np.flatnonzero(table["level"] == LEVEL_TASK)
    held = np.ones(task.size, dtype=bool) if multipliers is not None else program.task_errors(x) <= near
    lam = None if multipliers is None else np.ascontiguousarray(multipliers, dtype=float)
    for _ in range(2 * task.size + 2):
        if lam is not None:  # release the held blocks that are no exact penalty for their multipliers
            pays = np.empty(int(held.sum()), dtype=bool)
            released_penalties(table, lam, pays)
            new = held.copy()
            new[np.flatnonzero(held)[~pays]] = False
            new |= program.task_errors(x) <= near  # released blocks sitting on their target: hold them exactly
            if np.array_equal(new, held):
                break
            held = new
        table[task] = program.packed.blocks[task]
        table["level"][task[~held]] = LEVEL_REGULARIZER
        lam = np.zeros(int(table["rows"][task[held]].sum()))
        report = report._replace(errors=np.zeros(int(held.sum())))
        newton_phase.regularize(x, box, packed, newton_settings, lam, report)
        evaluations += int(report.stats[1])
    return x, evaluations


def minimize_sum(program: Program, x0: np.ndarray, settings: LocalSettings = LocalSettings(), *,
                 deadline: float | None = None) -> tuple[np.ndarray, str, int]:
    """Damped Newton on the weighted sum of every task and regularizer term from any ``x0``, in the box (norms
    smoothed at zero); see :func:`~framework.engine.weighted.weighted_newton`. Returns ``(x, status, evaluations)``.
    """
    program.refresh()
    x = np.array(x0, dtype=float)
    stats = np.zeros(3, dtype=np.int64)
    code = weighted_newton(x, search_box(program), program.packed, settings.newton_settings(_nanoseconds(deadline)),
                           stats)
    return x, _REGULARIZE_STATUS[int(code)], int(stats[1])


def objective_derivatives_at(program: Program, x: np.ndarray, level: int = -1, *, smoothing: float = 1e-10,
                             curvature: bool = True) -> tuple[float, np.ndarray, np.ndarray]:
    """Weighted value, gradient ``(n,)`` and Hessian ``(n, n)`` of the blocks of ``level`` at ``x`` (``-1``:
    task and regularizers), as the Newton phases see them (the second-order kinematics with ``curvature``)."""
    program.refresh()
    x = np.ascontiguousarray(x, dtype=float)
    return derivatives_at(x, np.int64(level), program.packed, float(smoothing), bool(curvature))
