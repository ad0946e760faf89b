"""Direction of a frame axis: a tool pointing along a world direction, free to turn about it."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import TaskError
from ..robot import Robot
from . import blocks as B
from .base import Term, as_vector
from .program import Block


def unit_vector(value: Sequence[float], what: str) -> np.ndarray:
    """``value`` as a unit vector (3,); raises :class:`TaskError` for a wrong shape, NaN / inf or zero length."""
    try:
        v = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise TaskError(f"{what} must be 3 numbers") from None
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise TaskError(f"{what} must be 3 finite numbers; got {value!r}")
    norm = np.linalg.norm(v)
    if norm < 1e-12:
        raise TaskError(f"{what} must not be the zero vector")
    return v / norm


def perpendicular_basis(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors ``(b1, b2)`` with ``(b1, b2, d)`` right-handed and orthonormal."""
    helper = np.eye(3)[int(np.argmin(np.abs(d)))]
    b1 = helper - (helper @ d) * d
    b1 /= np.linalg.norm(b1)
    return b1, np.cross(d, b1)


class Direction(Term):
    """The frame's ``axis`` (frame coordinates, default its z axis) along the world ``direction``: the angle
    θ [rad] between them, whatever the rotation about the direction ("point the gripper forward").

    Residual (2,): the rotation vector taking ``direction`` to the axis, in the plane perpendicular to
    ``direction`` (``‖r‖ = θ``); value θ; a task term held to the angular tolerance.
    """

    level = "task"
    has_target = True

    def __init__(self, frame: str, direction: Sequence[float], *, axis: Sequence[float] = (0.0, 0.0, 1.0),
                 name: str | None = None):
        self.frame = frame
        self.frames = (frame,)
        self.axis = unit_vector(axis, f"axis of direction term on {frame!r}")
        self.name = name or f"direction[{frame}]"
        self.set_target(direction)

    def set_target(self, direction: Sequence[float]) -> None:
        """Move the target direction (3,) [world]; it is normalized."""
        self.direction = unit_vector(direction, f"target direction of {self.frame!r}")
        self._touch()

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        b1, b2 = perpendicular_basis(self.direction)
        params = np.concatenate([self.axis, self.direction, b1, b2])
        return (Block(B.AXIS, B.NORM, 2, self.frames, params, tolerance=B.TOL_ANGULAR),)

    def __repr__(self) -> str:
        return f"Direction({self.frame!r}, {np.round(self.direction, 6).tolist()}, axis={self.axis.tolist()})"


class Cone(Direction):
    """The frame's ``axis`` within ``max_angle`` [rad] of the world ``direction`` (a cone around it): zero inside,
    the angle in excess outside ("keep the camera roughly level", BioIK's cone goal).

    Residual (1,): ``θ − max_angle`` when the axis is outside the cone, else 0 [rad]; a task term held to the
    angular tolerance.
    """

    def __init__(self, frame: str, direction: Sequence[float], max_angle: float, *,
                 axis: Sequence[float] = (0.0, 0.0, 1.0), name: str | None = None):
        if not (isinstance(max_angle, (int, float)) and np.isfinite(max_angle) and 0 <= max_angle <= np.pi):
            raise TaskError(f"cone max_angle must be an angle in [0, pi] rad; got {max_angle!r}")
        self.max_angle = float(max_angle)
        super().__init__(frame, direction, axis=axis, name=name or f"cone[{frame}]")

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        params = np.concatenate([self.axis, self.direction, [self.max_angle]])
        return (Block(B.CONE, B.NORM, 1, self.frames, params, tolerance=B.TOL_ANGULAR),)

    def __repr__(self) -> str:
        return (f"Cone({self.frame!r}, {np.round(self.direction, 6).tolist()}, max_angle={self.max_angle:g}, "
                f"axis={self.axis.tolist()})")


class LookAt(Term):
    """The frame's ``axis`` (frame coordinates, default its z axis) pointing at the world ``point`` [m]: a camera
    or a sensor aimed at a target, free to turn about its line of sight (BioIK's look-at goal).

    Residual (3,): ``R e − u`` with ``u`` the unit vector from the frame origin to the point; its norm is
    ``2 sin(θ/2)`` of the angle θ between the axis and the line of sight (the value; ≈ θ for small angles); a
    task term held to the angular tolerance.
    """

    level = "task"
    has_target = True

    def __init__(self, frame: str, point: Sequence[float], *, axis: Sequence[float] = (0.0, 0.0, 1.0),
                 name: str | None = None):
        self.frame = frame
        self.frames = (frame,)
        self.axis = unit_vector(axis, f"axis of look-at term on {frame!r}")
        self.name = name or f"look_at[{frame}]"
        self.set_target(point)

    def set_target(self, point: Sequence[float]) -> None:
        """Move the point looked at (3,) [m, world]."""
        self.point = as_vector(point, 3, f"look-at point of {self.frame!r}")
        self._touch()

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        return (Block(B.LOOK_AT, B.NORM, 3, self.frames, np.concatenate([self.axis, self.point]),
                      tolerance=B.TOL_ANGULAR),)

    def __repr__(self) -> str:
        return f"LookAt({self.frame!r}, {np.round(self.point, 6).tolist()}, axis={self.axis.tolist()})"
