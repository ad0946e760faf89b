"""Cost terms and their weighted composition.

A :class:`Term` maps a population of joint coordinates ``X`` ``(pop, n)`` to one value per member ``(pop,)``,
reading frame poses computed once for all terms (:class:`~framework.kinematics.FramePoses`). Terms compose
readably into an :class:`Objective`::

    f = 1.2 * Position("arm1_ee", t1) + 1.2 * Position("arm2_ee", t2) + 0.1 * Motion("base", q_prev)

A term that is a distance to a target (position, orientation, relative position) also exposes a *residual*
``r(x)`` with its analytic Jacobian from Pinocchio (``residual`` / ``jacobian``), so the same definition feeds
a metaheuristic (scalar, population) and a local refinement (residual + Jacobian). Such terms are *task*
terms: their unweighted sum is the task error that decides success.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import TaskError
from ..kinematics import FramePoses
from ..robot import Robot


class Term:
    """One cost term. Subclasses set :attr:`frames` and implement :meth:`value`.

    Attributes:
        name: label used in reports and recordings.
        frames: frames whose world poses :meth:`value` reads.
        is_task: True for terms that measure a distance to a target (they decide success).
    """

    name: str = "term"
    frames: tuple[str, ...] = ()
    is_task: bool = False

    def validate(self, robot: Robot) -> None:
        """Raise a :class:`~framework.errors.MetaikError` if the term cannot apply to ``robot``."""
        for frame in self.frames:
            robot.frame_id(frame)

    def value(self, robot: Robot, X: np.ndarray, poses: FramePoses) -> np.ndarray:
        """Unweighted value for each member of ``X`` ``(pop, n)``: shape ``(pop,)``."""
        raise NotImplementedError

    def bind(self, robot: Robot) -> Callable[[np.ndarray, FramePoses], np.ndarray]:
        """``value`` specialized to one robot, with lookups (frames, groups) done once: the hot path."""
        return lambda X, poses: self.value(robot, X, poses)

    # Residual view, for local refinement (task terms and smooth regularizers).
    def residual(self, robot: Robot, x: np.ndarray, local: LocalKinematics) -> np.ndarray:
        """Residual ``r(x)`` ``(m,)`` whose norm is :meth:`value`."""
        raise NotImplementedError(f"{type(self).__name__} has no residual view")

    def jacobian(self, robot: Robot, x: np.ndarray, local: LocalKinematics) -> np.ndarray:
        """``dr/dx`` ``(m, n)`` in joint coordinates."""
        raise NotImplementedError(f"{type(self).__name__} has no residual view")

    def gradient(self, robot: Robot, x: np.ndarray, local: LocalKinematics) -> np.ndarray:
        """``d value / dx`` ``(n,)`` at one configuration."""
        return self.linearize(robot, x, local).gradient

    def linearize(self, robot: Robot, x: np.ndarray, local: LocalKinematics) -> Linearization:
        """Value, gradient, residual and Jacobian at one configuration ``x`` ``(n,)``, from one kinematics call.

        The default is for terms whose value is ``‖r(x)‖`` (gradient ``Jᵀr/‖r‖``, 0 where ``r = 0``).
        """
        r = self.residual(robot, x, local)
        J = self.jacobian(robot, x, local)
        norm = float(np.sqrt(r @ r))
        return Linearization(norm, J.T @ r / norm if norm > 0 else np.zeros_like(x), r, J)

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


@dataclass(frozen=True)
class Linearization:
    """A term at one configuration: its value, gradient ``(n,)`` and, for terms with a residual view, the
    residual ``(m,)`` and its Jacobian ``(m, n)`` (``None`` otherwise, e.g. the joint-limit penalty)."""

    value: float
    gradient: np.ndarray
    residual: np.ndarray | None = None
    jacobian: np.ndarray | None = None


def check_weight(weight: float) -> float:
    w = float(weight)
    if not np.isfinite(w) or w < 0:
        raise TaskError(f"a cost weight must be a finite number >= 0; got {weight!r}")
    return w


@dataclass(frozen=True)
class Objective:
    """A weighted sum of terms: ``f(X) = Σ wᵢ termᵢ(X)``."""

    terms: tuple[tuple[float, Term], ...]

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
        seen: dict[str, int] = {}
        out = []
        for _, term in self.terms:
            seen[term.name] = seen.get(term.name, 0) + 1
            out.append(term.name if seen[term.name] == 1 else f"{term.name}#{seen[term.name]}")
        return tuple(out)

    @property
    def frames(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(f for _, t in self.terms for f in t.frames))


class LocalKinematics:
    """Pinocchio kinematics and frame Jacobians at one configuration, for residual views.

    Jacobians are returned in joint coordinates (``J_pin @ dv/dx``), world-aligned (``LOCAL_WORLD_ALIGNED``).
    """

    def __init__(self, robot: Robot, x: np.ndarray, data: pin.Data | None = None):
        self.robot = robot
        self.x = np.asarray(x, dtype=float)
        self.data = robot.model.createData() if data is None else data  # reuse one in loops: it is costly
        q = robot.to_pinocchio(self.x)
        pin.computeJointJacobians(robot.model, self.data, q)
        pin.updateFramePlacements(robot.model, self.data)
        self._T = None if robot._q_is_x else robot.coordinate_jacobian(self.x)

    def placement(self, frame: str) -> pin.SE3:
        return self.data.oMf[self.robot.frame_id(frame)]

    def frame_jacobian(self, frame: str) -> np.ndarray:
        """``(6, n)``: linear rows then angular rows, world-aligned, in joint coordinates."""
        J = pin.getFrameJacobian(self.robot.model, self.data, self.robot.frame_id(frame), pin.LOCAL_WORLD_ALIGNED)
        return J if self._T is None else J @ self._T


def stacked_residuals(
    robot: Robot, terms: Sequence[Term], x: np.ndarray, local: LocalKinematics | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Residuals ``(m,)`` and Jacobians ``(m, n)`` of ``terms`` at ``x``, stacked, from one kinematics call.

    Raises NotImplementedError for a term without a residual view.
    """
    local = LocalKinematics(robot, x) if local is None else local
    r = np.concatenate([t.residual(robot, x, local) for t in terms])
    return r, np.vstack([t.jacobian(robot, x, local) for t in terms])


def row_norms(D: np.ndarray) -> np.ndarray:
    """Euclidean norm of each row of ``D`` ``(pop, m)``: shape ``(pop,)``."""
    return np.sqrt(np.einsum("ij,ij->i", D, D))


def as_vector(value: Sequence[float] | np.ndarray, size: int, what: str) -> np.ndarray:
    """A finite float vector of length ``size``; raises :class:`TaskError` naming ``what``."""
    v = np.asarray(value, dtype=float)
    if v.shape != (size,):
        raise TaskError(f"{what} must have shape ({size},); got {v.shape}")
    if not np.all(np.isfinite(v)):
        raise TaskError(f"{what} holds NaN or inf: {v.tolist()}")
    return v
