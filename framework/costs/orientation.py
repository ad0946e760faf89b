"""Orientation of a frame: the rotation between the frame and a target (paper 002 eq. 6-15).

Residual ``r = log(R_targetᵀ R(x))`` (3,) [rad]: its norm is the angle φ ∈ [0, π] of the relative rotation.
Value ``ρ(r) = sin(‖r‖/2)`` — the norm of the relative quaternion's vector part, paper 002's measure: 0 for
equal rotations, 1 for a half turn. Success holds the angle ``‖r‖`` to the angular tolerance [rad].
Quaternion targets are ``(x, y, z, w)`` (scalar last, as ``scipy.spatial.transform.Rotation``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import TaskError
from ..robot import Robot
from . import blocks as B
from .base import Term
from .program import Block


def rotation_from(target: Sequence[float] | np.ndarray, what: str) -> np.ndarray:
    """A rotation matrix from a ``(3, 3)`` matrix or an ``(x, y, z, w)`` quaternion; validated."""
    try:
        t = np.asarray(target, dtype=float)
    except (TypeError, ValueError):
        raise TaskError(f"{what} must be a (3, 3) rotation matrix or an (x, y, z, w) quaternion") from None
    if not np.all(np.isfinite(t)):
        raise TaskError(f"{what} holds NaN or inf")
    if t.shape == (4,):
        norm = np.linalg.norm(t)
        if norm < 1e-9:
            raise TaskError(f"{what}: a zero quaternion is not a rotation")
        x, y, z, w = t / norm
        return np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
            ]
        )
    if t.shape == (3, 3):
        if not np.allclose(t.T @ t, np.eye(3), atol=1e-6) or np.linalg.det(t) < 0:
            raise TaskError(f"{what} is not a rotation matrix (RᵀR ≠ I or det < 0)")
        return t
    raise TaskError(f"{what} must be a (3, 3) rotation matrix or an (x, y, z, w) quaternion; got shape {t.shape}")


class Orientation(Term):
    """``sin(φ/2)`` (unitless) for the angle φ between the frame's rotation and the target's."""

    level = "task"

    def __init__(self, frame: str, target: Sequence[float] | np.ndarray, *, name: str | None = None):
        self.frame = frame
        self.frames = (frame,)
        self.name = name or f"orientation[{frame}]"
        self.set_target(target)

    def set_target(self, target: Sequence[float] | np.ndarray) -> None:
        """Change the target rotation (``(3, 3)`` matrix or ``(x, y, z, w)`` quaternion, world frame)."""
        self.target = rotation_from(target, f"orientation target of {self.frame!r}")
        self._touch()

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        return (Block(B.ORIENTATION, B.HALFSIN, 3, self.frames, self.target.ravel(), tolerance=B.TOL_ANGULAR),)
