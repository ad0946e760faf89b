"""Relative pose of two frames: two hands holding one object, the object's grasp poses moving with the hands."""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from ..compiled.native import matrix
from ..model.robot import Robot
from . import blocks as B
from .base import Term, TermEntry
from .kinds import BlockKind
from .lie import left_jacobian_inverse, rotation_log
from ..model.rotations import check_order
from .program import Block
from .workspace import RESIDUAL, views


def relative_local_residual(ws) -> int:
    """``R_aᵀ(p_b − p_a) − o`` (3) [m]; Jacobian ``R_aᵀ(∂v + v × ω_a)``, ``v = p_b − p_a``."""
    v = views(ws)
    block, row, n = v.blocks[ws.block], ws.row, ws.n
    p, fa, fb = block.params, block.fa, block.fb
    P, Jf = v.poses, v.jacobians
    v0, v1, v2 = P[fb, 9] - P[fa, 9], P[fb, 10] - P[fa, 10], P[fb, 11] - P[fa, 11]
    for c in range(3):  # R_aᵀ v: column c of R_a (row-major) dotted with v
        v.r[row + c] = P[fa, c] * v0 + P[fa, 3 + c] * v1 + P[fa, 6 + c] * v2 - v.params[p + c]
    if ws.mode != RESIDUAL:
        for i in range(n):
            o0, o1, o2 = Jf[fa, 3, i], Jf[fa, 4, i], Jf[fa, 5, i]
            q0 = Jf[fb, 0, i] - Jf[fa, 0, i] + v1 * o2 - v2 * o1  # ∂v + v × ω_a
            q1 = Jf[fb, 1, i] - Jf[fa, 1, i] + v2 * o0 - v0 * o2
            q2 = Jf[fb, 2, i] - Jf[fa, 2, i] + v0 * o1 - v1 * o0
            for c in range(3):
                v.J[row + c, i] = P[fa, c] * q0 + P[fa, 3 + c] * q1 + P[fa, 6 + c] * q2
    return 3


def relative_rotation_residual(ws) -> int:
    """``log(Mᵀ R_b)`` (3) [rad], ``M = R_a R_o``; Jacobian ``J_l⁻¹(r) Mᵀ (ω_b − ω_a)`` (a left perturbation of
    ``Mᵀ R_b`` by the relative angular velocity, exact to first order)."""
    v = views(ws)
    block, row, n = v.blocks[ws.block], ws.row, ws.n
    p, fa, fb = block.params, block.fa, block.fb
    P, Jf, params = v.poses, v.jacobians, v.params
    E9, L3 = v.scratch[9:18], matrix(v.scratch, 3, 3)
    for a in range(3):
        for c in range(3):  # E = Mᵀ R_b, M[k, a] = Σ_m R_a[k, m] R_o[m, a]
            e = 0.0
            for k in range(3):
                m = P[fa, 3 * k] * params[p + a] + P[fa, 3 * k + 1] * params[p + 3 + a] \
                    + P[fa, 3 * k + 2] * params[p + 6 + a]
                e += m * P[fb, 3 * k + c]
            E9[3 * a + c] = e
    rotation_log(E9, v.r[row : row + 3])
    if ws.mode == RESIDUAL:
        return 3
    left_jacobian_inverse(v.r[row : row + 3], L3)
    for k in range(3):  # E9 ← M (row-major)
        for a in range(3):
            E9[3 * k + a] = P[fa, 3 * k] * params[p + a] + P[fa, 3 * k + 1] * params[p + 3 + a] \
                + P[fa, 3 * k + 2] * params[p + 6 + a]
    for i in range(n):
        u0 = Jf[fb, 3, i] - Jf[fa, 3, i]
        u1 = Jf[fb, 4, i] - Jf[fa, 4, i]
        u2 = Jf[fb, 5, i] - Jf[fa, 5, i]
        m0 = E9[0] * u0 + E9[3] * u1 + E9[6] * u2  # Mᵀ u
        m1 = E9[1] * u0 + E9[4] * u1 + E9[7] * u2
        m2 = E9[2] * u0 + E9[5] * u1 + E9[8] * u2
        for a in range(3):
            v.J[row + a, i] = L3[a, 0] * m0 + L3[a, 1] * m1 + L3[a, 2] * m2
    return 3


#: Frame ``b``'s origin in frame ``a`` against an offset: ``R_aᵀ(p_b − p_a) − o`` (3) [m], params ``o`` (3); its
#: second order is left to Gauss-Newton.
RELATIVE_LOCAL = BlockKind("relative position in a frame", relative_local_residual)
#: Frame ``b``'s rotation in frame ``a`` against an offset: ``log((R_a R_o)ᵀ R_b)`` (3) [rad], params ``R_o`` (9,
#: row-major); its second order is left to Gauss-Newton.
RELATIVE_ROTATION = BlockKind("relative rotation", relative_rotation_residual)


class RelativePose(Term):
    """The pose of ``frame_b`` in ``frame_a`` held at ``offset`` (two hands holding one object: the object's grasp
    poses, moving with the hands wherever they go): ``‖R_aᵀ(p_b − p_a) − o‖ + sin(φ/2)``, ``φ`` the angle of
    ``R_oᵀ R_aᵀ R_b``. ``offset``: a ``pinocchio.SE3``, a 4x4 matrix or a ``(position, rotation)`` pair, in
    ``frame_a``'s coordinates.

    Residuals (3 + 3): the position error in ``frame_a`` [m] (linear tolerance) and the rotation vector [rad]
    (angular tolerance); their second order is left to Gauss-Newton in the Newton phase.
    """

    task_type, task_keys = "relative_pose", ("frame_a", "frame_b", "offset", "offset_rotation", "quaternion")
    #: the entry's keys, for the task-file reference (docs/taskfile.md)
    task_doc: ClassVar[dict[str, str]] = {
        'frame_a': 'the frame measured in',
        'frame_b': 'the frame held',
        'offset': "frame_b's position in frame_a [m]",
        'offset_rotation': "frame_b's rotation in frame_a (default the identity; as orientation's target)",
        'quaternion': 'the order of 4 numbers: "xyzw" or "wxyz"'
    }
    #: a robot, and an entry of this type for it (checked by tests/test_taskfile_doc.py)
    task_example: ClassVar[tuple[str, str]] = ('youbot_dual', 'type = "relative_pose"\nframe_a = "arm1_ee"\nframe_b = "arm2_ee"\noffset = [0.0, 0.0, 0.2]\noffset_rotation = "Rx(pi)"')

    @classmethod
    def from_entry(cls, entry: TermEntry) -> RelativePose:
        """``offset``: the position of ``frame_b`` in ``frame_a``; ``offset_rotation``: its rotation (default the
        identity; 4 numbers with ``quaternion`` naming their order)."""
        rotation = entry.value("offset_rotation") if entry.has("offset_rotation") else np.eye(3)
        return cls(entry.text("frame_a"), entry.text("frame_b"), (entry.value("offset"), rotation),
                   quaternion=entry.text("quaternion") if entry.has("quaternion") else None, name=entry.name)

    level = "task"
    has_target = True
    fixed_layout = True

    def __init__(self, frame_a: str, frame_b: str, offset, *, quaternion: str | None = None,
                 name: str | None = None):
        self.frames = (frame_a, frame_b)
        self.name = name or f"relative_pose[{frame_a}, {frame_b}]"
        self.quaternion = check_order(quaternion, self.name)
        self.set_target(offset)

    def set_target(self, offset) -> None:
        """Move the offset (pose of ``frame_b`` in ``frame_a``)."""
        from .pose import pose_from

        self.position, self.rotation = pose_from(offset, f"offset of {self.name}", self.quaternion)
        self._touch()

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        return (Block(RELATIVE_LOCAL, B.NORM, 3, self.frames, self.position, tolerance=B.TOL_LINEAR),
                Block(RELATIVE_ROTATION, B.HALFSIN, 3, self.frames, self.rotation.ravel(), tolerance=B.TOL_ANGULAR))
