"""Convex hulls of a robot's collision geometry, paired as a collision term keeps them apart: the tighter model of
the local engine's last steps (:mod:`framework.engine.hull_reach`).

A sphere cover is fatter than its link — centimetres on a large mesh — so a target a few millimetres above a
table can be out of reach in the sphere model although a configuration reaches it without contact. A convex hull
holds its mesh (hulls apart mean the meshes are) and is the mesh itself on the convex links robots are mostly made
of; coal measures two hulls, or a hull and a box, capsule or sphere, in microseconds (GJK), with the depth of an
overlap (EPA), so a hinge on their distance has a gradient on both sides.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import pinocchio as pin

from .collision import RobotShape
from .scene import Scene


@dataclass(frozen=True)
class HullPair:
    """Two convex solids kept ``margin`` [m] apart, each fixed on a joint (0: the world).

    Attributes:
        names: the geometries' names (an obstacle's as ``obstacle:<name>``).
        joints: Pinocchio joint indices.
        placements: each solid's placement in its joint's frame (in the world for joint 0).
        shapes: coal geometries (a mesh's convex hull; primitives and obstacle meshes as they are), with their
            local bounding spheres computed (``aabb_center``, ``aabb_radius``).
        margin: distance to keep [m].
        exact: the geometries themselves (meshes), for telling nested hulls from contact.
        loose: the collision term's sphere model of this pair is looser than the hulls (a mesh, box or cylinder
            covered by spheres); False when it is exact (spheres, or a sphere against a box used whole), where
            the hull steps cannot find more room.
    """

    names: tuple[str, str]
    joints: tuple[int, int]
    placements: tuple[pin.SE3, pin.SE3]
    shapes: tuple[Any, Any]
    margin: float
    exact: tuple[Any, Any]
    loose: bool


def self_pairs(shape: RobotShape, margin: float) -> tuple[HullPair, ...]:
    """The robot's own checked pairs (:attr:`RobotShape.pairs`), as hulls."""
    objects = shape.geometry.geometryObjects
    solids = shape.solids()
    out = []
    for p in shape.geometry.collisionPairs:
        a, b = objects[p.first], objects[p.second]
        exact = (_is_sphere(a) or a.name in solids) and (_is_sphere(b) or b.name in solids) \
            and (_is_sphere(a) or _is_sphere(b))  # spheres, or a sphere against a box or capsule used whole
        out.append(HullPair((a.name, b.name), (int(a.parentJoint), int(b.parentJoint)), (a.placement, b.placement),
                            (shape.hull(p.first), shape.hull(p.second)), margin, (a.geometry, b.geometry),
                            not exact))
    return tuple(out)


def _is_sphere(geometry_object) -> bool:
    """Whether a geometry is a sphere: its sphere cover is itself."""
    import coal

    return isinstance(geometry_object.geometry, coal.Sphere)


def obstacle_pairs(shape: RobotShape, scene: Scene, margin: float) -> tuple[HullPair, ...]:
    """Every geometry that moves (not fixed to the world) against every obstacle of ``scene``."""
    out = []
    for obstacle in scene:
        solid, placement = obstacle.coal()
        solid.computeLocalAABB()
        for k, g in enumerate(shape.geometry.geometryObjects):
            if g.parentJoint != 0:
                out.append(HullPair((g.name, f"obstacle:{obstacle.name}"), (int(g.parentJoint), 0),
                                    (g.placement, placement), (shape.hull(k), solid), margin, (g.geometry, solid),
                                    not _is_sphere(g)))
    return tuple(out)


def moving_loose(shape: RobotShape) -> bool:
    """Whether a geometry that moves is not a sphere: the obstacle pairs' sphere model is then looser than the
    hulls (see :func:`obstacle_pairs`)."""
    return any(g.parentJoint != 0 and not _is_sphere(g) for g in shape.geometry.geometryObjects)
