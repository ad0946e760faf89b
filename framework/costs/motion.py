"""Motion of a joint group: distance to the previous configuration (paper 000 eq. 10, paper 002 eq. 16)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import TaskError
from ..kinematics import FramePoses
from ..robot import Robot
from .base import Linearization, LocalKinematics, Term, row_norms

NORMS = ("l2", "l1")


class Motion(Term):
    """Distance of a joint group to its previous values.

    ``norm="l2"``: ``‖x_g − x_g^prev‖₂`` (paper 000 eq. 10); ``norm="l1"``: ``‖x_g − x_g^prev‖₁ / (n_g π)``
    (paper 002 eq. 16), with ``n_g`` the group size. ``previous`` is either the whole configuration ``(n,)`` or
    the group's values ``(n_g,)``; ``group`` is a group name (``"base"``, ``"arm1"``, ``"all"``) or a joint name.
    """

    def __init__(self, group: str, previous: Sequence[float], *, norm: str = "l2", name: str | None = None):
        if norm not in NORMS:
            raise TaskError(f"motion norm must be one of {NORMS}; got {norm!r}")
        self.group, self.norm = group, norm
        self.previous = np.asarray(previous, dtype=float)
        if self.previous.ndim != 1 or not np.all(np.isfinite(self.previous)):
            raise TaskError(f"previous configuration of group {group!r} must be a finite vector")
        self.name = name or f"motion[{group}]"
        self._local: tuple | None = None  # (robot, indices, previous values, Jacobian) of the last linearization

    def indices(self, robot: Robot) -> np.ndarray:
        return robot.group(self.group)

    def previous_values(self, robot: Robot) -> np.ndarray:
        idx = self.indices(robot)
        if self.previous.shape == (robot.n,):
            return self.previous[idx]
        if self.previous.shape == (len(idx),):
            return self.previous
        raise TaskError(
            f"previous configuration of group {self.group!r} must have {len(idx)} (group) or {robot.n} (robot) "
            f"values; got {self.previous.shape[0]}"
        )

    def validate(self, robot: Robot) -> None:
        self.previous_values(robot)

    def value(self, robot: Robot, X: np.ndarray, poses: FramePoses) -> np.ndarray:
        return self.bind(robot)(X, poses)

    def bind(self, robot: Robot):
        idx, previous = self.indices(robot), self.previous_values(robot)
        if len(idx) and np.array_equal(idx, np.arange(idx[0], idx[0] + len(idx))):
            idx = slice(int(idx[0]), int(idx[0]) + len(idx))  # a view instead of a gather
        scale = 1.0 / (len(previous) * np.pi)

        def l2(X: np.ndarray, poses: FramePoses) -> np.ndarray:
            return row_norms(X[:, idx] - previous)

        def l1(X: np.ndarray, poses: FramePoses) -> np.ndarray:
            return np.abs(X[:, idx] - previous).sum(axis=-1) * scale

        return l2 if self.norm == "l2" else l1

    def residual(self, robot: Robot, x: np.ndarray, local: LocalKinematics) -> np.ndarray:
        """``x_g − x_g^prev`` (its L2 norm is the ``"l2"`` value)."""
        return x[self.indices(robot)] - self.previous_values(robot)

    def linearize(self, robot: Robot, x: np.ndarray, local: LocalKinematics) -> Linearization:
        if self._local is None or self._local[0] is not robot:  # group lookups once per robot
            self._local = (robot, self.indices(robot), self.previous_values(robot), self.jacobian(robot, x, local))
        _, idx, previous, J = self._local
        r = x[idx] - previous
        g = np.zeros_like(x)
        if self.norm == "l2":
            norm = float(np.sqrt(r @ r))
            if norm > 0:
                g[idx] = r / norm
            return Linearization(norm, g, r, J)
        scale = 1.0 / (len(idx) * np.pi)
        g[idx] = np.sign(r) * scale
        return Linearization(float(np.abs(r).sum() * scale), g, r, J)

    def jacobian(self, robot: Robot, x: np.ndarray, local: LocalKinematics) -> np.ndarray:
        J = np.zeros((len(self.indices(robot)), robot.n))
        J[np.arange(J.shape[0]), self.indices(robot)] = 1.0
        return J
