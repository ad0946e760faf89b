"""Cost terms and their weighted composition.

A :class:`Term` is defined once, by its *blocks* (:class:`~framework.costs.program.Block`): residuals ``r(x)``
evaluated by compiled kernels together with the population forward kinematics, and a ρ that turns a residual
into the term's value (``‖r‖``, ``sin(‖r‖/2)``, ``Σ|r|``, ...). Every consumer reads terms through that one
definition: metaheuristics read the values of a population, the local engine the residuals, their Jacobians
and second-order kinematics, tracking and recordings the per-term values and task errors. Terms compose
readably into an :class:`Objective`::

    f = 1.2 * Position("arm1_ee", t1) + 1.2 * Position("arm2_ee", t2) + 0.1 * Motion("base", q_prev)

Each term has a *level*: ``"task"`` terms (positions, orientations, poses, relative positions) are reached
first and decide success, each held to a tolerance in its own unit (m or rad); ``"regularizer"`` terms (motion)
are minimized without leaving the task; ``"value"`` terms (the joint-limit penalty) only add to the value.
A user term without blocks implements :meth:`Term.value` in numpy; metaheuristics can use it, the local engine
cannot.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from ..errors import TaskError
from ..model.kinematics import FramePoses
from ..model.robot import Robot
from ..validate import all_finite

from .program import Block, Program, unique_labels

if TYPE_CHECKING:  # pragma: no cover
    from ..geometry.collision import CollisionReport
    from ..geometry.exact_check import ExactCheck
    from ..geometry.hulls import HullPair

LEVELS = ("task", "regularizer", "value")


@dataclass
class TermEntry:
    """A task file's ``[[terms]]`` entry as a term class reads it (:meth:`Term.from_entry`).

    Attributes:
        spec: the entry's table (its ``type``, ``weight`` and ``name`` included).
        where: how errors name it (``"[[terms]] #2 (position)"``).
        evaluate: ``(expression, where) -> value``: a number, a list or an expression over the case's variables.
        before: ``(n,)`` the configuration before the case (:attr:`previous`).
        world: the task file's collision shape and obstacles (``.shape``, ``.scene``; built on first use).
        follows: whether the term read :attr:`previous` (along a path, it then measures from the previous
            waypoint's solution).
    """

    spec: Mapping[str, Any]
    where: str
    evaluate: Callable[[Any, str], Any]
    before: np.ndarray
    world: Any
    follows: bool = False

    @property
    def previous(self) -> np.ndarray:
        """``(n,)`` the configuration before the case: motion terms measure from it by default (along a path, the
        previous waypoint's solution)."""
        self.follows = True
        return self.before

    @property
    def name(self) -> str | None:
        """The entry's ``name``, if it gives one."""
        return self.spec.get("name")

    def has(self, key: str) -> bool:
        return key in self.spec

    def value(self, key: str, default: Any = None) -> Any:
        """The value of entry ``key`` (evaluated); ``default`` when the entry has none (``None``: required)."""
        if key not in self.spec:
            if default is None:
                raise TaskError(f"{self.where} needs a {key!r} entry")
            return default
        return self.evaluate(self.spec[key], f"{self.where} {key}")

    def number(self, key: str, default: float | None = None) -> float:
        """Entry ``key`` as one number."""
        value = self.value(key, default)
        if np.ndim(value) != 0:
            raise TaskError(f"{self.where} {key} must be a number; got {self.spec[key]!r}")
        return float(value)

    def text(self, key: str, default: str | None = None) -> str:
        """Entry ``key`` as text (a frame, a group, a norm: not evaluated)."""
        if key not in self.spec:
            if default is None:
                raise TaskError(f"{self.where} needs a {key!r} entry")
            return default
        value = self.spec[key]
        if not isinstance(value, str):
            raise TaskError(f"{self.where} {key} must be text; got {value!r}")
        return value


class Term:
    """One cost term. Subclasses set :attr:`frames`, :attr:`level` and implement :meth:`blocks`.

    Attributes:
        name: label used in reports and recordings.
        frames: frames the term reads.
        level: ``"task"``, ``"regularizer"`` or ``"value"`` (see the module docstring).
        version: incremented whenever a target changes in place (packed problems re-read the term then).
    """

    #: numpy hands ``array * term`` to :meth:`__rmul__` (which takes one weight) instead of broadcasting it
    __array_ufunc__ = None

    name: str = "term"
    frames: tuple[str, ...] = ()
    level: str = "regularizer"
    version: int = 0
    #: Whether the term's blocks are laid out (kinds, rows, sizes; not their parameters' values) by its class and
    #: frames alone: a problem then finds its packed layout without building the blocks (a subclass whose
    #: blocks depend on more must set it back to ``False``).
    fixed_layout: bool = False
    #: Whether :meth:`set_target` moves a target (tracking and batches move it).
    has_target: bool = False
    #: Whether :meth:`collisions` checks something (collision terms).
    checks_collisions: bool = False
    #: The task files' ``type`` of the term (``None``: task files cannot name it) and the keys its entries take
    #: beside ``type``, ``weight`` and ``name`` (:meth:`from_entry` reads them).
    task_type: ClassVar[str | None] = None
    task_keys: ClassVar[tuple[str, ...]] = ()
    #: What the term measures, for reports that sum errors by kind: ``"position"`` [m], ``"orientation"``,
    #: ``"motion"``, or ``None``.
    category: ClassVar[str | None] = None

    @classmethod
    def from_entry(cls, entry: TermEntry) -> Term:
        """The term a task file's ``[[terms]]`` entry of :attr:`task_type` describes."""
        raise TaskError(f"{entry.where}: {cls.__name__} terms cannot be given in task files")

    @property
    def is_task(self) -> bool:
        """Whether the term is a task term (reached first; decides success)."""
        return self.level == "task"

    def validate(self, robot: Robot) -> None:
        """Raise a :class:`~framework.errors.MetaikError` if the term cannot apply to ``robot``."""
        for frame in self.frames:
            robot.frame_id(frame)

    def why_unmet(self, robot: Robot, x: np.ndarray) -> str | None:
        """Why this task term may not be met at all, in a few words, when it knows (a target beyond the robot's
        reach, outside the joint bounds), for a failed solve's :attr:`~framework.solvers.solve.IKResult.reason`;
        ``None`` otherwise (``x``: where the solve ended)."""
        return None

    def blocks(self, robot: Robot) -> tuple[Block, ...] | None:
        """The term's residual blocks for ``robot`` (``None``: no compiled form, :meth:`value` is used)."""
        return None

    def packed(self, robot: Robot) -> tuple[tuple[Block, ...] | None, tuple | None]:
        """``(blocks, signature)`` for ``robot``, remembered until a target changes (packing reads it)."""
        cache = self.__dict__.get("_packed")
        if cache is not None and cache[0] is robot and cache[1] == self.version:
            return cache[2], cache[3]
        blocks = self.blocks(robot)
        signature = None if blocks is None else tuple(b.signature() for b in blocks)
        self._packed = (robot, self.version, blocks, signature)
        return blocks, signature

    def layout_key(self, robot: Robot) -> tuple | None:
        """What decides the term's part of a packed layout: its class and frames with :attr:`fixed_layout`, else
        its blocks' signature (``None``: no blocks)."""
        if self.fixed_layout:
            return (type(self), self.frames)
        return self.packed(robot)[1]

    def value(self, robot: Robot, X: np.ndarray, poses: FramePoses | None = None) -> np.ndarray:
        """Unweighted value of each member of ``X`` ``(pop, n)``: shape ``(pop,)``.

        Terms with blocks are evaluated by the compiled kernel (``poses`` is not needed); a user term without
        blocks overrides this with numpy code reading ``poses`` (the world poses of its :attr:`frames`).
        """
        if self.blocks(robot) is None:
            raise NotImplementedError(f"{type(self).__name__} defines neither blocks() nor value()")
        X = robot.check_population(X, finite=False)
        return Program(robot, Objective(((1.0, self),))).values(X)[:, 0]

    def set_target(self, target) -> None:
        """Move the term's target (terms with a target override this and set :attr:`has_target`)."""
        raise TaskError(f"term {self.name!r} ({type(self).__name__}) has no target to move")

    def copy(self) -> Term:
        """A copy of the term whose target moves on its own (:meth:`set_target` sets new values, never writes into
        shared ones; blocks built for this term are not carried over)."""
        made = copy.copy(self)
        made.__dict__.pop("_packed", None)
        return made

    def target_parameters(self, robot: Robot, targets: Sequence) -> np.ndarray:
        """``(B, p)``: the parameters of the term's blocks (concatenated in block order) for each of ``targets``,
        each validated as :meth:`set_target` validates it; the term itself does not move."""
        probe = self.copy()
        rows = []
        for k, target in enumerate(targets):
            try:
                probe.set_target(target)
            except TaskError as err:
                raise TaskError(f"target {k}: {err}") from None
            rows.append(probe.parameters(robot))
        return np.array(rows, dtype=float).reshape(len(rows), -1)

    def parameters(self, robot: Robot) -> np.ndarray:
        """``(p,)``: the parameters of the term's blocks at its current target, concatenated in block order (the
        term's span of the packed program's parameters; a term with a target may give them without building its
        blocks)."""
        blocks = self.packed(robot)[0] or ()
        return np.concatenate([b.params for b in blocks], dtype=float, casting="unsafe") if blocks else np.zeros(0)

    def exact_check(self) -> ExactCheck | None:
        """The pairs this term keeps apart, as the exact check reads them (``None``: none; the collision terms
        answer with coal on the exact geometry, and a solve is a success only without contacts)."""
        return None

    def collisions(self, robot: Robot, x: np.ndarray, *, margin: bool = False) -> CollisionReport | None:
        """The exact collision check this term stands for at configuration ``x`` ``(n,)`` (``None``: none; see
        :meth:`exact_check`); with ``margin``, pairs closer than the term's margin count as contacts too."""
        check = self.exact_check()
        return None if check is None else check.check(x, margins=margin)

    def hull_pairs(self, robot: Robot) -> tuple[HullPair, ...]:
        """The pairs of convex hulls this term keeps apart (:mod:`framework.geometry.hulls`; the collision terms' tighter
        model for the engine's last steps), none for other terms."""
        return ()

    def loose_hulls(self, robot: Robot) -> bool:
        """Whether any of :meth:`hull_pairs` is loose (its rows' spheres are fatter than its hulls)."""
        return False

    def frame_target(self) -> tuple[str, np.ndarray | None, np.ndarray | None] | None:
        """``(frame, position (3,) [m] or None, rotation (3, 3) or None)`` when the term is met exactly where that
        frame has that position and / or rotation (position, orientation and pose terms: the closed form of an arm
        solves them), else ``None``."""
        return None

    def target_points(self, robot: Robot, x: np.ndarray) -> dict[str, np.ndarray]:
        """Frame -> the world point ``(3,)`` [m] it should reach at configuration ``x`` (for drawing targets)."""
        return {}

    def _touch(self) -> None:
        self.version = self.version + 1

    # Composition
    def __mul__(self, weight: float) -> Objective:
        return Objective(((check_weight(weight), self),))

    __rmul__ = __mul__

    def __add__(self, other: Term | Objective) -> Objective:
        return Objective(((1.0, self),)) + other

    def __radd__(self, other):
        if other == 0:  # sum([...]) starts from 0
            return Objective(((1.0, self),))
        return NotImplemented


def check_weight(weight: float) -> float:
    """``weight`` as a float; raises :class:`TaskError` unless it is a finite number >= 0."""
    if type(weight) is float and 0.0 <= weight < math.inf:  # the common case, without a conversion
        return weight
    try:
        w = float(weight)
    except (TypeError, ValueError):
        raise TaskError(f"a cost weight must be a finite number >= 0; got {weight!r}") from None
    if not math.isfinite(w) or w < 0:
        raise TaskError(f"a cost weight must be a finite number >= 0; got {weight!r}")
    return w


@dataclass(frozen=True)
class Objective:
    """A weighted sum of terms: ``f(X) = Σ wᵢ termᵢ(X)``."""

    #: numpy hands ``array * objective`` to :meth:`__rmul__` (which takes one weight) instead of broadcasting it
    __array_ufunc__ = None

    terms: tuple[tuple[float, Term], ...]

    def __post_init__(self) -> None:
        pairs = []
        for pair in self.terms:
            if not (isinstance(pair, tuple) and len(pair) == 2 and isinstance(pair[1], Term)):
                raise TaskError(f"an objective is (weight, term) pairs; got {pair!r}")
            pairs.append((check_weight(pair[0]), pair[1]))
        object.__setattr__(self, "terms", tuple(pairs))

    @classmethod
    def of(cls, objective: Term | Objective | Iterable[tuple[float, Term]]) -> Objective:
        """``objective`` as an :class:`Objective`: a term (weight 1), an objective, or ``(weight, term)`` pairs."""
        if isinstance(objective, Term):  # one pair, nothing to check: made without __post_init__'s checks
            made = object.__new__(cls)
            object.__setattr__(made, "terms", ((1.0, objective),))
            return made
        if isinstance(objective, Objective):
            return objective
        try:
            return cls(tuple(tuple(pair) if isinstance(pair, list) else pair for pair in objective))
        except TypeError:
            raise TaskError(f"an objective is a term or (weight, term) pairs; got {objective!r}") from None

    def __add__(self, other: Term | Objective) -> Objective:
        if isinstance(other, Term):
            other = Objective(((1.0, other),))
        if not isinstance(other, Objective):
            return NotImplemented
        return Objective(self.terms + other.terms)

    def __radd__(self, other):
        if other == 0:
            return self
        return NotImplemented

    def __mul__(self, weight: float) -> Objective:
        w = check_weight(weight)
        return Objective(tuple((w * v, t) for v, t in self.terms))

    __rmul__ = __mul__

    def __iter__(self) -> Iterator[tuple[float, Term]]:
        return iter(self.terms)

    def __len__(self) -> int:
        return len(self.terms)

    @property
    def names(self) -> tuple[str, ...]:
        """Unique labels of the terms (a repeated name gets ``#2``, ``#3``, ...)."""
        return unique_labels(term.name for _, term in self.terms)

    @property
    def frames(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(f for _, t in self.terms for f in t.frames))


def finite_rows(values, shape: tuple[int, ...], what: str) -> np.ndarray:
    """``values`` as a float ``(B, *shape)`` array of finite numbers; raises :class:`TaskError` naming ``what``
    and the first bad item."""
    try:
        array = np.array(values, dtype=float)
    except (TypeError, ValueError):
        raise TaskError(f"{what} must be numbers of shape (B, {', '.join(map(str, shape))})") from None
    if array.ndim != len(shape) + 1 or array.shape[1:] != shape:
        raise TaskError(f"{what} must have shape (B, {', '.join(map(str, shape))}); got {array.shape}")
    bad = np.flatnonzero(~np.isfinite(array.reshape(array.shape[0], -1)).all(axis=1))
    if bad.size:
        raise TaskError(f"{what}: item {bad[0]} holds NaN or inf")
    return array


def as_vector(value: Sequence[float] | np.ndarray, size: int, what: str | Callable[[], str]) -> np.ndarray:
    """A finite float vector of length ``size`` (a new array); raises :class:`TaskError` naming ``what`` (a
    string, or a callable making it only when there is an error)."""
    try:
        v = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise TaskError(f"{_name(what)} must be {size} numbers; got {value!r}") from None
    if v.shape != (size,):
        raise TaskError(f"{_name(what)} must have shape ({size},); got {v.shape}")
    if not all_finite(v):
        raise TaskError(f"{_name(what)} holds NaN or inf: {v.tolist()}")
    return v


def _name(what: str | Callable[[], str]) -> str:
    return what() if callable(what) else what
