"""The broad phase of the exact collision check: one bounding sphere per geometry, and the pairs that come near.

A pair of geometries can be closer than a margin only if their bounding spheres are; the fast check
(:meth:`framework.geometry.collision.RobotShape.check` with ``distances=False``) hands coal only those pairs. The spheres hold
their geometry exactly (a sphere is its own; any other shape sits inside the sphere through the corners of its
local axis-aligned box, coal's ``aabb_center`` / ``aabb_radius``; an unbounded one, a half-space, gets an infinite
radius), so the pairs left out are clear: the check's answer is the one coal gives on every pair, at a fraction of
the cost (a dual-arm youBot: 906 pairs, about 16 near at a solved configuration).

A geometry whose exact shape is a solid of :mod:`framework.geometry.solids` (an obstacle's sphere, box, capsule or
half-space; a link's box, or the capsule holding its cylinder) is measured as that solid against the other's sphere:
its signed distance to the sphere's centre, less the radius, is a lower bound of the pair's distance too, and a
tight one where the bounding sphere is not (a table's sphere holds the room above it; a floor's is infinite).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property

from typing import NamedTuple

import numpy as np
import pinocchio as pin

from ..model.kinematics import PopulationKinematics, fk_one
from ..compiled.native import compiled, internal
from ..model.robot import Robot
from .solids import CAPSULE, ROW, solid_distance

#: Added to every margin [m]: pairs within this of their spheres touching go to coal too (coal's own tolerance on
#: distances between primitives is about 1e-6 m).
SLACK = 1e-6


def bounding_sphere(geometry) -> tuple[np.ndarray, float]:
    """Centre ``(3,)`` in the geometry's own frame and radius [m] of a sphere holding the coal ``geometry``."""
    import coal

    if isinstance(geometry, coal.Sphere):
        return np.zeros(3), float(geometry.radius)
    geometry.computeLocalAABB()
    center, radius = np.array(geometry.aabb_center, dtype=float), float(geometry.aabb_radius)
    if not (np.isfinite(center).all() and np.isfinite(radius)):
        return np.zeros(3), np.inf
    return center, radius


@dataclass(frozen=True)
class BoundingSpheres:
    """Every geometry of a Pinocchio geometry model in one sphere on its body, and the model's collision pairs.

    Attributes:
        kinematics: the compiled forward kinematics of the bodies' frames (none: every geometry is fixed in the
            world).
        slots: ``(g,)`` each geometry's body, as an index into ``kinematics.frames`` (``-1``: fixed in the world).
        centers: ``(g, 3)`` sphere centres in their body's frame (the world's for slot ``-1``) [m].
        radii: ``(g,)`` radii [m] (``inf``: unbounded).
        codes: ``(g,)`` the solid code of a geometry whose exact shape is a solid (``-1``: none).
        solids: ``(g * 16,)`` those solids' rows (:mod:`framework.geometry.solids`) in their body's frame, one after another.
        first, second: ``(pairs,)`` the geometry indices of each collision pair.
    """

    kinematics: PopulationKinematics
    slots: np.ndarray
    centers: np.ndarray
    radii: np.ndarray
    codes: np.ndarray
    solids: np.ndarray
    first: np.ndarray
    second: np.ndarray

    def near_pairs(self, x: np.ndarray, margin: float) -> np.ndarray:
        """Indices of the collision pairs whose spheres are closer than ``margin`` [m] (plus :data:`SLACK`) at
        joint coordinates ``x`` ``(n,)``: every pair that can be closer than ``margin``."""
        out = np.empty(self.first.size, dtype=np.int64)
        count = _near_pairs(np.ascontiguousarray(x, dtype=float), self._tables, self._spheres, float(margin) + SLACK,
                            out)
        return out[:count]

    @cached_property
    def _spheres(self) -> Spheres:
        """The arrays the compiled broad phase reads (made once: a tuple made per call cost ~1 µs)."""
        return Spheres(self.slots, self.centers, self.radii, self.codes, self.solids, self.first, self.second)

    @cached_property
    def _tables(self) -> tuple:
        """The forward kinematics' tables."""
        return self.kinematics.tables


class Spheres(NamedTuple):
    """The arrays of :class:`BoundingSpheres` the compiled broad phase reads."""

    slots: np.ndarray
    centers: np.ndarray
    radii: np.ndarray
    codes: np.ndarray
    solids: np.ndarray
    first: np.ndarray
    second: np.ndarray


def bounding_spheres(robot: Robot, geometry: pin.GeometryModel,
                     solids: Mapping[int, np.ndarray] | None = None) -> BoundingSpheres:
    """The :class:`BoundingSpheres` of ``geometry`` (a geometry model of ``robot``'s model; the bodies' frames are
    added to the model, :meth:`~framework.model.robot.Robot.body_frame`); ``solids``: geometry index -> the row
    ``(16,)`` of the solid that is (or holds) its exact shape, in its body's frame (the world's for a geometry
    fixed there)."""
    objects = geometry.geometryObjects
    codes, rows = np.full(len(objects), -1, dtype=np.int64), np.zeros((len(objects), ROW))
    for k, row in (solids or {}).items():
        codes[k], rows[k] = int(row[0]), row
    bodies = sorted({int(g.parentJoint) for g in objects if g.parentJoint != 0})
    slot = {joint: k for k, joint in enumerate(bodies)}
    centers, radii = np.empty((len(objects), 3)), np.empty(len(objects))
    for k, g in enumerate(objects):
        center, radii[k] = bounding_sphere(g.geometry)
        centers[k] = g.placement.act(center)
    slots = np.array([slot.get(int(g.parentJoint), -1) for g in objects], dtype=np.int64)
    kinematics = robot.kinematics(tuple(robot.body_frame(j) for j in bodies))
    pairs = geometry.collisionPairs
    return BoundingSpheres(kinematics, slots, centers, radii, codes, rows.ravel(),
                           np.array([p.first for p in pairs], dtype=np.int64),
                           np.array([p.second for p in pairs], dtype=np.int64))


@compiled
def _near_pairs(x, tables, spheres, margin, out) -> int:
    """The pairs ``(first[p], second[p])`` of ``spheres`` (:class:`Spheres`) that can be closer than ``margin`` at
    joint coordinates ``x (n,)`` (the bodies' poses from the FK ``tables``, in one compiled call: a check's broad
    phase cost more in Python around the FK than in it), into ``out``; returns their count: those whose spheres
    are, unless a solid of the pair is clear of the other's sphere by ``margin``."""
    jint, jgeo, fslot, fgeo = tables
    slots, centers, radii, codes, solids, first, second = spheres
    poses, placements = np.empty((fslot.shape[0], 12)), np.empty((jint.shape[0], 12))
    fk_one(x, jint, jgeo, fslot, fgeo, poses, placements)
    positions, rotations = poses[:, 9:], poses[:, :9]
    world = np.empty((centers.shape[0], 3))
    for g in range(centers.shape[0]):
        s = slots[g]
        for i in range(3):
            if s < 0:
                world[g, i] = centers[g, i]
            else:
                world[g, i] = positions[s, i] + rotations[s, 3 * i] * centers[g, 0] \
                    + rotations[s, 3 * i + 1] * centers[g, 1] + rotations[s, 3 * i + 2] * centers[g, 2]
    gradient = np.empty(3)
    count = 0
    for p in range(first.shape[0]):
        a, b = first[p], second[p]
        reach = radii[a] + radii[b] + margin
        d2 = 0.0
        for i in range(3):
            d2 += (world[a, i] - world[b, i]) ** 2
        if d2 >= reach * reach:  # inf radii: never clear this way
            continue
        if codes[b] >= 0 and _solid_gap(b, world[a], slots, positions, rotations, solids, gradient) - radii[a] \
                >= margin:
            continue
        if codes[a] >= 0 and _solid_gap(a, world[b], slots, positions, rotations, solids, gradient) - radii[b] \
                >= margin:
            continue
        if codes[a] == CAPSULE and codes[b] == CAPSULE \
                and _capsules_gap(a, b, slots, positions, rotations, solids) >= margin:
            continue
        out[count] = p
        count += 1
    return count


@internal
def _capsules_gap(a, b, slots, positions, rotations, solids) -> float:
    """Distance [m] between the capsules of geometries ``a`` and ``b`` (their rows in their bodies' frames; negative:
    they overlap): their segments' distance less both radii."""
    ends = np.empty((4, 3))  # a's segment, then b's, in the world
    for e in range(2):
        g = a if e == 0 else b
        s, p = slots[g], ROW * g
        for k in range(2):
            sign = -1.0 if k == 0 else 1.0
            q0, q1, q2 = (solids[p + 10] + sign * solids[p + 14] * solids[p + 3],  # centre ± half length · axis
                          solids[p + 11] + sign * solids[p + 14] * solids[p + 6],
                          solids[p + 12] + sign * solids[p + 14] * solids[p + 9])
            for i in range(3):
                ends[2 * e + k, i] = (q0, q1, q2)[i] if s < 0 else positions[s, i] + rotations[s, 3 * i] * q0 \
                    + rotations[s, 3 * i + 1] * q1 + rotations[s, 3 * i + 2] * q2
    return segments_distance(ends[0], ends[1], ends[2], ends[3]) - solids[ROW * a + 13] - solids[ROW * b + 13]


@internal
def segments_distance(p0, p1, q0, q1) -> float:
    """Distance [m] between the segments ``p0 p1`` and ``q0 q1`` (each ``(3,)``; Ericson, Real-Time Collision
    Detection, 5.1.9)."""
    a = e = b = c = f = 0.0
    for i in range(3):
        d1, d2, r = p1[i] - p0[i], q1[i] - q0[i], p0[i] - q0[i]
        a, e, b, c, f = a + d1 * d1, e + d2 * d2, b + d1 * d2, c + d1 * r, f + d2 * r
    if a <= 1e-18 and e <= 1e-18:
        s, t = 0.0, 0.0
    elif a <= 1e-18:
        s, t = 0.0, min(max(f / e, 0.0), 1.0)
    elif e <= 1e-18:
        s, t = min(max(-c / a, 0.0), 1.0), 0.0
    else:
        denominator = a * e - b * b
        s = min(max((b * f - c * e) / denominator, 0.0), 1.0) if denominator > 1e-18 else 0.0
        t = (b * s + f) / e
        if t < 0.0:
            s, t = min(max(-c / a, 0.0), 1.0), 0.0
        elif t > 1.0:
            s, t = min(max((b - c) / a, 0.0), 1.0), 1.0
    d2 = 0.0
    for i in range(3):
        gap = p0[i] + s * (p1[i] - p0[i]) - q0[i] - t * (q1[i] - q0[i])
        d2 += gap * gap
    return np.sqrt(d2)


@internal
def _solid_gap(g, point, slots, positions, rotations, solids, gradient) -> float:
    """Signed distance [m] of the world ``point`` ``(3,)`` to geometry ``g``'s solid (its row in its body's
    frame); ``positions (k, 3)`` and ``rotations (k, 9)`` (row-major) are the bodies' world poses."""
    x, y, z = point[0], point[1], point[2]
    s = slots[g]
    if s >= 0:  # the point in the body's frame: Rᵀ(point − p)
        v0, v1, v2 = x - positions[s, 0], y - positions[s, 1], z - positions[s, 2]
        x = rotations[s, 0] * v0 + rotations[s, 3] * v1 + rotations[s, 6] * v2
        y = rotations[s, 1] * v0 + rotations[s, 4] * v1 + rotations[s, 7] * v2
        z = rotations[s, 2] * v0 + rotations[s, 5] * v1 + rotations[s, 8] * v2
    return solid_distance(x, y, z, solids, ROW * g, gradient)
