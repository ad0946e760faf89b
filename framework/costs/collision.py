"""Collision avoidance as task terms on sphere covers: hinges on signed distances, zero when clear.

Each sphere of a :class:`~framework.spheres.SphereCover` becomes a frame of the robot (``sphere[k]`` at its centre
on its joint); a pair of spheres is one ``DISTANCE`` block held at least ``r_a + r_b + margin`` apart (the same
compiled residual, Jacobian and second order as :class:`~framework.costs.Distance`), a sphere against a box or
capsule — a link's own (``geometry[name]`` frames) or an obstacle — one ``CLEARANCE`` block (the signed distance
to the solid), so every solver reads them through the one term interface. Links' boxes and capsules are used
whole on one side of a pair because few spheres cover a flat box badly. They sit at the first priority level with the task: a collision is as wrong as a
missed target. Each term also has an exact check (:meth:`Term.collisions`, coal on the URDF's geometry), which
:func:`framework.solve` asks before it calls a solve a success.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from ..collision import CollisionReport, RobotShape
from ..errors import TaskError
from ..robot import Robot
from ..scene import Scene
from ..spheres import SphereCover
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


def _geometry_frame(shape: RobotShape, name: str, joint: int, placement: pin.SE3) -> str:
    """A frame at a geometry's placement on its joint (a link's box or capsule), added to the model once."""
    frame = f"geometry[{name}]"
    shape.robot.add_frame(frame, joint, placement)
    return frame


def _margin(value: float, what: str) -> float:
    if isinstance(value, bool) or not (isinstance(value, (int, float)) and np.isfinite(value) and value >= 0):
        raise TaskError(f"{what} margin must be a distance >= 0 [m]; got {value!r}")
    return float(value)


class SelfCollision(Term):
    """The robot's own links kept ``margin`` [m] apart: every pair of spheres on geometry pairs the
    :class:`~framework.collision.RobotShape` checks (adjacent links and SRDF-disabled pairs left out).

    Residual: one row per sphere pair, ``‖c_a − c_b‖ − (r_a + r_b + margin)`` when negative, else 0 [m].
    """

    level = "task"
    has_target = False
    checks_collisions = True

    def __init__(self, shape: RobotShape, *, margin: float = 0.0, cover: SphereCover | None = None,
                 name: str | None = None):
        self.shape, self.margin = shape, _margin(margin, "self-collision")
        self.cover = cover if cover is not None else shape.cover()
        self.frames = ()
        self.name = name or "self_collision"

    def validate(self, robot: Robot) -> None:
        if robot is not self.shape.robot:
            raise TaskError(f"{self.name} was built for robot {self.shape.robot.name!r}, not this one")

    def collisions(self, robot: Robot, x: np.ndarray) -> CollisionReport:
        """The robot's own pairs in contact at ``x`` on the exact geometry (coal's fast check)."""
        return self.shape.check(x, distances=False)

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        """Per geometry pair: the spheres of one against the other's box or capsule when it has one (the larger
        such solid; ``CLEARANCE`` blocks on its frame, exact), else sphere against sphere (``DISTANCE``)."""
        frames = _sphere_frames(self.shape, self.cover)
        solids = self.shape.solids()
        solid_frames = {name: _geometry_frame(self.shape, name, joint, placement)
                        for name, (joint, placement, _, _) in solids.items()}
        spheres: dict[str, list[int]] = {}
        for k, geometry in enumerate(self.cover.geometries):
            spheres.setdefault(geometry, []).append(k)
        blocks = []
        for a, b in self.shape.pairs:
            if a in solids and (b not in solids or solids[a][3] > solids[b][3]):
                a, b = b, a  # b: the solid, a: the spheres
            if b in solids:
                for i in spheres.get(a, ()):
                    lo = self.cover.radii[i] + self.margin
                    blocks.append(Block(B.CLEARANCE, B.NORM, 1, (frames[i], solid_frames[b]),
                                        np.append(solids[b][2], lo), tolerance=B.TOL_LINEAR))
                continue
            for i in spheres.get(a, ()):
                for j in spheres.get(b, ()):
                    gap = self.cover.radii[i] + self.cover.radii[j] + self.margin
                    blocks.append(Block(B.DISTANCE, B.NORM, 1, (frames[i], frames[j]),
                                        np.array([0.0, 0.0, 0.0, gap, FAR]), tolerance=B.TOL_LINEAR))
        if not blocks:
            raise TaskError(f"{self.name}: no pair of links to keep apart "
                            f"({len(self.shape.geometry.geometryObjects)} geometries)")
        return tuple(blocks)

    def __repr__(self) -> str:
        return f"SelfCollision({self.shape.robot.name!r}, margin={self.margin:g}, spheres={len(self.cover.radii)})"


class Obstacles(Term):
    """The robot kept ``margin`` [m] clear of a :class:`~framework.scene.Scene`'s obstacles: every sphere of the
    robot's cover that moves (not fixed to the world) against every solid, one ``CLEARANCE`` block each.

    Residual: one row per sphere and solid, ``sd(c) − (r + margin)`` when negative, else 0 [m] (``sd``: the signed
    distance of the sphere's centre to the solid). The exact check reports the moving geometries against the
    obstacles (not the robot's own pairs: :class:`SelfCollision` does that).
    """

    level = "task"
    has_target = False
    checks_collisions = True

    def __init__(self, shape: RobotShape, scene: Scene | Sequence, *, margin: float = 0.0,
                 cover: SphereCover | None = None, name: str | None = None):
        self.shape, self.margin = shape, _margin(margin, "obstacle")
        self.scene = scene if isinstance(scene, Scene) else Scene(tuple(scene))
        if not len(self.scene):
            raise TaskError("obstacles: the scene holds no obstacle")
        self.cover = cover if cover is not None else shape.cover()
        self.frames = ()
        self.name = name or "obstacles"

    validate = SelfCollision.validate

    def collisions(self, robot: Robot, x: np.ndarray) -> CollisionReport:
        """The moving geometries in contact with the obstacles at ``x``, on the exact geometry (coal's fast
        check)."""
        return self.shape.check(x, scene=self.scene, self_pairs=False, distances=False)

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        frames = _sphere_frames(self.shape, self.cover)
        solids = self.scene.solids()
        blocks = []
        for k, frame in enumerate(frames):
            if self.cover.joints[k] == 0:  # fixed to the world: where the user placed it
                continue
            lo = self.cover.radii[k] + self.margin
            for solid in solids:
                blocks.append(Block(B.CLEARANCE, B.NORM, 1, (frame,), np.append(solid, lo), tolerance=B.TOL_LINEAR))
        if not blocks:
            raise TaskError(f"{self.name}: no moving sphere of the robot to keep clear")
        return tuple(blocks)

    def __repr__(self) -> str:
        return f"Obstacles({self.shape.robot.name!r}, {len(self.scene)} obstacles, margin={self.margin:g})"
