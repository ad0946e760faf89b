"""Motion of a joint group: distance to the previous configuration (paper 000 eq. 10, paper 002 eq. 16)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import TaskError
from ..kinematics import FramePoses
from ..robot import Robot
from .base import LocalKinematics, Term

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
        delta = X[:, self.indices(robot)] - self.previous_values(robot)
        if self.norm == "l2":
            return np.linalg.norm(delta, axis=-1)
        return np.abs(delta).sum(axis=-1) / (delta.shape[-1] * np.pi)

    def residual(self, robot: Robot, x: np.ndarray, local: LocalKinematics) -> np.ndarray:
        """``x_g − x_g^prev`` (its L2 norm is the ``"l2"`` value)."""
        return x[self.indices(robot)] - self.previous_values(robot)

    def jacobian(self, robot: Robot, x: np.ndarray, local: LocalKinematics) -> np.ndarray:
        J = np.zeros((len(self.indices(robot)), robot.n))
        J[np.arange(J.shape[0]), self.indices(robot)] = 1.0
        return J
