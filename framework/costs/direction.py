"""Direction of a frame axis: a tool pointing along a world direction, free to turn about it."""

from __future__ import annotations

from typing import ClassVar

from collections.abc import Sequence

import numpy as np

from ..errors import TaskError
from ..compiled.native import internal
from ..model.robot import Robot
from . import blocks as B
from .base import Term, TermEntry
from .curvature import chain_curvature
from .kinds import BlockKind
from .program import Block
from .workspace import RESIDUAL, views


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


@internal
def axis_world(poses, fa, params, p):
    """``w = R_a e`` (3,) and ``d`` (3,) of a block whose parameters start with the frame axis ``e`` and the world
    direction ``d``."""
    w0 = poses[fa, 0] * params[p] + poses[fa, 1] * params[p + 1] + poses[fa, 2] * params[p + 2]
    w1 = poses[fa, 3] * params[p] + poses[fa, 4] * params[p + 1] + poses[fa, 5] * params[p + 2]
    w2 = poses[fa, 6] * params[p] + poses[fa, 7] * params[p + 1] + poses[fa, 8] * params[p + 2]
    return w0, w1, w2, params[p + 3], params[p + 4], params[p + 5]


def axis_residual(ws) -> int:
    """``r = Bᵀ v``, ``v = f(θ) (d × w)``, ``f = θ/sinθ`` (so ``‖r‖ = θ``, the angle between ``w = R_a e`` and
    ``d``), and its Jacobian ``dv = f (d × dw) − g (d·dw)(d × w)`` with ``dw = ω_i × w``,
    ``g = f'/sinθ = (sinθ − θcosθ)/sin³θ`` (series below 1e-3 rad). Exactly opposite (θ = π, no rotation axis),
    ``r = (π, 0)`` and the Jacobian uses ``f = 1``."""
    v = views(ws)
    block, row, n = v.blocks[ws.block], ws.row, ws.n
    p, fa, params, Jf = block.params, block.fa, v.params, v.jacobians
    w0, w1, w2, d0, d1, d2 = axis_world(v.poses, fa, params, p)
    c0, c1, c2 = d1 * w2 - d2 * w1, d2 * w0 - d0 * w2, d0 * w1 - d1 * w0
    s = np.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
    co = d0 * w0 + d1 * w1 + d2 * w2
    theta = np.arctan2(s, co)
    if s < 1e-12 and co < 0.0:  # opposite
        f, g = 1.0, 0.0
        v.r[row], v.r[row + 1] = np.pi, 0.0
    else:
        if s < 1e-3 and co > 0.0:  # θ < 1e-3: the series of θ/sinθ and (sinθ − θcosθ)/sin³θ
            t2 = theta * theta
            f, g = 1.0 + t2 / 6.0 + 7.0 * t2 * t2 / 360.0, 1.0 / 3.0 + 2.0 * t2 / 15.0
        else:
            f, g = theta / s, (s - theta * co) / (s * s * s)
        v.r[row] = f * (params[p + 6] * c0 + params[p + 7] * c1 + params[p + 8] * c2)
        v.r[row + 1] = f * (params[p + 9] * c0 + params[p + 10] * c1 + params[p + 11] * c2)
    if ws.mode == RESIDUAL:
        return 2
    for i in range(n):
        o0, o1, o2 = Jf[fa, 3, i], Jf[fa, 4, i], Jf[fa, 5, i]
        e0, e1, e2 = o1 * w2 - o2 * w1, o2 * w0 - o0 * w2, o0 * w1 - o1 * w0  # dw = ω × w
        dd = d0 * e0 + d1 * e1 + d2 * e2
        u0 = f * (d1 * e2 - d2 * e1) - g * dd * c0
        u1 = f * (d2 * e0 - d0 * e2) - g * dd * c1
        u2 = f * (d0 * e1 - d1 * e0) - g * dd * c2
        v.J[row, i] = params[p + 6] * u0 + params[p + 7] * u1 + params[p + 8] * u2
        v.J[row + 1, i] = params[p + 9] * u0 + params[p + 10] * u1 + params[p + 11] * u2
    return 2


def axis_second_order(ws) -> int:
    """``Σ μ·∇²r = m·∂²w``, ``m = (Bμ) × d``, ``∂²w/∂x_i∂x_j = ω_i × (ω_j × w)`` for ``i`` before ``j``."""
    v = views(ws)
    block, mu, n = v.blocks[ws.block], v.multipliers, ws.n
    p, fa, params, Jf = block.params, block.fa, v.params, v.jacobians
    w0, w1, w2, d0, d1, d2 = axis_world(v.poses, fa, params, p)
    a0 = mu[0] * params[p + 6] + mu[1] * params[p + 9]
    a1 = mu[0] * params[p + 7] + mu[1] * params[p + 10]
    a2 = mu[0] * params[p + 8] + mu[1] * params[p + 11]
    dw = np.empty((3, n))  # ∂w/∂x_j = ω_j × w: the axis moves like a point at w
    for j in range(n):
        vx, vy, vz = Jf[fa, 3, j], Jf[fa, 4, j], Jf[fa, 5, j]
        dw[0, j], dw[1, j], dw[2, j] = vy * w2 - vz * w1, vz * w0 - vx * w2, vx * w1 - vy * w0
    chain_curvature(fa, a1 * d2 - a2 * d1, a2 * d0 - a0 * d2, a0 * d1 - a1 * d0, dw, Jf, v.chain_ptr, v.chain_idx,
                    v.hessian)
    return 0


#: A frame axis ``e`` along a world direction ``d``, free to turn about it: the rotation vector taking ``d`` to
#: ``R_a e`` in a basis ``(b₁, b₂)`` of the plane perpendicular to ``d`` (2) [rad]; params ``e, d, b₁, b₂`` (12).
AXIS = BlockKind("axis direction", axis_residual, axis_second_order)


class Direction(Term):
    """The frame's ``axis`` (frame coordinates, default its z axis) along the world ``direction``: the angle
    θ [rad] between them, whatever the rotation about the direction ("point the gripper forward").

    Residual (2,): the rotation vector taking ``direction`` to the axis, in the plane perpendicular to
    ``direction`` (``‖r‖ = θ``); value θ; a task term held to the angular tolerance.
    """

    task_type, task_keys = "direction", ("frame", "direction", "axis")
    #: the entry's keys, for the task-file reference (docs/taskfile.md)
    task_doc: ClassVar[dict[str, str]] = {
        'frame': 'the frame whose axis is aimed',
        'direction': 'the direction [world] (3 numbers)',
        'axis': "the frame's axis [frame] (default [0, 0, 1])"
    }
    #: a robot, and an entry of this type for it (checked by tests/test_taskfile_doc.py)
    task_example: ClassVar[tuple[str, str]] = ('puma560', 'type = "direction"\nframe = "ee"\ndirection = [0, 0, -1]')

    @classmethod
    def from_entry(cls, entry: TermEntry) -> Direction:
        return cls(entry.text("frame"), entry.value("direction"), axis=entry.value("axis", (0.0, 0.0, 1.0)),
                   name=entry.name)

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
        return (Block(AXIS, B.NORM, 2, self.frames, params, tolerance=B.TOL_ANGULAR),)

    def __repr__(self) -> str:
        return f"Direction({self.frame!r}, {np.round(self.direction, 6).tolist()}, axis={self.axis.tolist()})"
