"""The interface every IK solver implements: ``solver.solve(problem, request) -> Outcome``.

:func:`framework.solve` builds a :class:`Request` from its arguments, looks the solver up by name
(:func:`~framework.solvers.registry.ik_solver`) and turns the :class:`Outcome` into an
:class:`~framework.solvers.solve.IKResult`. A solver declares what it can take as class attributes (a warm start, a
search distribution carried along a path, Jacobians), so callers never branch on solver names. Options are a
frozen dataclass per solver (:attr:`IKSolver.Options`): typed, documented, with defaults; unknown names are
an error.
"""

from __future__ import annotations

import dataclasses
import time
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, NamedTuple

import numpy as np

from ..errors import SolverError

if TYPE_CHECKING:  # pragma: no cover
    from ..engine import LocalSettings
    from ..costs.problem import Problem

Callback = Callable[[int, float, np.ndarray], "bool | None"]


class Request(NamedTuple):
    """What one solve asks for (built by :func:`framework.solve`; a named tuple: it is built once per solve).

    Attributes:
        rng: the generator (created on first use, so solves that need no randomness do not pay for it).
        seed: the integer the local engine's restart stream starts from (:func:`~framework.engine.draws.stream`).
        tolerance: every position-like task term within this [m]; angle_tolerance: orientations [rad].
        max_iterations: the solver's iteration budget (``None``: its own default).
        population: candidates per iteration (metaheuristics; the hybrid's global phase).
        initial: ``(k, n)`` warm starts, or ``None``.
        deadline: ``time.monotonic()`` at which to stop, or ``None``.
        stop_at_tolerance: stop as soon as the task is within tolerance (metaheuristics run their budget).
        callback: ``callback(iteration, best_f, best_x)`` after each iteration; True stops.
        progress: print progress lines.
    """

    rng: Callable[[], np.random.Generator]
    seed: int
    tolerance: float
    angle_tolerance: float
    max_iterations: int | None = None
    population: int = 30
    initial: np.ndarray | None = None
    deadline: float | None = None
    stop_at_tolerance: bool = False
    callback: Callback | None = None
    progress: bool = False

    def time_left(self) -> float:
        return np.inf if self.deadline is None else self.deadline - time.monotonic()


class Outcome(NamedTuple):
    """What a solver found: the configuration ``x`` ``(n,)`` and how it got there (``history``: the best cost
    after each iteration, ``None`` for just the final cost; ``task_errors`` and ``values``: each task block's
    error and each term's value at ``x``, when the solver computed them on the way; ``collisions``: the exact
    check at ``x`` likewise)."""

    x: np.ndarray
    stop_reason: str
    iterations: int
    evaluations: int
    history: np.ndarray | None = None
    settings: dict[str, Any] = {}
    state: dict[str, Any] = {}
    task_errors: np.ndarray | None = None
    values: np.ndarray | None = None
    collisions: Any = None  # the exact collision check at x, when the solver made it (a CollisionReport)


class BatchPlan(NamedTuple):
    """How a solve begins when its beginning is the local engine alone, so :func:`framework.solve_batch` can run
    it compiled over a whole batch: the first start ``x0 (n,)``, the settings of the descent from it (with the
    random restarts that follow it when ``first.restarts``), and whether the solver goes on when the engine misses
    the task (``escalates``: such items are solved by the solver itself; otherwise the engine's best miss is the
    answer). ``report``: the settings a result the engine phase answers reports (:attr:`IKResult.settings`), but
    its restart count and its regularizer phase's status (``restart_count``, ``regularized``: per item)."""

    x0: np.ndarray
    first: LocalSettings
    escalates: bool = True
    report: Mapping[str, Any] = {}
    #: the first descent is on the problem without its collision terms, and an item is finished when coal finds
    #: its answer clear by the terms' margins (the solver's own first step for a loose sphere cover)
    clear_first: bool = False
    #: when the first descent misses the task: a descent from a start drawn from the item's stream with these
    #: settings (its restarts), as the solver's next step (none: the solver itself takes the item)
    then: LocalSettings | None = None


@dataclass(frozen=True)
class NoOptions:
    """A solver without options."""


def _rehearsal_rng() -> np.random.Generator:
    """The generator of :meth:`IKSolver.prepare`'s rehearsal."""
    return np.random.default_rng(0)


#: How far the rehearsal's deadline lies [s]: never reached, only there to take the budgeted path.
_REHEARSAL_SECONDS = 3600.0


class IKSolver(ABC):
    """One IK method behind one interface.

    Class attributes (capabilities, read by tracking and the CLI instead of solver names):
        name: registry name; reference: where the method comes from; kind: what it is, in a few words (the
            solver table of ``metaik solvers``).
        Options: its options dataclass.
        uses_jacobians: a local method (tracking gives it a Jacobian predictor by default).
        carries_distribution: takes its previous solve's :attr:`Outcome.state` (a search distribution) along a
            path (CMA-ES).
        step_option: name of the option setting its initial search spread around a warm start (``"sigma0"``),
            or ``None``.
    """

    name: ClassVar[str] = ""
    reference: ClassVar[str] = ""
    kind: ClassVar[str] = ""
    Options: ClassVar[type] = NoOptions
    uses_jacobians: ClassVar[bool] = False
    carries_distribution: ClassVar[bool] = False
    step_option: ClassVar[str | None] = None

    def __init__(self, options: Mapping[str, Any] | None = None):
        self.options = parse_options(self.Options, options, self.name)

    @classmethod
    def instance(cls, options: Mapping[str, Any] | None = None) -> IKSolver:
        """The instance of this solver for ``options``, made once per options (of hashable values; others make a
        new one): a solver keeps no state between solves, only tables derived from its options, so a loop that
        passes the same options to every solve reuses one instead of validating them again (~12 µs a call, a
        third of a pose solve). The class keeps its instances (at most ``_KEPT``; cleared beyond)."""
        key = _options_key(options)
        kept = cls.__dict__.get("_instances")
        if kept is None:
            kept = {}
            setattr(cls, "_instances", kept)  # this class's own table (not a parent's)
        made = kept.get(key) if key is not None else None
        if made is None:
            made = cls(options or None)
            if key is not None:
                if len(kept) >= _KEPT:
                    kept.clear()
                kept[key] = made
        return made

    @abstractmethod
    def solve(self, problem: Problem, request: Request) -> Outcome:
        """Solve ``problem`` as ``request`` asks."""

    def prepare(self, problem: Problem) -> None:
        """Load the compiled code this solver runs on ``problem`` before a time budget starts (``solve`` calls it
        first): numba loads it from its disk cache, or compiles it, on a process's first use — up to seconds,
        which a 5 ms budget would not survive. The default rehearses: one iteration of the solver with a distant
        deadline (the path a budgeted solve takes), once per solver and problem layout."""
        entries = problem.program.layout.entries
        key = (IKSolver.prepare, self.name)
        if key not in entries:
            rehearsal = Request(_rehearsal_rng, 0, 1e-6, 1e-6, max_iterations=1,
                                deadline=time.monotonic() + _REHEARSAL_SECONDS)
            self.solve(problem, rehearsal)
            entries[key] = None

    def batch_plan(self, problem: Problem, request: Request) -> BatchPlan | None:
        """The engine-only beginning of :meth:`solve` for ``request``, or ``None`` (the default: a batch is solved
        one item at a time through :meth:`solve`)."""
        return None

    @classmethod
    def defaults(cls) -> dict[str, Any]:
        """Option name -> default value."""
        return {f.name: f.default for f in dataclasses.fields(cls.Options)}

    @property
    def option_names(self) -> frozenset[str]:
        """The names of the solver's options."""
        return frozenset(self.defaults())


#: The most instances :meth:`IKSolver.instance` keeps per solver class.
_KEPT = 256


def _options_key(options: Any) -> tuple | None:
    """The key of ``options`` among a solver's instances, ``None`` when they cannot be one (an unhashable value).
    A value's type is part of it: ``{"stall": 6.0}`` is not ``{"stall": 6}`` (which one is valid is the options'
    own check)."""
    if not options:
        return ()
    try:
        if isinstance(options, Mapping):
            key = tuple(sorted((k, type(v), v) for k, v in options.items()))
        else:
            key = (type(options), options)
        hash(key)
    except TypeError:
        return None
    return key


def parse_options(options_type: type, options: Mapping[str, Any] | None, solver: str):
    """An ``options_type`` instance from a mapping; unknown names raise :class:`SolverError` listing the known."""
    if options is None:
        return options_type()
    if isinstance(options, options_type):
        return options
    if not isinstance(options, Mapping):
        raise SolverError(f"options of solver {solver!r} must be a table of names and values; got {options!r}")
    known = {f.name for f in dataclasses.fields(options_type)}
    unknown = sorted(set(options) - known)
    if unknown:
        raise SolverError(f"unknown option(s) {unknown} for solver {solver!r}; its options are {sorted(known)}")
    return options_type(**options)


