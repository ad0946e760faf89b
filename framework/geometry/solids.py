"""Solids the compiled collision kernels measure exactly — a sphere, box, capsule or half-space — as parameter
rows, and the signed distance of a point to one.

A solid's row ``(16,)``: its code (:data:`SPHERE`, :data:`BOX`, :data:`CAPSULE`, :data:`HALFSPACE`), its rotation
``R`` (row-major) and centre ``c`` [m] in the frame it is given in, and three dims [m]: a sphere's radius; a box's
half sides; a capsule's radius and half length along its z axis; nothing for a half-space (the solid
``q_z <= 0`` of the point ``q = Rᵀ(point − c)`` in the solid's frame). Obstacles (:mod:`framework.geometry.scene`), links'
own boxes and capsules (:meth:`framework.geometry.collision.RobotShape.solids`), the ``SOLIDS`` blocks of the collision terms
(:mod:`framework.costs.sphere_rows`) and the exact check's broad phase (:mod:`framework.geometry.broad_phase`) all
read this one definition.
"""

from __future__ import annotations

from collections.abc import Sequence

from ..compiled.native import internal
import numpy as np

#: Solid codes (a row's first entry).
SPHERE, BOX, CAPSULE, HALFSPACE = range(4)
#: Length of a solid's row.
ROW = 16


def solid_row(code: int, rotation: np.ndarray, center: np.ndarray, dims: Sequence[float]) -> np.ndarray:
    """One solid's row ``(16,)``: ``code``, ``rotation`` ``(3, 3)`` (row-major), ``center`` ``(3,)`` [m], ``dims``
    (three, [m])."""
    return np.concatenate([[float(code)], np.asarray(rotation, dtype=float).ravel(), np.asarray(center, dtype=float),
                           np.asarray(dims, dtype=float)])


def holding_capsule(points: np.ndarray) -> np.ndarray:
    """The row (:func:`solid_row`) of a capsule holding every one of ``points`` ``(k, 3)`` [m] (so their convex
    hull: a capsule is convex), in their frame: its axis along their principal direction, through the middle of
    their extent across it; the radius their largest distance from the axis, the half length the least that holds
    them all."""
    points = np.asarray(points, dtype=float)
    mean = points.mean(axis=0)
    axes = np.linalg.eigh(np.cov((points - mean).T))[1][:, ::-1]  # columns: principal directions, largest first
    rotation = np.column_stack([axes[:, 1], np.cross(axes[:, 0], axes[:, 1]), axes[:, 0]])  # z: the axis
    local = (points - mean) @ rotation
    middle = (local.min(axis=0) + local.max(axis=0)) / 2
    middle_xy = np.array([middle[0], middle[1], 0.0])
    across = np.hypot(local[:, 0] - middle[0], local[:, 1] - middle[1])
    radius = float(across.max())
    along = np.abs(local[:, 2] - middle[2])
    half = float(np.max(along - np.sqrt(np.maximum(radius ** 2 - across ** 2, 0.0)), initial=0.0))
    return solid_row(CAPSULE, rotation, mean + rotation @ (middle_xy + [0.0, 0.0, middle[2]]),
                     [radius * (1 + 1e-9) + 1e-12, max(half, 0.0), 0.0])


@internal(inline=True)
def solid_distance(x, y, z, params, p, g) -> float:
    """Signed distance [m] of the point ``(x, y, z)`` to the solid whose row (:func:`solid_row`) starts at
    ``params[p]`` (negative inside), and its gradient into ``g[:3]``, both in the frame the row is given in.
    Inside a box the gradient is the nearest face's normal."""
    solid = int(params[p])
    v0, v1, v2 = x - params[p + 10], y - params[p + 11], z - params[p + 12]
    q0 = params[p + 1] * v0 + params[p + 4] * v1 + params[p + 7] * v2  # Rᵀ v
    q1 = params[p + 2] * v0 + params[p + 5] * v1 + params[p + 8] * v2
    q2 = params[p + 3] * v0 + params[p + 6] * v1 + params[p + 9] * v2
    d0, d1, d2 = params[p + 13], params[p + 14], params[p + 15]
    l0, l1, l2 = 0.0, 0.0, 0.0  # the gradient in the solid's frame
    if solid == HALFSPACE:
        sd, l2 = q2, 1.0
    elif solid == BOX:
        a0, a1, a2 = abs(q0) - d0, abs(q1) - d1, abs(q2) - d2
        o0, o1, o2 = max(a0, 0.0), max(a1, 0.0), max(a2, 0.0)
        outside = np.sqrt(o0 * o0 + o1 * o1 + o2 * o2)
        s0, s1, s2 = (1.0 if q0 >= 0.0 else -1.0), (1.0 if q1 >= 0.0 else -1.0), (1.0 if q2 >= 0.0 else -1.0)
        if outside > 0.0:
            sd = outside
            l0, l1, l2 = s0 * o0 / outside, s1 * o1 / outside, s2 * o2 / outside
        elif a0 >= a1 and a0 >= a2:
            sd, l0 = a0, s0
        elif a1 >= a2:
            sd, l1 = a1, s1
        else:
            sd, l2 = a2, s2
    else:  # a sphere (the capsule's segment of half length 0) or a capsule
        if solid == CAPSULE:
            q2 -= min(d1, max(-d1, q2))
        norm = np.sqrt(q0 * q0 + q1 * q1 + q2 * q2)
        sd = norm - d0
        if norm > 0.0:
            l0, l1, l2 = q0 / norm, q1 / norm, q2 / norm
        else:
            l2 = 1.0
    for c in range(3):  # g = R l
        g[c] = params[p + 1 + 3 * c] * l0 + params[p + 2 + 3 * c] * l1 + params[p + 3 + 3 * c] * l2
    return sd
