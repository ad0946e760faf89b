"""Collision avoidance as task terms on sphere covers: hinges on signed distances, zero when clear.

Each sphere of a :class:`~framework.spheres.SphereCover` becomes a frame of the robot (``sphere[k]`` at its centre
on its joint); a pair of spheres is one ``DISTANCE`` block held at least ``r_a + r_b + margin`` apart (the same
compiled residual, Jacobian and second order as :class:`~framework.costs.Distance`), so every solver reads them
through the one term interface. They sit at the first priority level with the task: a collision is as wrong as a
missed target.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from ..errors import TaskError
from ..robot import Robot
from . import blocks as B
from .base import Term
from .program import Block

#: Stand-in for "no upper bound" in a DISTANCE block.
FAR = 1e300


def _sphere_frames(shape, cover) -> list[str]:
    """Frames at the cover's sphere centres, added to the robot's model once (named by geometry and centre, so
    two covers never share a frame that is not at the same place)."""
    import hashlib

    frames = []
    for j, c, geometry in zip(cover.joints, cover.centers, cover.geometries):
        name = f"sphere[{geometry}:{hashlib.sha1(np.asarray(c, dtype=float).tobytes()).hexdigest()[:8]}]"
        shape.robot.add_frame(name, int(j), pin.SE3(np.eye(3), np.asarray(c, dtype=float)))
        frames.append(name)
    return frames


class SelfCollision(Term):
    """The robot's own links kept ``margin`` [m] apart: every pair of spheres on geometry pairs the
    :class:`~framework.collision.RobotShape` checks (adjacent links and SRDF-disabled pairs left out).

    Residual: one row per sphere pair, ``‖c_a − c_b‖ − (r_a + r_b + margin)`` when negative, else 0 [m].
    """

    level = "task"
    has_target = False

    def __init__(self, shape, *, margin: float = 0.0, cover=None, name: str | None = None):
        from ..spheres import sphere_cover

        if not (isinstance(margin, (int, float)) and np.isfinite(margin) and margin >= 0):
            raise TaskError(f"self-collision margin must be a distance >= 0 [m]; got {margin!r}")
        self.shape, self.margin = shape, float(margin)
        self.cover = cover if cover is not None else sphere_cover(shape)
        self.frames = ()
        self.name = name or "self_collision"

    def validate(self, robot: Robot) -> None:
        if robot is not self.shape.robot:
            raise TaskError(f"{self.name} was built for robot {self.shape.robot.name!r}, not this one")

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        frames = _sphere_frames(self.shape, self.cover)
        names = [g.name for g in self.shape.geometry.geometryObjects]
        spheres: dict[str, list[int]] = {}
        for k, geometry in enumerate(self.cover.geometries):
            spheres.setdefault(geometry, []).append(k)
        blocks = []
        for a, b in self.shape.pairs:
            for i in spheres.get(a, ()):
                for j in spheres.get(b, ()):
                    gap = self.cover.radii[i] + self.cover.radii[j] + self.margin
                    blocks.append(Block(B.DISTANCE, B.NORM, 1, (frames[i], frames[j]),
                                        np.array([0.0, 0.0, 0.0, gap, FAR]), tolerance=B.TOL_LINEAR))
        if not blocks:
            raise TaskError(f"{self.name}: no pair of links to keep apart ({len(names)} geometries)")
        return tuple(blocks)

    def __repr__(self) -> str:
        return f"SelfCollision({self.shape.robot.name!r}, margin={self.margin:g}, spheres={len(self.cover.radii)})"


class SphereObstacles(Term):
    """The robot kept ``margin`` [m] clear of spheres in the world (``centers (k, 3)`` [m], ``radii (k,)``):
    every sphere of the robot's cover against every obstacle, one ``DISTANCE`` block to a point each."""

    level = "task"
    has_target = False

    def __init__(self, shape, centers: Sequence[Sequence[float]], radii: Sequence[float], *, margin: float = 0.0,
                 cover=None, name: str | None = None):
        from ..spheres import sphere_cover

        centers = np.atleast_2d(np.asarray(centers, dtype=float))
        radii = np.atleast_1d(np.asarray(radii, dtype=float))
        if centers.shape[1:] != (3,) or radii.shape != (len(centers),) or not np.isfinite(centers).all() \
                or not (np.isfinite(radii).all() and (radii >= 0).all()):
            raise TaskError("sphere obstacles need centers (k, 3) [m] and radii (k,) >= 0 [m], all finite")
        if not (isinstance(margin, (int, float)) and np.isfinite(margin) and margin >= 0):
            raise TaskError(f"obstacle margin must be a distance >= 0 [m]; got {margin!r}")
        self.shape, self.margin = shape, float(margin)
        self.centers, self.radii = centers, radii
        self.cover = cover if cover is not None else sphere_cover(shape)
        self.frames = ()
        self.name = name or "obstacles"

    validate = SelfCollision.validate

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        frames = _sphere_frames(self.shape, self.cover)
        return tuple(
            Block(B.DISTANCE, B.NORM, 1, (frame,), np.array([*center, self.cover.radii[k] + radius + self.margin, FAR]),
                  tolerance=B.TOL_LINEAR)
            for k, frame in enumerate(frames) for center, radius in zip(self.centers, self.radii)
        )
