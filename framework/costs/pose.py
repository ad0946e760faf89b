"""Pose of a frame: position and orientation at once, from a ``pinocchio.SE3`` or a 4x4 homogeneous matrix."""

from __future__ import annotations

from typing import ClassVar

from collections.abc import Callable

import numpy as np
import pinocchio as pin

from ..errors import TaskError
from ..model.robot import Robot
from ..model.rotations import check_order, pack_transform, rotation_defects, rotation_from
from . import blocks as B
from ..model.reach import reach_hint
from .base import Term, TermEntry, as_vector, finite_rows
from .orientation import ORIENTATION
from .position import POSITION
from .program import Block


def pose_parameters(target, what: str | Callable[[], str], quaternion: str | None = None) -> np.ndarray:
    """``(12,)``: the position then the row-major rotation of a ``pinocchio.SE3``, a 4x4 homogeneous matrix or a
    ``(position, rotation)`` pair (rotation in any form :func:`~framework.model.rotations.rotation_from` takes,
    4 numbers in the ``quaternion`` order); validated (``what`` names it in errors: a string, or a callable making it
    only when there is one)."""
    out = np.empty(12)
    if type(target) is pin.SE3 and pack_transform(target.homogeneous, out) == 0:  # the common case
        return out
    what = what if isinstance(what, str) else what()
    if isinstance(target, tuple) and len(target) == 2:
        out[:3] = as_vector(target[0], 3, f"{what} position")
        out[3:] = rotation_from(target[1], f"{what} rotation", quaternion).ravel()
        return out
    if isinstance(target, pin.SE3):
        T = target.homogeneous  # a new array
    else:
        try:
            T = np.array(target, dtype=float)
        except (TypeError, ValueError):
            raise TaskError(f"{what} must be a pinocchio.SE3, a 4x4 matrix or a (position, rotation) pair") from None
        if T.shape != (4, 4):
            raise TaskError(f"{what} must be a pinocchio.SE3, a 4x4 matrix or a (position, rotation) pair; "
                            f"got shape {T.shape}")
    defect = pack_transform(T, out)
    if defect == 1:
        raise TaskError(f"{what} holds NaN or inf: {T.tolist()}")
    if defect == 2:
        raise TaskError(f"{what} is not a rotation matrix (RᵀR ≠ I or det < 0)")
    if defect == 3:
        raise TaskError(f"{what}: the last row of a homogeneous matrix must be [0, 0, 0, 1]; got {T[3].tolist()}")
    return out


def pose_from(target, what: str, quaternion: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(position (3,), rotation (3, 3))`` of what :func:`pose_parameters` reads; validated."""
    p = pose_parameters(target, what, quaternion)
    return p[:3], p[3:].reshape(3, 3)


class Pose(Term):
    """Position and orientation of a frame: ``‖p − t‖ + sin(φ/2)`` (the sum of :class:`Position` and
    :class:`Orientation` of the same target).

    Residual ``(p − t, log(R_tᵀ R))`` (6,); success holds the distance to the linear tolerance [m] and the angle
    φ to the angular one [rad]. ``target``: a ``pinocchio.SE3``, a 4x4 homogeneous matrix, or a ``(position,
    rotation)`` pair, in the world frame; the rotation in any form :class:`Orientation` takes (4 numbers with
    ``quaternion=`` naming their order, kept for the targets the term is moved to).
    """

    task_type, task_keys = "pose", ("frame", "position", "rotation", "quaternion")
    #: the entry's keys, for the task-file reference (docs/taskfile.md)
    task_doc: ClassVar[dict[str, str]] = {
        'frame': 'the frame placed',
        'position': 'its target position [m, world]',
        'rotation': "its target rotation [world] (as orientation's target)",
        'quaternion': 'the order of 4 numbers: "xyzw" or "wxyz"'
    }
    #: a robot, and an entry of this type for it (checked by tests/test_taskfile_doc.py)
    task_example: ClassVar[tuple[str, str]] = ('puma560', 'type = "pose"\nframe = "ee"\nposition = [0.4, 0.1, 0.3]\nrotation = [0, 0.7071068, 0, 0.7071068]\nquaternion = "xyzw"')

    @classmethod
    def from_entry(cls, entry: TermEntry) -> Pose:
        return cls(entry.text("frame"), (entry.value("position"), entry.value("rotation")),
                   quaternion=entry.text("quaternion") if entry.has("quaternion") else None, name=entry.name)

    level = "task"
    has_target = True
    fixed_layout = True

    def __init__(self, frame: str, target, *, quaternion: str | None = None, name: str | None = None):
        self.frame = frame
        self.frames = (frame,)
        self.name = name or f"pose[{frame}]"
        # (the common case names no order: no message is made for it)
        self.quaternion = quaternion if quaternion is None else check_order(quaternion,
                                                                            f"pose target of {frame!r}")
        self.set_target(target)

    def set_target(self, target) -> None:
        """Move the target pose (``pinocchio.SE3``, 4x4 matrix or ``(position, rotation)``)."""
        self._parameters = pose_parameters(target, lambda: f"pose target of {self.frame!r}", self.quaternion)
        self._touch()

    @property
    def position(self) -> np.ndarray:
        """``(3,)`` the target position [m] (a view of the packed parameters)."""
        return self._parameters[:3]

    @property
    def rotation(self) -> np.ndarray:
        """``(3, 3)`` the target rotation (a view of the packed parameters)."""
        return self._parameters[3:].reshape(3, 3)

    def why_unmet(self, robot: Robot, x: np.ndarray) -> str | None:
        return reach_hint(robot, self.frame, self.position)

    def frame_target(self) -> tuple[str, np.ndarray, np.ndarray]:
        return self.frame, self._parameters[:3], self._parameters[3:].reshape(3, 3)

    def pose_vector(self) -> np.ndarray:
        """``(12,)`` the target's position [m] and row-major rotation (the term's own array: read, do not write)."""
        return self._parameters

    def parameters(self, robot: Robot) -> np.ndarray:
        return self._parameters

    def target_parameters(self, robot: Robot, targets) -> np.ndarray:
        """``(B, 12)`` positions and row-major rotations of a batch of poses: ``(B, 4, 4)`` homogeneous matrices
        are validated at once (as :meth:`set_target` validates one); other forms one by one."""
        if not (isinstance(targets, np.ndarray) and targets.ndim == 3 and targets.shape[1:] == (4, 4)):
            return super().target_parameters(robot, targets)
        what = f"pose targets of {self.frame!r}"
        T = finite_rows(targets, (4, 4), what)
        R = T[:, :3, :3]
        bad = np.flatnonzero((np.abs(T[:, 3] - [0.0, 0.0, 0.0, 1.0]).max(axis=1) > 1e-9) | rotation_defects(R))
        if bad.size:
            raise TaskError(f"{what}: item {bad[0]} is not a homogeneous transform (last row [0, 0, 0, 1], a "
                            f"rotation with RᵀR = I and det > 0)")
        return np.concatenate([T[:, :3, 3], R.reshape(-1, 9)], axis=1)

    @property
    def target(self) -> pin.SE3:
        """The target as a ``pinocchio.SE3``."""
        return pin.SE3(self.rotation, self.position)

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        p = self._parameters
        return (Block(POSITION, B.NORM, 3, self.frames, p[:3], tolerance=B.TOL_LINEAR),
                Block(ORIENTATION, B.HALFSIN, 3, self.frames, p[3:], tolerance=B.TOL_ANGULAR))

    def target_points(self, robot: Robot, x: np.ndarray) -> dict[str, np.ndarray]:
        return {self.frame: self.position}

    def __repr__(self) -> str:
        return f"Pose({self.frame!r}, position={np.round(self.position, 6).tolist()})"

