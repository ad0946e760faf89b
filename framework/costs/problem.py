"""An IK problem: a robot, a weighted objective over its joint coordinates, and how to treat the box.

``Problem.cost(X)`` is what solvers minimize: one compiled pass over the population computes the forward
kinematics of every frame the terms read and every term's value (:class:`~framework.costs.Program`), then the
weighted sum. ``Problem.evaluate(X)`` reports every term separately; ``Problem.errors(x)`` each task term's
error in its own unit (m or rad), which decides success, with ``Problem.collisions(x)`` (the exact check of the
collision terms) when there are any.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..geometry.collision import CollisionReport
from ..geometry.exact_check import CheckGroup, check_all, grouped
from .base import Objective
from .program import Program
from ..errors import TaskError
from ..model.robot import Robot

BOUNDS = ("resample", "clip", "penalty")


@dataclass(frozen=True)
class Evaluation:
    """Per-term values of a population.

    Attributes:
        names: term labels, in objective order.
        weights: ``(k,)`` term weights.
        values: ``(pop, k)`` unweighted term values.
        cost: ``(pop,)`` the objective ``values @ weights``.
        task_error: ``(pop,)`` sum of the unweighted task terms (position, orientation, relative).
    """

    names: tuple[str, ...]
    weights: np.ndarray
    values: np.ndarray
    cost: np.ndarray
    task_error: np.ndarray

    def term(self, name: str) -> np.ndarray:
        """``(pop,)`` unweighted values of one term."""
        return self.values[:, self.names.index(name)]

    def as_dict(self, member: int = 0) -> dict[str, float]:
        """Unweighted term values of one member, by name."""
        return {n: float(v) for n, v in zip(self.names, self.values[member])}


@dataclass(frozen=True, eq=False)
class Problem:
    """Minimize ``objective`` over the robot's joint coordinates within its search box.

    Args:
        robot: the robot (its ``lower``/``upper`` are the search box).
        objective: weighted terms: an :class:`Objective`, ``(weight, term)`` pairs or a single :class:`Term`.
        bounds: out-of-box candidates are ``"resample"``-d uniformly (paper 000 eq. 12), ``"clip"``-ped, or
            left to a ``"penalty"`` (a :class:`~framework.costs.JointLimitPenalty` is appended if the objective
            has none); the local engine always keeps its steps in the box.
        priorities: ``True`` (default): the task terms come first, whatever the weights — the local solvers reach
            the task and minimize the regularizers without leaving it. ``False`` (the papers' weighted sums):
            the weighted sum is what counts, so with small task weights the optimum may stop short of a
            reachable target. Metaheuristics rank by Deb's rules on these levels when there are
            regularizers (a candidate within the task's tolerances first, then the lower regularizer cost), by
            the weighted sum without priorities (or with ``options={"ranking": "weighted"}``).

    Targets of the terms may be changed in place (``term.set_target(...)``); the problem re-reads them.
    ``program`` is the objective packed for the compiled kernels and the local engine (built with the problem);
    ``checks_collisions`` tells whether a term stands for an exact collision check (then success needs
    :meth:`collisions` clear).
    """

    robot: Robot
    objective: Objective
    bounds: str = "resample"
    priorities: bool = True
    program: Program = field(init=False, repr=False)
    checks_collisions: bool = field(init=False, repr=False)

    def __init__(self, robot: Robot, objective, bounds: str = "resample", priorities: bool = True) -> None:
        # (written out, not the dataclass's: a pose solve's Python is most of its time; one update sets the fields)
        objective = Objective.of(objective)
        terms = objective.terms
        if not terms:
            raise TaskError("a problem needs an objective of at least one cost term")
        if bounds not in BOUNDS:
            raise TaskError(f"bounds handling must be one of {BOUNDS}; got {bounds!r}")
        if not isinstance(priorities, bool):
            raise TaskError(f"priorities must be true or false; got {priorities!r}")
        if bounds == "penalty" and not any(getattr(t, "penalizes_limits", False) for _, t in terms):
            from . import JointLimitPenalty

            objective = objective + JointLimitPenalty()
            terms = objective.terms
        checks = False
        for _, term in terms:
            term.validate(robot)
            checks = checks or term.checks_collisions
        self.__dict__.update(robot=robot, objective=objective, bounds=bounds, priorities=priorities,
                             checks_collisions=checks, program=Program(robot, objective))

    @property
    def n(self) -> int:
        return self.robot.n

    @property
    def weights(self) -> np.ndarray:
        return self.program.weights.copy()

    @cached_property
    def fixed_frames(self) -> tuple[tuple[str, tuple, int], ...]:
        """The frames whose position and rotation the task terms fix together: ``(frame, terms, count)`` with the
        terms giving its position and its rotation (:meth:`~framework.costs.Term.frame_target`; one term for a pose)
        and how many task terms place it; read the targets from the terms (they may move)."""
        found: dict[str, list] = {}
        for _, term in self.objective:
            target = term.frame_target() if term.is_task else None
            if target is None:
                continue
            entry = found.setdefault(target[0], [None, None, 0])
            entry[0] = term if target[1] is not None else entry[0]
            entry[1] = term if target[2] is not None else entry[1]
            entry[2] += 1
        return tuple((frame, (p, r), count) for frame, (p, r, count) in found.items() if p is not None and r is not None)

    @cached_property
    def task_mask(self) -> np.ndarray:
        """``(k,)`` True for task terms."""
        return np.array([t.is_task for _, t in self.objective], dtype=bool)

    @property
    def names(self) -> tuple[str, ...]:
        """Unique labels of the terms, in objective order."""
        return self.program.layout.names

    @property
    def repair_mode(self) -> str:
        """Bounds mode for the optimizer loop (``"none"`` when a penalty term handles the box)."""
        return "none" if self.bounds == "penalty" else self.bounds

    @property
    def previous(self) -> np.ndarray | None:
        """``(n,)`` the configuration the regularizers pull towards (e.g. motion terms' ``q_prev``; the box
        middle on coordinates none covers), clipped to the box; ``None`` when no regularizer has one.
        The natural warm start."""
        program = self.program
        if not program.layout.reference_slots[0].size:
            return None
        x = self.robot.middle.copy()
        program.refresh()
        program.reference(x)
        np.maximum(x, self.robot.lower, out=x)  # np.clip, without its ~1 µs of dispatch
        return np.minimum(x, self.robot.upper, out=x)

    def values(self, X: np.ndarray) -> np.ndarray:
        """``(pop, k)`` unweighted term values for a population ``X`` ``(pop, n)``."""
        return self.program.values(self.robot.check_population(X, finite=False))

    def cost(self, X: np.ndarray) -> np.ndarray:
        """``(pop,)`` objective values: the population cost solvers minimize."""
        return self.program.cost(self.robot.check_population(X, finite=False))

    def evaluate(self, X: np.ndarray) -> Evaluation:
        """Every term of every member, the cost and the task error."""
        values = self.values(X)
        return Evaluation(
            self.names, self.weights, values, values @ self.program.weights, values[:, self.task_mask].sum(axis=1)
        )

    def collisions(self, x: np.ndarray, *, margins: bool = False) -> CollisionReport | None:
        """The exact collision check of the problem's collision terms at ``x`` ``(n,)``, as one report (coal on
        the URDF's geometry; ``None`` without collision terms); with ``margins``, pairs closer than their term's
        margin count as contacts too."""
        if not self.checks_collisions:
            return None
        return check_all(self._exact_checks, x, margins=margins)

    @cached_property
    def _exact_checks(self) -> tuple[CheckGroup, ...]:
        """The pairs the collision terms keep apart, as the exact check reads them (:meth:`collisions`)."""
        return grouped([t.exact_check() for _, t in self.objective if t.checks_collisions])

    @cached_property
    def without_collision_terms(self) -> Problem | None:
        """The same problem without its collision terms (same term objects: targets moved on one move on both),
        or ``None`` when it has none."""
        if not self.checks_collisions:
            return None
        kept = tuple((w, t) for w, t in self.objective if not t.checks_collisions)
        return Problem(self.robot, Objective(kept), bounds=self.bounds, priorities=self.priorities) if kept else None

    def with_own_terms(self, names: Iterable[str]) -> Problem:
        """The same problem with its own copies of the terms ``names`` (the others shared): targets moved on the
        copies leave this problem's terms as they are (a batch's items, solved one by one)."""
        names = set(names)
        terms = tuple((w, t.copy() if name in names else t) for (w, t), name in zip(self.objective, self.names))
        return Problem(self.robot, Objective(terms), bounds=self.bounds, priorities=self.priorities)

    def errors(self, x: np.ndarray) -> dict[str, float]:
        """Each task block's error at one configuration ``x`` ``(n,)``: distance [m] for position-like terms,
        angle [rad] for orientations, by name (a pose contributes ``name.distance`` and ``name.angle``)."""
        x = self.robot.check_population(x)[0]
        return self.program.named_errors(self.program.task_errors(x).tolist())
