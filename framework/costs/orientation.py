"""Orientation of a frame: norm of the vector part of the relative quaternion (paper 002 eq. 6-15).

Quaternions are given as ``(x, y, z, w)`` (scalar last, as ``scipy.spatial.transform.Rotation``).
For a relative rotation by angle φ the error is ``|sin(φ/2)|``: 0 for equal rotations, 1 for a half turn.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from ..errors import TaskError
from ..kinematics import FramePoses
from ..robot import Robot
from .base import Linearization, LocalKinematics, Term


def rotation_from(target: Sequence[float] | np.ndarray, what: str) -> np.ndarray:
    """A rotation matrix from a ``(3, 3)`` matrix or an ``(x, y, z, w)`` quaternion; validated."""
    t = np.asarray(target, dtype=float)
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


def quaternion_error(R: np.ndarray, R_target: np.ndarray) -> np.ndarray:
    """``|sin(φ/2)|`` of ``R_targetᵀ R`` for a batch ``R`` ``(..., 3, 3)``: shape ``(...)``.

    Exact near 0 (from the skew part, ``sin φ = 2 sin(φ/2) cos(φ/2)``) and near π (from the trace).
    """
    E = np.einsum("ji,...jk->...ik", R_target, R)
    trace = np.clip(E[..., 0, 0] + E[..., 1, 1] + E[..., 2, 2], -1.0, 3.0)
    w = 0.5 * np.sqrt(1.0 + trace)  # cos(φ/2) >= 0
    skew = 0.25 * np.stack(
        [E[..., 2, 1] - E[..., 1, 2], E[..., 0, 2] - E[..., 2, 0], E[..., 1, 0] - E[..., 0, 1]], axis=-1
    )  # = w · sin(φ/2) · axis
    near_zero = w > 0.5
    from_skew = np.linalg.norm(skew, axis=-1) / np.where(near_zero, w, 1.0)
    from_trace = np.sqrt(np.clip(0.25 * (3.0 - trace), 0.0, 1.0))
    return np.where(near_zero, from_skew, from_trace)


class Orientation(Term):
    """``‖vec(q_targetᵀ ⊗ q(x))‖ = |sin(φ/2)|`` (unitless) for the rotation φ between frame and target."""

    is_task = True

    def __init__(self, frame: str, target: Sequence[float] | np.ndarray, *, name: str | None = None):
        self.frame = frame
        self.frames = (frame,)
        self.target = rotation_from(target, f"orientation target of {frame!r}")
        self.name = name or f"orientation[{frame}]"

    def value(self, robot: Robot, X: np.ndarray, poses: FramePoses) -> np.ndarray:
        return quaternion_error(poses.rotation(self.frame), self.target)

    def residual(self, robot: Robot, x: np.ndarray, local: LocalKinematics) -> np.ndarray:
        """``log(R_targetᵀ R)`` (3,) [rad]: zero exactly when the value is zero, smooth for refinement."""
        return pin.log3(self.target.T @ local.placement(self.frame).rotation)

    def linearize(self, robot: Robot, x: np.ndarray, local: LocalKinematics) -> Linearization:
        """Value ``sin(φ/2)`` with ``φ = ‖log(R_targetᵀ R)‖``, its gradient, the log residual and Jacobian."""
        R = local.placement(self.frame).rotation
        E = self.target.T @ R
        r = pin.log3(E)
        J = pin.Jlog3(E) @ R.T @ local.frame_jacobian(self.frame)[3:]
        phi = float(np.sqrt(r @ r))
        gradient = 0.5 * np.cos(phi / 2) * (J.T @ r) / phi if phi > 0 else np.zeros_like(x)
        return Linearization(float(np.sin(phi / 2)), gradient, r, J)

    def jacobian(self, robot: Robot, x: np.ndarray, local: LocalKinematics) -> np.ndarray:
        return self.linearize(robot, x, local).jacobian
