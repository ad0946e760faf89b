"""A weighted objective packed for the compiled kernels: the kinematic tables of its frames and its blocks.

:class:`Program` is built once per problem. Targets can change afterwards without rebuilding it: a term whose
target was set in place (``term.set_target(...)``) is re-packed on the next :meth:`Program.refresh`, which
costs a few microseconds, so tracking moves one problem along a path instead of building one per waypoint.
Terms without blocks (user terms written in numpy) are evaluated by their own ``value`` beside the kernel.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from functools import cached_property
from operator import attrgetter
from typing import TYPE_CHECKING, NamedTuple, Protocol, TypeVar

import numpy as np

from ..errors import ConfigurationError
from ..model.joints import JointKind
from ..model.robot import Robot
from ..validate import all_finite, float_copy
from . import blocks as B
from .kernels import population_cost, population_values, task_errors_at, values_and_errors

#: What :meth:`Program.memo` keeps.
T = TypeVar("T")

if TYPE_CHECKING:  # pragma: no cover
    from .kinds import BlockKind

if TYPE_CHECKING:  # pragma: no cover
    from ..geometry.hulls import HullPair


class Term(Protocol):
    """What a program reads of a term (:class:`~framework.costs.base.Term`, which imports this module)."""

    name: str
    level: str
    frames: tuple[str, ...]
    version: int

    def layout_key(self, robot: Robot) -> tuple: ...
    def packed(self, robot: Robot) -> tuple[tuple[Block, ...] | None, tuple | None]: ...
    def parameters(self, robot: Robot) -> np.ndarray: ...
    def value(self, robot: Robot, X: np.ndarray, poses=None) -> np.ndarray: ...


class Objective(Protocol):
    """What a program reads of an objective (:class:`~framework.costs.base.Objective`): its weighted terms."""

    terms: tuple[tuple[float, Term], ...]

_VERSION = attrgetter("version")
_LEVELS = {"value": B.LEVEL_VALUE, "task": B.LEVEL_TASK, "regularizer": B.LEVEL_REGULARIZER}


class Block(NamedTuple):
    """One residual block of a term (see :mod:`framework.costs.blocks`).

    Attributes:
        kind: what it computes (:class:`~framework.costs.kinds.BlockKind`, defined with its term).
        rho: how the residual becomes the value: ``NORM``, ``HALFSIN``, ``L1`` or ``SQUARED``.
        rows: residual size.
        frames: the frames it reads (``a`` then ``b``; a kind with ``frame_indices`` reads them all).
        params: its target parameters (position, row-major rotation, offset, previous values, limits).
        indices: its coordinates (a kind with ``unit_rows``); frames of a kind with ``frame_indices`` are listed
            by ``frames`` instead.
        scale: factor of ρ (``1 / (n π)`` for paper 002's normalized L1 motion, δ for the limit penalty).
        tolerance: ``TOL_LINEAR`` [m], ``TOL_ANGULAR`` [rad] or ``TOL_NONE``: which tolerance ``‖r‖`` is held to.
        scratch: the float entries its kernel's scratch needs.
    """

    kind: BlockKind
    rho: int
    rows: int
    frames: tuple[str, ...] = ()
    params: np.ndarray = np.zeros(0)
    indices: np.ndarray | None = None
    scale: float = 1.0
    tolerance: int = B.TOL_NONE
    scratch: int = 18

    def signature(self) -> tuple:
        """Everything but the parameters' values: blocks of equal signatures pack into the same layout."""
        indices = None if self.indices is None else self.indices.tobytes()
        return (self.kind, self.rho, self.rows, self.frames, self.scale, self.tolerance, len(self.params), indices,
                self.scratch)


def unique_labels(names: Iterable[str]) -> tuple[str, ...]:
    """``names`` made unique in order: a repeated name gets ``#2``, ``#3``, ..."""
    seen: dict[str, int] = {}
    out = []
    for name in names:
        seen[name] = seen.get(name, 0) + 1
        out.append(name if seen[name] == 1 else f"{name}#{seen[name]}")
    return tuple(out)


def _kind(level: int, blocks: tuple[Block, ...] | None) -> str:
    """What a term measures, for reports: ``"position"`` (all its blocks in metres), ``"orientation"`` (all in
    radians), ``"motion"`` (a regularizer), ``"collision"`` (contact rows: clearances, not errors), ``"other"``."""
    if blocks and all(b.kind.contact for b in blocks):
        return "collision"
    tolerances = {b.tolerance for b in blocks or ()}
    if level == B.LEVEL_TASK and tolerances == {B.TOL_LINEAR}:
        return "position"
    if level == B.LEVEL_TASK and tolerances == {B.TOL_ANGULAR}:
        return "orientation"
    if level == B.LEVEL_REGULARIZER and blocks:
        return "motion"
    return "other"


def wrapping_coordinates(robot: Robot) -> np.ndarray:
    """``(n,)`` True for coordinates that are angles without end stops (continuous joints, planar θ)."""
    mask = np.zeros(robot.n, dtype=bool)
    for joint in robot.joints:
        if joint.kind is JointKind.CONTINUOUS:
            mask[joint.index] = True
        elif joint.kind is JointKind.PLANAR:
            mask[joint.index + 2] = True
    return mask


class _Layout:
    """What a program's arrays hold apart from targets and weights: frames, kinematic tables, block table.

    Shared by every problem with the same terms (kinds, frames, coordinates) on the same robot.
    """

    @classmethod
    def of(cls, robot: Robot, terms: tuple[Term, ...]) -> _Layout:
        """The layout of ``terms`` on ``robot`` (their blocks built)."""
        return cls(robot, terms, [t.packed(robot)[0] for t in terms])

    def __init__(self, robot: Robot, terms: tuple[Term, ...], packed: list[tuple[Block, ...] | None]):
        #: compiled entry points resolved for this layout's argument types, by kernel (the local engine's; a
        #: program's arrays have the same types as every other program's of its layout)
        self.entries: dict = {}
        levels = [_LEVELS[t.level] for t in terms]
        frames = list(dict.fromkeys(f for p in packed if p for block in p for f in block.frames))
        self.frames = tuple(frames)
        kinematics = robot.kinematics(self.frames)
        self.kin = kinematics.tables
        self.chains = kinematics.chains
        slot = {f: i for i, f in enumerate(frames)}
        rows, indices, self.block_term, kinds = [], [], [], []
        self.param_spans: list[tuple[int, int]] = []  # per term: its blocks' parameters, contiguous
        references: list[tuple[int, slice, slice]] = []  # (term, params, idx) of the regularizers' unit-row blocks
        pptr = iptr = 0
        scratch = 9
        for k, (level, blocks) in enumerate(zip(levels, packed)):
            first = pptr
            for block in blocks or ():
                count = 0
                kind = block.kind
                if kind.frame_indices:  # the frames it reads, by slot
                    indices.append(np.array([slot[f] for f in block.frames], dtype=np.int64))
                    count = indices[-1].size
                elif block.indices is not None:
                    indices.append(np.asarray(block.indices, dtype=np.int64))
                    count = indices[-1].size
                size = int(np.size(block.params))
                fa = slot[block.frames[0]] if block.frames and not kind.frame_indices else -1
                fb = slot[block.frames[1]] if len(block.frames) > 1 and not kind.frame_indices else -1
                kinds.append(kind)
                rows.append((level, block.rows, block.rho, block.tolerance, kind.flags, fa, fb, pptr, iptr, count, k,
                             0, 0, kind.margin, 0.0, block.scale))
                self.block_term.append(k)
                scratch = max(scratch, block.scratch)
                if kind.unit_rows and level == B.LEVEL_REGULARIZER:
                    references.append((k, slice(pptr, pptr + size), slice(iptr, iptr + count)))
                pptr += size
                iptr += count
            self.param_spans.append((first, pptr))
        #: the block table (:data:`~framework.costs.blocks.BLOCK`), weights 0 (see :meth:`table`)
        self.blocks = np.array(rows, dtype=B.BLOCK)
        #: each block's kind
        self.kinds = tuple(kinds)
        self._link()
        self.block_term = np.array(self.block_term, dtype=np.int64)
        self.idx = np.concatenate(indices) if indices else np.zeros(0, dtype=np.int64)
        self.wrap = wrapping_coordinates(robot)
        task = self.blocks["level"] == B.LEVEL_TASK
        self.task_tolerances = self.blocks["tolerance"][task]
        self.task_block_rows = self.blocks["rows"][task]
        self.levels_present = frozenset(self.blocks["level"].tolist())
        self.term_kinds = tuple(_kind(level, blocks) for level, blocks in zip(levels, packed))
        self.generic = [k for k, p in enumerate(packed) if p is None]
        self.packed_terms = tuple(k for k, p in enumerate(packed) if p)  # the terms whose parameters are packed
        names = []
        for term, level, blocks in zip(terms, levels, packed):
            for block in (blocks or ()) if level == B.LEVEL_TASK else ():
                suffix = {B.TOL_ANGULAR: ".angle", B.TOL_LINEAR: ".distance"}.get(block.tolerance, "")
                names.append(term.name + (suffix if len(blocks) > 1 else ""))
        self.task_blocks = tuple(names)
        groups: dict[str, list[int]] = {}
        for k, name in enumerate(names):
            groups.setdefault(name, []).append(k)
        # a name over several blocks (a collision term's rows): its blocks, as a slice when they are contiguous
        self.task_block_groups = None if len(groups) == len(names) else tuple(
            (name, slice(ks[0], ks[-1] + 1) if ks[-1] - ks[0] + 1 == len(ks) else ks) for name, ks in groups.items())
        self.names = unique_labels(t.name for t in terms)  # the problem's term labels
        # the task terms a task error sums: the collision terms' clearances are left out (the exact check reports
        # contacts; their sphere rows may overlap at an answer coal finds clear)
        self.task_terms = tuple(k for k, level in enumerate(levels)
                                if level == B.LEVEL_TASK and self.term_kinds[k] != "collision")
        self._tables: dict[tuple[float, ...], np.ndarray] = {}
        self.task_angular = tuple((self.task_tolerances == B.TOL_ANGULAR).tolist())
        self.task_checked_exactly = tuple(bool(terms[k].checks_collisions) for k in self.block_term[task].tolist())
        #: ``(block, angular)`` of every task block, and of those the exact collision check does not replace
        self.task_limits = tuple(enumerate(self.task_angular))
        self.task_limits_unchecked = tuple((k, a) for k, a in self.task_limits if not self.task_checked_exactly[k])
        self.task_rows = int(self.task_block_rows.sum())
        self.box_wrap = self.wrap & (robot.upper - robot.lower >= 2 * np.pi - 1e-9)
        self._references = references
        #: ``int64 (r,)`` twice: the parameters that hold the regularizers' reference configuration, and the
        #: coordinates each holds (``params[slots] = x[coordinates]`` moves the reference to ``x``)
        self.reference_slots = self.references_of(range(len(terms)))
        #: the scratch entries the blocks' kernels need (a ``Packed`` field)
        self.scratch = np.array([scratch], dtype=np.int64)
        #: the attributes every program of this layout has (:class:`Program` copies them in one update)
        self.shared = {
            "frames": self.frames, "wrap": self.wrap, "task_tolerances": self.task_tolerances,
            "task_block_rows": self.task_block_rows, "task_angular": self.task_angular,
            "task_checked_exactly": self.task_checked_exactly, "task_rows": self.task_rows,
            "task_blocks": self.task_blocks, "term_kinds": self.term_kinds,
            "has_regularizers": B.LEVEL_REGULARIZER in self.levels_present}

    def _link(self) -> None:
        """The block table's kernel addresses, this process's (the kinds' kernels compiled or loaded on first use)."""
        for b, kind in enumerate(self.kinds):
            self.blocks[b]["residual"], self.blocks[b]["curvature"] = kind.addresses()

    def __getstate__(self) -> dict:
        """Pickled without what holds this process's addresses (compiled entries, weighted tables); unpickled, the
        kernels' addresses are the unpickling process's."""
        state = dict(self.__dict__)
        state["entries"], state["_tables"] = {}, {}
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._link()

    def references_of(self, terms: Iterable[int]) -> tuple[np.ndarray, np.ndarray]:
        """:attr:`reference_slots` of the terms ``terms`` (indices in objective order) alone."""
        chosen = set(terms)
        picked = [(p, i) for k, p, i in self._references if k in chosen]
        if not picked:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        return (np.concatenate([np.arange(p.start, p.stop) for p, _ in picked]).astype(np.int64),
                np.concatenate([self.idx[i] for _, i in picked]).astype(np.int64))

    def table(self, weights: tuple[float, ...]) -> np.ndarray:
        """The block table with the terms' ``weights`` (built once per weights; read-only use)."""
        table = self._tables.get(weights)
        if table is None:
            if len(self._tables) > 64:
                self._tables.clear()
            table = self.blocks.copy()
            if table.size:
                table["weight"] = np.asarray(weights)[self.block_term]
            self._tables[weights] = table
        return table

    def packed(self, blocks: np.ndarray, params: np.ndarray) -> B.Packed:
        """The arrays of a program of this layout with its block table and parameters."""
        joints, joint_geometry, frame_joints, frame_geometry = self.kin
        return B.Packed(joints, joint_geometry, frame_joints, frame_geometry, *self.chains, blocks, params, self.idx,
                        self.wrap, self.scratch)


class Program:
    """An objective's terms as packed arrays for :mod:`framework.costs.kernels` and the local engine.

    Attributes:
        packed: the arrays the compiled code reads (:class:`~framework.costs.blocks.Packed`: the population-FK
            tables of every frame the blocks read, the block table, the parameters, ...).
        task_blocks: a name for each task block's error, in block order (``"position[ee]"``, ...).
    """

    def __getstate__(self) -> dict:
        """Pickled with its parameters, not its packed arrays (their block table holds this process's kernel
        addresses): unpickled, they are packed again from its layout. What :meth:`memo` kept is left out."""
        state = dict(self.__dict__)
        state["packed"] = state["packed"].params
        state.pop("_memo", None)
        return state

    def __setstate__(self, state: dict) -> None:
        params = state.pop("packed")
        self.__dict__.update(state)
        self.packed = self.layout.packed(self.layout.table(self.weight_list), params)

    def memo(self, make: Callable[[Program], T]) -> T:
        """``make(self)``, built once per program: what a solver derives from the program's terms and keeps (the
        hull steps' tables); not pickled."""
        table = self.__dict__.setdefault("_memo", {})
        value = table.get(make)
        if value is None:
            value = table[make] = make(self)
        return value

    def __init__(self, robot: Robot, objective: Objective):
        pairs = objective.terms
        if len(pairs) == 1:  # (the common case: no zip, no comprehension frames)
            (weight, term), = pairs
            weights, terms = (weight,), (term,)
            key = ("layout", ((term.level, term.name, term.layout_key(robot)),))
        else:
            weights, terms = zip(*pairs) if pairs else ((), ())  # floats (``Objective`` checked)
            key = ("layout", tuple([(t.level, t.name, t.layout_key(robot)) for t in terms]))
        layout = robot.derived(_Layout.of, terms, key=key)
        packed = layout.packed_terms
        if len(packed) == 1:  # a copy: the program's own
            params = float_copy(terms[packed[0]].parameters(robot))
        else:
            flat = [terms[k].parameters(robot) for k in packed]
            params = np.concatenate(flat, dtype=float, casting="unsafe") if flat else np.zeros(0)
        self.__dict__.update(layout.shared)  # what every program of the layout reads from it (see _Layout.shared)
        self.robot, self.terms, self.weight_list, self.layout = robot, terms, weights, layout
        self.packed = layout.packed(layout.table(weights), params)
        self._versions = list(map(_VERSION, terms))

    @cached_property
    def weights(self) -> np.ndarray:
        """``(terms,)`` the terms' weights."""
        return np.array(self.weight_list)

    def named_errors(self, errors: Sequence[float]) -> dict[str, float]:
        """Task block errors (block order) by name; blocks sharing a name (a collision term's hundreds of sphere
        pairs) report their worst."""
        groups = self.layout.task_block_groups
        if groups is None:
            return dict(zip(self.task_blocks, errors))
        return {name: max(errors[ks]) if isinstance(ks, slice) else max(errors[k] for k in ks) for name, ks in groups}

    def task_errors(self, x: np.ndarray) -> np.ndarray:
        """``(blocks,)`` each task block's error ``‖r_b‖`` at one configuration ``x`` ``(n,)`` [m, or rad for
        orientations], in block order; ``(pop, blocks)`` for a population ``x`` ``(pop, n)``."""
        self.refresh()
        X = np.ascontiguousarray(np.atleast_2d(x), dtype=float)
        errors = np.empty((X.shape[0], self.task_block_rows.size))
        if errors.size:
            task_errors_at(X, self.packed, errors)
        return errors if np.ndim(x) == 2 else errors[0]

    def values_and_errors(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`values` ``(terms,)`` and :meth:`task_errors` ``(blocks,)`` at one configuration ``x`` ``(n,)``
        (finite), in one entry into compiled code."""
        if self.layout.generic or not all_finite(x):  # (Python terms; NaN or inf: values raises, naming it)
            return self.values(np.atleast_2d(x))[0], self.task_errors(x)
        self.refresh()
        V, errors = np.zeros(len(self.terms)), np.empty(self.task_block_rows.size)
        values_and_errors(np.ascontiguousarray(x, dtype=float), self.packed, V, errors)
        return V, errors

    def limits(self, tolerance: float, angle_tolerance: float) -> np.ndarray:
        """``(blocks,)`` each task block's tolerance: ``angle_tolerance`` [rad] for orientations, ``tolerance``
        [m] for the others (the limits :meth:`within` compares :meth:`task_errors` with)."""
        return np.where(np.array(self.task_angular, dtype=bool), angle_tolerance, tolerance)

    def within(self, errors: Sequence[float], tolerance: float, angle_tolerance: float, *,
               exact_checked: bool = False) -> bool:
        """Whether every task block's error (block order, from :meth:`task_errors`) is within
        ``angle_tolerance`` [rad] for orientations and ``tolerance`` [m] for the others; with ``exact_checked``
        (the exact collision check has the last word) the collision terms' sphere rows are not asked."""
        layout = self.layout
        for k, angular in layout.task_limits_unchecked if exact_checked else layout.task_limits:
            if errors[k] > (angle_tolerance if angular else tolerance):
                return False
        return True

    @cached_property
    def hull_pairs(self) -> tuple[HullPair, ...]:
        """The convex-hull pairs the collision terms keep apart (:meth:`Term.hull_pairs`), built once."""
        return tuple(p for t in self.terms for p in t.hull_pairs(self.robot))

    @cached_property
    def loose_hulls(self) -> bool:
        """Whether a collision term's hull pairs include a loose one (:meth:`Term.loose_hulls`)."""
        return any(t.loose_hulls(self.robot) for t in self.terms)

    def reference(self, x: np.ndarray) -> bool:
        """Write the configuration the regularizers pull towards into ``x`` ``(n,)`` (only the coordinates they
        cover); returns whether there is any."""
        slots, coordinates = self.layout.reference_slots
        x[coordinates] = self.packed.params[slots]
        return bool(slots.size)

    def refresh(self) -> None:
        """Re-pack the parameters of terms whose targets changed since the last call (a few µs)."""
        versions = self._versions
        for k, term in enumerate(self.terms):
            if term.version != versions[k]:
                versions[k] = term.version
                start, stop = self.layout.param_spans[k]
                self.packed.params[start:stop] = term.parameters(self.robot)

    def cost(self, X: np.ndarray) -> np.ndarray:
        """``(pop,)`` weighted sums of a population ``X`` ``(pop, n)`` (float64, C-contiguous)."""
        if self.layout.generic:
            return self.values(X) @ self.weights
        self.refresh()
        F = np.empty(X.shape[0])
        _check_finite(X, population_cost(X, self.packed, F))
        return F

    def values(self, X: np.ndarray) -> np.ndarray:
        """``(pop, terms)`` unweighted values of a population ``X`` ``(pop, n)`` (float64, C-contiguous)."""
        self.refresh()
        V = np.zeros((X.shape[0], len(self.terms)))
        _check_finite(X, population_values(X, self.packed, V))
        generic = self.layout.generic
        if generic:
            frames = tuple(dict.fromkeys(f for k in generic for f in self.terms[k].frames))
            poses = self.robot.frame_poses(X, frames) if frames else None
            for k in generic:
                V[:, k] = self.terms[k].value(self.robot, X, poses)
        return V


def _check_finite(X: np.ndarray, bad: int) -> None:
    """Raise for row ``bad`` of ``X`` if a kernel found NaN or inf there (``bad < 0``: none)."""
    if bad >= 0:
        raise ConfigurationError(f"configuration holds NaN or inf (row {bad}: {X[bad].tolist()})")
