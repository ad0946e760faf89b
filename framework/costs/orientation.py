"""Orientation of a frame: the rotation between the frame and a target (paper 002 eq. 6-15).

Residual ``r = log(R_targetᵀ R(x))`` (3,) [rad]: its norm is the angle φ ∈ [0, π] of the relative rotation.
Value ``ρ(r) = sin(‖r‖/2)`` — the norm of the relative quaternion's vector part, paper 002's measure: 0 for
equal rotations, 1 for a half turn. Success holds the angle ``‖r‖`` to the angular tolerance [rad].
A quaternion target given as 4 numbers names its order (``quaternion="xyzw"`` or ``"wxyz"``, :mod:`framework.model.rotations`).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from ..errors import TaskError
from ..compiled.native import internal, matrix
from ..model.robot import Robot
from ..model.rotations import check_order, rotation_defects, rotation_from
from . import blocks as B
from .base import Term, TermEntry, finite_rows
from .curvature import chain_curvature
from .kinds import BlockKind
from .lie import left_jacobian_inverse, rotation_log
from .program import Block
from .workspace import JACOBIAN_ONLY, RESIDUAL, views


def orientation_residual(ws) -> int:
    """``log(R_tᵀ R_a)`` (3) [rad], its norm the angle; Jacobian ``J_l⁻¹(r) R_tᵀ J_ω,a``. In mode
    :data:`~.workspace.JACOBIAN_ONLY` the Jacobian comes from the rows already there (no second logarithm)."""
    v = views(ws)
    block, row = v.blocks[ws.block], ws.row
    p, fa = block.params, block.fa
    if ws.mode != JACOBIAN_ONLY:
        E = v.scratch[9:18]
        for a in range(3):
            for c in range(3):  # E = R_tᵀ R
                E[3 * a + c] = (v.params[p + a] * v.poses[fa, c] + v.params[p + 3 + a] * v.poses[fa, 3 + c]
                                + v.params[p + 6 + a] * v.poses[fa, 6 + c])
        rotation_log(E, v.r[row : row + 3])
    if ws.mode != RESIDUAL:
        orientation_jacobian(v.jacobians, fa, v.params, p, v.r, v.J, row, ws.n, matrix(v.scratch, 3, 3))
    return 3


@internal(inline=True)
def orientation_jacobian(jacobians, fa, params, p, r, J, row, n, L3) -> None:
    """``J[row:row + 3] = J_l⁻¹(r) R_tᵀ J_ω`` of an orientation block with residual ``r[row:row + 3] = log(R_tᵀ R)``
    (``R_t``: the target rotation, row-major at ``params[p:p + 9]``); ``L3 (3, 3)`` scratch."""
    left_jacobian_inverse(r[row : row + 3], L3)
    for a in range(3):
        m0 = L3[a, 0] * params[p] + L3[a, 1] * params[p + 1] + L3[a, 2] * params[p + 2]
        m1 = L3[a, 0] * params[p + 3] + L3[a, 1] * params[p + 4] + L3[a, 2] * params[p + 5]
        m2 = L3[a, 0] * params[p + 6] + L3[a, 1] * params[p + 7] + L3[a, 2] * params[p + 8]
        for i in range(n):  # row a of J_l⁻¹ R_tᵀ times J_ω
            J[row + a, i] = m0 * jacobians[fa, 3, i] + m1 * jacobians[fa, 4, i] + m2 * jacobians[fa, 5, i]


def orientation_second_order(ws) -> int:
    """``Σ μ_c ∇²r_c`` of ``r = log(R_tᵀ R_a)``: ``½ μ'·(ω_i × ω_j)`` over the chain with ``μ' = R_t J_l⁻ᵀ μ`` —
    exact on the target (``r = 0``)."""
    v = views(ws)
    block, row, mu = v.blocks[ws.block], ws.row, v.multipliers
    p, fa = block.params, block.fa
    L = matrix(v.scratch, 3, 3)
    left_jacobian_inverse(v.r[row : row + 3], L)
    v0 = L[0, 0] * mu[0] + L[1, 0] * mu[1] + L[2, 0] * mu[2]  # J_l⁻ᵀ μ
    v1 = L[0, 1] * mu[0] + L[1, 1] * mu[1] + L[2, 1] * mu[2]
    v2 = L[0, 2] * mu[0] + L[1, 2] * mu[1] + L[2, 2] * mu[2]
    m0 = v.params[p] * v0 + v.params[p + 1] * v1 + v.params[p + 2] * v2
    m1 = v.params[p + 3] * v0 + v.params[p + 4] * v1 + v.params[p + 5] * v2
    m2 = v.params[p + 6] * v0 + v.params[p + 7] * v1 + v.params[p + 8] * v2
    chain_curvature(fa, 0.5 * m0, 0.5 * m1, 0.5 * m2, v.jacobians[fa, 3:6], v.jacobians, v.chain_ptr, v.chain_idx,
                    v.hessian)
    return 0


#: A frame's rotation against a world rotation: ``log(R_tᵀ R_a)`` (3) [rad], params ``R_t`` (9, row-major).
ORIENTATION = BlockKind("orientation", orientation_residual, orientation_second_order)


class Orientation(Term):
    """``sin(φ/2)`` (unitless) for the angle φ between the frame's rotation and the target's.

    The target (world frame) is a ``(3, 3)`` rotation matrix, a ``pinocchio.Quaternion``, a scipy ``Rotation``, a
    ``pinocchio.SE3`` or 4x4 matrix (its rotation), or 4 numbers with their order named: ``quaternion="xyzw"``
    (scipy, ROS messages) or ``quaternion="wxyz"`` (``pinocchio.Quaternion(w, x, y, z)``, Eigen, MuJoCo); the term
    keeps that order for the targets it is moved to.
    """

    task_type, task_keys, category = "orientation", ("frame", "target", "quaternion"), "orientation"
    #: the entry's keys, for the task-file reference (docs/taskfile.md)
    task_doc: ClassVar[dict[str, str]] = {
        'frame': 'the frame turned',
        'target': 'its rotation [world]: a 3x3 matrix, an expression such as "Ry(pi/2)", or 4 numbers with quaternion',
        'quaternion': 'the order of 4 numbers: "xyzw" or "wxyz"'
    }
    #: a robot, and an entry of this type for it (checked by tests/test_taskfile_doc.py)
    task_example: ClassVar[tuple[str, str]] = ('puma560', 'type = "orientation"\nframe = "ee"\ntarget = "Ry(pi/2)"')

    @classmethod
    def from_entry(cls, entry: TermEntry) -> Orientation:
        return cls(entry.text("frame"), entry.value("target"),
                   quaternion=entry.text("quaternion") if entry.has("quaternion") else None, name=entry.name)

    level = "task"
    has_target = True
    fixed_layout = True

    def __init__(self, frame: str, target: Any, *, quaternion: str | None = None, name: str | None = None):
        self.frame = frame
        self.frames = (frame,)
        self.name = name or f"orientation[{frame}]"
        # (the common case names no order: no message is made for it)
        self.quaternion = quaternion if quaternion is None else check_order(quaternion,
                                                                            f"orientation target of {frame!r}")
        self.set_target(target)

    def set_target(self, target: Any) -> None:
        """Change the target rotation (world frame), in any form the constructor takes (4 numbers in the term's
        ``quaternion`` order)."""
        self.target = rotation_from(target, f"orientation target of {self.frame!r}", self.quaternion)
        self._touch()

    def frame_target(self) -> tuple[str, None, np.ndarray]:
        return self.frame, None, self.target

    def target_parameters(self, robot: Robot, targets) -> np.ndarray:
        """``(B, 9)`` row-major target rotations of a batch: ``(B, 3, 3)`` matrices are validated at once (as
        :meth:`set_target` validates one); other forms one by one."""
        if not (isinstance(targets, np.ndarray) and targets.ndim == 3 and targets.shape[1:] == (3, 3)):
            return super().target_parameters(robot, targets)
        what = f"orientation targets of {self.frame!r}"
        R = finite_rows(targets, (3, 3), what)
        bad = np.flatnonzero(rotation_defects(R))
        if bad.size:
            raise TaskError(f"{what}: item {bad[0]} is not a rotation matrix (RᵀR = I, det > 0)")
        return R.reshape(-1, 9)

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        return (Block(ORIENTATION, B.HALFSIN, 3, self.frames, self.target.ravel(), tolerance=B.TOL_ANGULAR),)
