"""An IK problem: a robot, a weighted objective over its joint coordinates, and how to treat the box.

``Problem.cost(X)`` is what solvers minimize: one population forward-kinematics call for every frame the
terms need, then the weighted sum. ``Problem.evaluate(X)`` reports every term separately.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .costs import JointLimitPenalty, Motion, Objective, Term
from .errors import TaskError
from .robot import Robot

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
        objective: weighted terms (a single :class:`Term` is accepted).
        bounds: out-of-box candidates are ``"resample"``-d uniformly (paper 000 eq. 12), ``"clip"``-ped, or
            left to a ``"penalty"`` (a :class:`JointLimitPenalty` is appended if the objective has none).
    """

    robot: Robot
    objective: Objective
    bounds: str = "resample"

    def __post_init__(self) -> None:
        objective = self.objective
        if isinstance(objective, Term):
            objective = Objective(((1.0, objective),))
        if not isinstance(objective, Objective) or len(objective) == 0:
            raise TaskError("a problem needs an objective of at least one cost term")
        if self.bounds not in BOUNDS:
            raise TaskError(f"bounds handling must be one of {BOUNDS}; got {self.bounds!r}")
        if self.bounds == "penalty" and not any(isinstance(t, JointLimitPenalty) for _, t in objective):
            objective = objective + JointLimitPenalty()
        for _, term in objective:
            term.validate(self.robot)
        object.__setattr__(self, "objective", objective)
        # The hot path, prepared once: bound term evaluators, the weights, one FK program for all frames.
        object.__setattr__(self, "_evaluators", tuple(t.bind(self.robot) for _, t in objective))
        object.__setattr__(self, "_weights", np.array([w for w, _ in objective]))
        frames = objective.frames
        object.__setattr__(self, "_kinematics", self.robot._kinematics(frames) if frames else None)

    @property
    def n(self) -> int:
        return self.robot.n

    @property
    def names(self) -> tuple[str, ...]:
        return self.objective.names

    @property
    def weights(self) -> np.ndarray:
        return self._weights.copy()

    @property
    def task_mask(self) -> np.ndarray:
        return np.array([t.is_task for _, t in self.objective])

    @property
    def repair_mode(self) -> str:
        """Bounds mode for the optimizer loop (``"none"`` when a penalty term handles the box)."""
        return "none" if self.bounds == "penalty" else self.bounds

    @property
    def previous(self) -> np.ndarray | None:
        """``(n,)`` the configuration the motion terms measure from (box middle on joints no motion term covers),
        clipped to the box; ``None`` when the objective has no motion term. The natural warm start."""
        motions = [t for _, t in self.objective if isinstance(t, Motion)]
        if not motions:
            return None
        x = self.robot.middle.copy()
        for term in motions:
            x[term.indices(self.robot)] = term.previous_values(self.robot)
        return np.clip(x, self.robot.lower, self.robot.upper)

    def values(self, X: np.ndarray) -> np.ndarray:
        """``(pop, k)`` unweighted term values for a population ``X`` ``(pop, n)``."""
        if self._kinematics is None:
            X = self.robot.check_population(X)
            poses = None
        else:  # the FK kernel rejects NaN/inf itself
            X = self.robot.check_population(X, finite=False)
            poses = self._kinematics(X)
        values = np.empty((X.shape[0], len(self._evaluators)))
        for k, evaluate in enumerate(self._evaluators):
            values[:, k] = evaluate(X, poses)
        return values

    def cost(self, X: np.ndarray) -> np.ndarray:
        """``(pop,)`` objective values: the population cost solvers minimize."""
        return self.values(X) @ self._weights

    def evaluate(self, X: np.ndarray) -> Evaluation:
        """Every term of every member, the cost and the task error."""
        values = self.values(X)
        return Evaluation(
            self.names, self.weights, values, values @ self._weights, values[:, self.task_mask].sum(axis=1)
        )
