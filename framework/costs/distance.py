"""Distance of a frame to another frame or to a point, held within bounds (at least, at most, or exactly)."""

from __future__ import annotations

from typing import ClassVar

from collections.abc import Sequence

import numpy as np

from ..errors import TaskError
from ..compiled.native import internal
from ..model.robot import Robot
from . import blocks as B
from .base import Term, TermEntry, as_vector
from .curvature import position_curvature, projected_curvature
from .kinds import BlockKind
from .program import Block
from .workspace import RESIDUAL, views


@internal
def distance_direction(poses, fa, fb, params, p):
    """``(u₀, u₁, u₂, ‖v‖)``: ``v = p_a − p_b`` (or ``p_a −`` the block's point when ``fb < 0``), ``u = v/‖v‖`` (zero
    when ``v = 0``)."""
    v0 = poses[fa, 9] - (poses[fb, 9] if fb >= 0 else params[p])
    v1 = poses[fa, 10] - (poses[fb, 10] if fb >= 0 else params[p + 1])
    v2 = poses[fa, 11] - (poses[fb, 11] if fb >= 0 else params[p + 2])
    dist = np.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    if dist > 0.0:
        return v0 / dist, v1 / dist, v2 / dist, dist
    return 0.0, 0.0, 0.0, dist


def distance_residual(ws) -> int:
    """``‖v‖ − hi`` above the band, ``‖v‖ − lo`` below it, else 0 (1) [m]; Jacobian ``uᵀ ∂v`` outside the band."""
    v = views(ws)
    block, row, n = v.blocks[ws.block], ws.row, ws.n
    p, fa, fb, Jf = block.params, block.fa, block.fb, v.jacobians
    u0, u1, u2, dist = distance_direction(v.poses, fa, fb, v.params, p)
    lo, hi = v.params[p + 3], v.params[p + 4]
    v.r[row] = dist - hi if dist > hi else (dist - lo if dist < lo else 0.0)
    if ws.mode != RESIDUAL:
        active = v.r[row] != 0.0 and dist > 0.0
        for i in range(n):
            g = 0.0
            if active:
                g = u0 * Jf[fa, 0, i] + u1 * Jf[fa, 1, i] + u2 * Jf[fa, 2, i]
                if fb >= 0:
                    g -= u0 * Jf[fb, 0, i] + u1 * Jf[fb, 1, i] + u2 * Jf[fb, 2, i]
            v.J[row, i] = g
    return 1


def distance_second_order(ws) -> int:
    """``μ[Dᵀ(I − uuᵀ)D/‖v‖ + Σ u_c ∇²v_c]``, ``D = ∂v``, outside the band (inside: none)."""
    v = views(ws)
    block, row, mu, n = v.blocks[ws.block], ws.row, v.multipliers, ws.n
    p, fa, fb, Jf = block.params, block.fa, block.fb, v.jacobians
    u0, u1, u2, dist = distance_direction(v.poses, fa, fb, v.params, p)
    if dist <= 0.0 or v.r[row] == 0.0:
        return 0
    u = np.array((u0, u1, u2))
    position_curvature(fa, mu[0] * u[0], mu[0] * u[1], mu[0] * u[2], Jf, v.chain_ptr, v.chain_idx, v.hessian)
    if fb >= 0:
        position_curvature(fb, -mu[0] * u[0], -mu[0] * u[1], -mu[0] * u[2], Jf, v.chain_ptr, v.chain_idx, v.hessian)
    D = np.zeros((3, n))
    for c in range(3):
        for i in range(n):
            D[c, i] = Jf[fa, c, i] - (Jf[fb, c, i] if fb >= 0 else 0.0)
    projected_curvature(mu[0] / dist, u, D, v.hessian)
    return 0


#: A frame's distance to another frame (``b``) or to a point, held in a band ``[lo, hi]`` (1) [m], a hinge on
#: each side; params ``point, lo, hi`` (5).
DISTANCE = BlockKind("distance", distance_residual, distance_second_order, hinge=True)


class Distance(Term):
    """``‖p_frame − p_to‖`` [m] within ``[at_least, at_most]``: ``to`` is another frame's name or a point
    (3,) [m, world]; ``exactly=d`` sets both bounds (keep two hands 30 cm apart, stay 10 cm from a point).

    Residual (1,): the distance minus the bound it crosses (0 inside the band) [m]; a task term held to the
    linear tolerance.
    """

    task_type, task_keys = "distance", ("frame", "to_frame", "to_point", "at_least", "at_most", "exactly")
    #: the entry's keys, for the task-file reference (docs/taskfile.md)
    task_doc: ClassVar[dict[str, str]] = {
        'frame': 'the frame measured from',
        'to_frame': 'another frame (or to_point)',
        'to_point': 'a point [m, world] (or to_frame)',
        'at_least': 'lower bound [m]',
        'at_most': 'upper bound [m]',
        'exactly': 'the distance [m] (instead of bounds)'
    }
    #: a robot, and an entry of this type for it (checked by tests/test_taskfile_doc.py)
    task_example: ClassVar[tuple[str, str]] = ('puma560', 'type = "distance"\nframe = "ee"\nto_point = [0, 0, 0]\nat_least = 0.3')

    @classmethod
    def from_entry(cls, entry: TermEntry) -> Distance:
        if entry.has("to_frame") == entry.has("to_point"):
            raise TaskError(f"{entry.where} needs exactly one of to_frame and to_point")
        bounds = {k: entry.number(k) for k in ("at_least", "at_most", "exactly") if entry.has(k)}
        to = entry.text("to_frame") if entry.has("to_frame") else entry.value("to_point")
        return cls(entry.text("frame"), to, name=entry.name, **bounds)

    level = "task"
    has_target = True

    def __init__(self, frame: str, to: str | Sequence[float], *, at_least: float | None = None,
                 at_most: float | None = None, exactly: float | None = None, name: str | None = None):
        if exactly is not None:
            if at_least is not None or at_most is not None:
                raise TaskError("distance: give exactly= alone, or at_least= / at_most=")
            at_least = at_most = exactly
        if at_least is None and at_most is None:
            raise TaskError("distance needs at_least=, at_most= or exactly= [m]")
        lo = 0.0 if at_least is None else float(at_least)
        hi = np.inf if at_most is None else float(at_most)
        if not (np.isfinite(lo) and lo >= 0 and (np.isinf(hi) or np.isfinite(hi)) and hi >= lo):
            raise TaskError(f"distance bounds must satisfy 0 <= at_least <= at_most; got {at_least!r}, {at_most!r}")
        self.frame, self.bounds = frame, (lo, hi)
        self.to_frame = to if isinstance(to, str) else None
        self.frames = (frame, to) if self.to_frame else (frame,)
        self.name = name or f"distance[{frame}, {to if self.to_frame else 'point'}]"
        self.point = np.zeros(3)
        if self.to_frame is None:
            self.set_target(to)

    def set_target(self, point: Sequence[float]) -> None:
        """Move the point (3,) [m, world] the distance is measured to (a frame-to-frame distance has none)."""
        if self.to_frame is not None:
            raise TaskError(f"{self.name} measures to frame {self.to_frame!r}: it has no point to move")
        self.point = as_vector(point, 3, lambda: f"point of {self.name}")
        self._touch()

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        params = np.concatenate([self.point, [self.bounds[0], min(self.bounds[1], 1e300)]])
        return (Block(DISTANCE, B.NORM, 1, self.frames, params, tolerance=B.TOL_LINEAR),)

    def __repr__(self) -> str:
        return f"Distance({self.frame!r}, {self.to_frame or self.point.tolist()}, bounds={self.bounds})"
