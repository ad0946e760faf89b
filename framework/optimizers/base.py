"""The robot-independent optimizer layer: search box, bounds repair, result record, ask/tell base class
and the one shared optimization loop :func:`minimize`.

A solver minimizes a *population cost* ``cost(X) -> F`` with ``X`` of shape ``(pop, n)`` (float64) and
``F`` of shape ``(pop,)``. It knows nothing about robots. Every algorithm is an :class:`Algorithm`
(ask/tell, like pycma's ``es.ask()`` / ``es.tell(X, F)``); :func:`minimize` owns everything the
algorithms share: evaluation counting, bounds repair, best-so-far bookkeeping, history, stopping rules,
``KeyboardInterrupt`` handling and timing.
"""

from __future__ import annotations

import sys
import time
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from ..compiled.native import compiled
from ..errors import LimitsError, SolverError
from ..interrupts import graceful_interrupt
from ..validate import positive_int
from .registry import get_solver

BOUNDS_MODES = ("resample", "clip", "none")
STOP_REASONS = ("max_iterations", "f_target", "stagnation", "max_evaluations", "callback", "interrupted")

#: Relative decrease of the best cost that counts as an improvement for the stagnation rule.
IMPROVEMENT_RTOL = 1e-15

PopulationCost = Callable[[np.ndarray], np.ndarray]
Callback = Callable[[int, float, np.ndarray], "bool | None"]

#: Largest population a solver accepts (its work arrays are population x n floats, several of them).
MAX_POPULATION = 100_000


@dataclass(frozen=True)
class Box:
    """Axis-aligned search box ``lower <= x <= upper``.

    Attributes:
        lower: Lower bounds, shape ``(n,)``, finite.
        upper: Upper bounds, shape ``(n,)``, finite, ``upper > lower`` elementwise.
    """

    lower: np.ndarray
    upper: np.ndarray

    def __post_init__(self) -> None:
        lower = np.array(self.lower, dtype=float).reshape(-1) if np.ndim(self.lower) <= 1 else None
        upper = np.array(self.upper, dtype=float).reshape(-1) if np.ndim(self.upper) <= 1 else None
        if lower is None or upper is None or lower.shape != upper.shape or lower.size == 0:
            raise LimitsError(
                f"Box bounds must be two 1-D arrays of the same non-zero length, got shapes "
                f"{np.shape(self.lower)} and {np.shape(self.upper)}."
            )
        bad = ~(np.isfinite(lower) & np.isfinite(upper))
        if bad.any():
            raise LimitsError(
                f"Box bounds must be finite; non-finite at indices {np.flatnonzero(bad).tolist()}."
            )
        inverted = ~(lower < upper)
        if inverted.any():
            idx = np.flatnonzero(inverted).tolist()
            raise LimitsError(
                f"Box needs lower < upper; violated at indices {idx} "
                f"(lower={lower[idx].tolist()}, upper={upper[idx].tolist()})."
            )
        lower.flags.writeable = False
        upper.flags.writeable = False
        object.__setattr__(self, "lower", lower)
        object.__setattr__(self, "upper", upper)

    @property
    def n(self) -> int:
        """Dimension of the search space."""
        return self.lower.size

    @property
    def width(self) -> np.ndarray:
        """``upper - lower``, shape ``(n,)``."""
        return self.upper - self.lower

    def sample(self, rng: np.random.Generator, count: int) -> np.ndarray:
        """Uniform samples in the box, shape ``(count, n)``."""
        return self.lower + rng.random((count, self.n)) * self.width

    def contains(self, X: np.ndarray) -> np.ndarray:
        """Row-wise membership of ``X`` (pop, n) in the box; NaN rows are outside. Shape ``(pop,)``."""
        return np.all((X >= self.lower) & (X <= self.upper), axis=-1)


def repair(X: np.ndarray, box: Box, rng: np.random.Generator, mode: str) -> np.ndarray:
    """Bring candidates back into the box.

    Args:
        X: Candidates, shape ``(pop, n)``. Not modified.
        box: The search box.
        rng: Random generator (used by ``"resample"`` only).
        mode: ``"resample"``: every row with a coordinate outside the box (or a non-finite one) is
            re-sampled *as a whole row* uniformly in the box (paper 000, eq. 12, recalculates the
            infeasible member; re-sampling the whole row keeps the new member unbiased by the old one).
            ``"clip"``: coordinates are clipped to the box (non-finite rows are re-sampled).
            ``"none"``: ``X`` is returned unchanged; a penalty term in the cost handles violations.

    Returns:
        The repaired candidates, shape ``(pop, n)``; a new array unless ``mode == "none"``.
    """
    if mode == "none":
        return X
    if mode == "resample":
        bad = _outside(X, box.lower, box.upper)
        if not bad.any():
            return X.copy()
        out = X.copy()
    elif mode == "clip":
        out = np.clip(X, box.lower, box.upper)
        bad = ~np.all(np.isfinite(X), axis=1)
    else:
        raise SolverError(f"Unknown bounds mode {mode!r}; use one of {list(BOUNDS_MODES)}.")
    if bad.any():
        out[bad] = box.sample(rng, int(bad.sum()))
    return out


@dataclass(frozen=True)
class OptimizeResult:
    """What a solver run produced.

    Attributes:
        x: Best candidate found, shape ``(n,)``.
        f: Its cost (``inf`` if nothing was evaluated).
        iterations: Completed iterations (generations).
        evaluations: Number of evaluated candidates (rows passed to the cost).
        history: Best-so-far cost after each iteration, shape ``(iterations,)``.
        stop_reason: One of ``"max_iterations"``, ``"f_target"``, ``"stagnation"``,
            ``"max_evaluations"``, ``"callback"``, ``"interrupted"``.
        wall_time: Seconds spent in :func:`minimize`.
        solver: Registered solver name.
        settings: Every setting actually used (loop settings and algorithm parameters).
        state: What a following run on a similar problem may start from (see :attr:`Algorithm.state`).
    """

    x: np.ndarray
    f: float
    iterations: int
    evaluations: int
    history: np.ndarray
    stop_reason: str
    wall_time: float
    solver: str
    settings: dict[str, Any] = field(default_factory=dict)
    state: dict[str, Any] = field(default_factory=dict, repr=False)


class Algorithm(ABC):
    """Base class of every optimizer: the ask/tell protocol plus option handling.

    Subclasses declare ``DEFAULTS`` (parameter name -> default value, documented in the subclass
    docstring); user ``options`` override them by name and unknown names raise :class:`SolverError`.

    An *iteration* (generation) may consist of several ask/tell batches (e.g. the initial population,
    or the two phases of cuckoo search); :attr:`iteration_complete` tells the loop when one is done.

    Args:
        n: Dimension of the search space.
        box: Search box.
        population: Candidates per generation (see each algorithm for its exact use).
        rng: The only source of randomness.
        options: Parameter overrides, or ``None``.
        initial: ``None`` or starting points, shape ``(k, n)``: they seed the first population
            (population-based methods) or the mean (CMA-ES).
        max_iterations: Iteration budget, used by algorithms whose parameters follow a schedule.
    """

    name: ClassVar[str] = ""
    DEFAULTS: ClassVar[dict[str, Any]] = {}
    MIN_POPULATION: ClassVar[int] = 1

    def __init__(
        self,
        n: int,
        box: Box,
        population: int,
        rng: np.random.Generator,
        options: Mapping[str, Any] | None = None,
        initial: np.ndarray | None = None,
        *,
        max_iterations: int = 1000,
    ) -> None:
        if box.n != n:
            raise LimitsError(f"Box has dimension {box.n}, the problem has {n}.")
        if int(population) != population or not self.MIN_POPULATION <= population <= MAX_POPULATION:
            raise SolverError(
                f"{self.name}: population must be an integer in [{self.MIN_POPULATION}, {MAX_POPULATION:,}], "
                f"got {population}."
            )
        self.n = n
        self.box = box
        self.population = int(population)
        self.rng = rng
        self.max_iterations = max(1, int(max_iterations))
        self.options = resolve_options(self.name, self.DEFAULTS, options)
        self.initial = check_initial(initial, n)
        self.generation = 0  #: completed generations
        self._best_x = np.full(n, np.nan)
        self._best_f = np.inf
        self.setup()

    def setup(self) -> None:
        """Algorithm-specific initialization, called at the end of ``__init__`` (options are resolved)."""

    @property
    def progress(self) -> float:
        """Fraction of the iteration budget used, in ``[0, 1]`` (drives parameter schedules)."""
        return min(1.0, self.generation / self.max_iterations)

    @property
    def iteration_complete(self) -> bool:
        """True when the last :meth:`tell` completed a generation."""
        return True

    @property
    def best(self) -> tuple[np.ndarray, float]:
        """Best candidate told so far and its cost: ``(x (n,), f)``."""
        return self._best_x.copy(), self._best_f

    @property
    def settings(self) -> dict[str, Any]:
        """The parameters in use."""
        return dict(self.options)

    @property
    def state(self) -> dict[str, Any]:
        """What a following run on a similar problem may start from, as options of the same solver (e.g. the
        adapted covariance of CMA-ES, for the next waypoint of a trajectory); empty for most solvers."""
        return {}

    @abstractmethod
    def ask(self) -> np.ndarray:
        """Candidates to evaluate next, shape ``(k, n)``."""

    def tell(self, X: np.ndarray, F: np.ndarray) -> None:
        """Report the costs ``F`` (shape ``(k,)``) of the evaluated (possibly repaired) candidates ``X``."""
        i = int(np.argmin(F))
        if F[i] < self._best_f:
            self._best_f = float(F[i])
            self._best_x = X[i].copy()
        self._tell(X, F)

    @abstractmethod
    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        """Algorithm-specific update."""

    def schedule(self, start: float, end: float) -> float:
        """Linear schedule from ``start`` (first generation) to ``end`` (last generation)."""
        return start + (end - start) * self.progress


def resolve_options(
    name: str, defaults: Mapping[str, Any], options: Mapping[str, Any] | None
) -> dict[str, Any]:
    """Merge user ``options`` into ``defaults``; unknown names raise :class:`SolverError`."""
    merged = dict(defaults)
    if options:
        unknown = sorted(set(options) - set(defaults))
        if unknown:
            raise SolverError(
                f"Unknown option(s) {unknown} for solver {name!r}; its options are {sorted(defaults)}."
            )
        for key, value in options.items():
            _check_option_kind(name, key, defaults[key], value)
        merged.update(options)
    return merged


def _check_option_kind(solver: str, key: str, default: Any, value: Any) -> None:
    """An option's value of the kind its default is (a number for a number, true / false for a flag, text for
    text; an option whose default is ``None`` or a table is checked by its algorithm)."""
    def number(v: Any) -> bool:
        return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, (bool, np.bool_))

    if isinstance(default, bool):
        ok, kind = isinstance(value, (bool, np.bool_)), "true or false"
    elif number(default):
        ok, kind = number(value) and bool(np.isfinite(value)), "a finite number"
    elif isinstance(default, str):
        ok, kind = isinstance(value, str), "text"
    else:
        return
    if not ok:
        raise SolverError(f"option {key!r} of solver {solver!r} must be {kind}; got {value!r}")


def check_initial(initial: np.ndarray | None, n: int) -> np.ndarray | None:
    """Validate warm-start points: ``None``, shape ``(n,)`` or ``(k, n)``; returns ``(k, n)`` or ``None``."""
    if initial is None:
        return None
    X0 = np.array(initial, dtype=float)
    if X0.ndim == 1:
        X0 = X0[None, :]
    if X0.ndim != 2 or X0.shape[1] != n or X0.shape[0] == 0 or not np.all(np.isfinite(X0)):
        raise SolverError(
            f"initial must be finite with shape (k, {n}) or ({n},), got shape {np.shape(initial)}."
        )
    return X0


def _as_box(box: Box | tuple[np.ndarray, np.ndarray]) -> Box:
    if isinstance(box, Box):
        return box
    if not isinstance(box, (tuple, list)) or len(box) != 2:
        raise LimitsError(f"the search box must be a Box or a (lower, upper) pair; got {box!r}")
    return Box(*box)


def _evaluate(cost: PopulationCost, X: np.ndarray) -> np.ndarray:
    """Call the population cost and check its output; NaN costs become ``+inf``."""
    F = np.asarray(cost(X), dtype=float)
    if F.shape != (X.shape[0],):
        raise SolverError(
            f"The cost must return shape ({X.shape[0]},) for X of shape {X.shape}, got {F.shape}."
        )
    nan = np.isnan(F)
    return np.where(nan, np.inf, F) if nan.any() else F


@compiled
def _outside(X, lower, upper):
    """``(pop,)`` True for rows of ``X`` with a coordinate outside ``[lower, upper]`` or not finite."""
    bad = np.zeros(X.shape[0], dtype=np.bool_)
    for k in range(X.shape[0]):
        for i in range(X.shape[1]):
            v = X[k, i]
            if not (lower[i] <= v <= upper[i]):
                bad[k] = True
                break
    return bad


def _improved(previous_f: float, f: float) -> bool:
    """True if ``f`` improves on ``previous_f`` by more than ``IMPROVEMENT_RTOL`` relative."""
    if not f < previous_f:
        return False
    return bool(np.isinf(previous_f) or previous_f - f > IMPROVEMENT_RTOL * abs(previous_f))


def _print_progress(iteration: int, max_iterations: int, f: float, evaluations: int) -> None:
    print(
        f"[metaik] iteration {iteration}/{max_iterations}  best f = {f:.6e}  evaluations = {evaluations}",
        file=sys.stderr,
    )


@dataclass
class _Search:
    """The best candidate so far and the evaluations spent (:func:`minimize`'s running state)."""

    best_x: np.ndarray
    best_f: float = np.inf
    evaluations: int = 0


def _generation(algorithm: Algorithm, cost: PopulationCost, box: Box, rng: np.random.Generator, bounds: str,
                search: _Search, stop: Callable[[], bool]) -> None:
    """One generation: ask, repair, evaluate and tell until the algorithm completes it or ``stop()`` says so after
    a batch; ``search`` keeps the best candidate and counts the evaluations."""
    while True:
        X = repair(np.asarray(algorithm.ask(), dtype=float), box, rng, bounds)
        F = _evaluate(cost, X)
        search.evaluations += X.shape[0]
        i = int(np.argmin(F))
        if F[i] < search.best_f:
            search.best_f, search.best_x = float(F[i]), X[i].copy()
        algorithm.tell(X, F)
        if algorithm.iteration_complete or stop():
            return


def minimize(
    cost: PopulationCost,
    box: Box | tuple[np.ndarray, np.ndarray],
    *,
    solver: str = "cmaes",
    rng: np.random.Generator,
    max_iterations: int = 1000,
    population: int = 30,
    initial: np.ndarray | None = None,
    f_target: float | None = None,
    max_evaluations: int | None = None,
    stagnation: int | None = None,
    bounds: str = "resample",
    options: Mapping[str, Any] | None = None,
    callback: Callback | None = None,
    progress: bool = False,
) -> OptimizeResult:
    """Minimize a population cost over a box with a registered solver.

    Args:
        cost: ``cost(X) -> F``, ``X`` shape ``(k, n)``, ``F`` shape ``(k,)``. NaN costs count as ``+inf``.
        box: Search box (or a ``(lower, upper)`` pair).
        solver: Registered solver name (see :func:`~framework.solvers.registry.available_solvers`).
        rng: The only randomness; the same seed gives a bitwise identical ``x``, ``f`` and ``history``.
        max_iterations: Generation budget.
        population: Population size (candidates per generation for most solvers).
        initial: Warm-start points, shape ``(k, n)`` or ``(n,)``.
        f_target: Stop as soon as the best cost is ``<= f_target``.
        max_evaluations: Stop once this many candidates were evaluated (checked after each batch, so
            the count may exceed it by less than one batch).
        stagnation: Stop after this many consecutive iterations without a relative improvement of the
            best cost larger than ``1e-15``; ``None`` disables the rule.
        bounds: ``"resample"``, ``"clip"`` or ``"none"``, see :func:`repair`.
        options: Algorithm parameters overriding its ``DEFAULTS``.
        callback: ``callback(iteration, best_f, best_x)`` after each iteration; returning True stops.
        progress: Print a short progress line to stderr about 20 times per run.

    Returns:
        An :class:`OptimizeResult`. Problems whose optimum is out of reach just use up the budget.

    Raises:
        SolverError: unknown solver, unknown option, bad settings, or a cost returning a wrong shape.
        LimitsError: invalid box.
    """

    start = time.perf_counter()
    box = _as_box(box)
    if not isinstance(rng, np.random.Generator):
        raise SolverError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}.")
    if bounds not in BOUNDS_MODES:
        raise SolverError(f"Unknown bounds mode {bounds!r}; use one of {list(BOUNDS_MODES)}.")
    max_iterations = positive_int(max_iterations, "max_iterations")
    stagnation = None if stagnation is None else positive_int(stagnation, "stagnation")
    max_evaluations = None if max_evaluations is None else positive_int(max_evaluations, "max_evaluations")
    algorithm = get_solver(solver)(
        box.n, box, population, rng, options, initial, max_iterations=int(max_iterations)
    )

    initial_x = algorithm.initial[0] if algorithm.initial is not None else 0.5 * (box.lower + box.upper)
    search = _Search(initial_x.copy())
    history: list[float] = []
    stale = 0
    stop_reason = "max_iterations"
    report_every = max(1, int(max_iterations) // 20)
    with graceful_interrupt() as interrupt:  # Ctrl-C is checked after each batch: pycma swallows exceptions

        def budget_spent() -> bool:
            return max_evaluations is not None and search.evaluations >= max_evaluations

        def reached() -> bool:
            return f_target is not None and search.best_f <= f_target

        try:
            for iteration in range(1, int(max_iterations) + 1):
                previous_f = search.best_f
                _generation(algorithm, cost, box, rng, bounds, search,
                            lambda: budget_spent() or reached() or interrupt.requested)
                history.append(search.best_f)
                stale = 0 if _improved(previous_f, search.best_f) else stale + 1
                if progress and (iteration % report_every == 0 or iteration == 1):
                    _print_progress(iteration, int(max_iterations), search.best_f, search.evaluations)
                reason = ("interrupted" if interrupt.requested else "f_target" if reached()
                          else "max_evaluations" if budget_spent()
                          else "stagnation" if stagnation is not None and stale >= stagnation
                          else "callback" if callback is not None
                          and callback(iteration, search.best_f, search.best_x.copy()) else None)
                if reason is not None:
                    stop_reason = reason
                    break
        except KeyboardInterrupt:  # the second Ctrl-C
            stop_reason = "interrupted"
    settings = {"solver": solver, "population": algorithm.population, "max_iterations": int(max_iterations),
                "bounds": bounds, "f_target": f_target, "max_evaluations": max_evaluations, "stagnation": stagnation,
                **algorithm.settings}
    return OptimizeResult(x=search.best_x, f=search.best_f, iterations=len(history), evaluations=search.evaluations,
                          history=np.array(history, dtype=float), stop_reason=stop_reason,
                          wall_time=time.perf_counter() - start, solver=solver, settings=settings,
                          state=algorithm.state)
