"""Collision avoidance as task terms on sphere covers: hinges on signed distances, zero when clear.

The spheres of a :class:`~framework.spheres.SphereCover` sit on the bodies (joints) they move with; each pair of
bodies is one ``SPHERES`` row (the closest sphere pair, held ``margin`` apart), each body against a box or capsule
— a link's own (``geometry[name]`` frames) or an obstacle — one ``SOLIDS`` row (the closest sphere's signed
distance to the solid), so a term has one row per pair of bodies however many spheres cover them, and every
solver reads them through the one term interface. Links' boxes and capsules are used whole on one side of a pair
because few spheres cover a flat box badly. They sit at the first priority level with the task: a collision is as wrong as a
missed target. Each term also has an exact check (:meth:`Term.collisions`, coal on the URDF's geometry), which
decides a solve's success (not the sphere rows), and its pairs as convex hulls (:meth:`Term.hull_pairs`), on which
the engine takes its last steps when the fatter spheres keep it from the task.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from ..collision import CollisionReport, RobotShape
from ..errors import TaskError
from ..hulls import HullPair, moving_loose, obstacle_pairs, self_pairs
from ..robot import Robot
from ..scene import Scene
from ..spheres import SphereCover
from . import blocks as B
from .base import Term
from .program import Block


def _geometry_frame(shape: RobotShape, name: str, joint: int, placement: pin.SE3) -> str:
    """A frame at a geometry's placement on its joint (a link's box or capsule), added to the model once."""
    frame = f"geometry[{name}]"
    shape.robot.add_frame(frame, joint, placement)
    return frame


def bounding_sphere(centers: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """A sphere ``(centre (3), radius)`` holding the spheres ``centers (k, 3)``, ``radii (k,)``: centred on their
    centres' bounding box."""
    center = 0.5 * (centers.min(axis=0) + centers.max(axis=0))
    return np.r_[center, (np.linalg.norm(centers - center, axis=1) + radii).max()]


def _spheres_block(shape: RobotShape, cover: SphereCover, pairs: list[tuple[int, int]], margin: float) -> Block:
    """One ``SPHERES`` block over sphere pairs ``(i, j)`` of the cover, every ``i`` on one body, every ``j`` on
    another: each body's spheres listed once, the pairs as a mask unless they are all pairs of the two lists."""
    a, b = sorted({i for i, _ in pairs}), sorted({j for _, j in pairs})
    mask = np.zeros((len(a), len(b)))
    mask[np.searchsorted(a, [i for i, _ in pairs]), np.searchsorted(b, [j for _, j in pairs])] = 1.0
    full = bool(mask.all())
    frames = (shape.robot.body_frame(cover.joints[a[0]]), shape.robot.body_frame(cover.joints[b[0]]))
    params = [[len(a), len(b), margin], bounding_sphere(cover.centers[a], cover.radii[a]),
              bounding_sphere(cover.centers[b], cover.radii[b]), [float(full)],
              np.c_[cover.centers[a], cover.radii[a]].ravel(), np.c_[cover.centers[b], cover.radii[b]].ravel(),
              [] if full else mask.ravel()]
    return Block(B.SPHERES, B.NORM, 1, frames, np.concatenate(params), tolerance=B.TOL_LINEAR)


def _solids_block(shape: RobotShape, cover: SphereCover, spheres: list[int], solid: np.ndarray, margin: float,
                  solid_frame: str | None) -> Block:
    """One ``SOLIDS`` block: the cover's ``spheres`` (all on one body) against ``solid`` (16 parameters), fixed in
    the world or on ``solid_frame``."""
    body = shape.robot.body_frame(cover.joints[spheres[0]])
    frames = (body,) if solid_frame is None else (body, solid_frame)
    params = [solid, [margin, len(spheres)], bounding_sphere(cover.centers[spheres], cover.radii[spheres]),
              np.c_[cover.centers[spheres], cover.radii[spheres]].ravel()]
    return Block(B.SOLIDS, B.NORM, 1, frames, np.concatenate(params), tolerance=B.TOL_LINEAR)


def _margin(value: float, what: str) -> float:
    if isinstance(value, bool) or not (isinstance(value, (int, float)) and np.isfinite(value) and value >= 0):
        raise TaskError(f"{what} margin must be a distance >= 0 [m]; got {value!r}")
    return float(value)


class SelfCollision(Term):
    """The robot's own links kept ``margin`` [m] apart: the geometry pairs the
    :class:`~framework.collision.RobotShape` checks (adjacent links and SRDF-disabled pairs left out), through
    their sphere covers (or a link's own box or capsule).

    Residual: one row per pair of bodies, the smallest ``‖c_a − c_b‖ − (r_a + r_b)`` over their sphere pairs
    (or signed distance of a sphere to a box minus its radius) minus the margin when negative, else 0 [m].
    Pairs whose covers no collision-free configuration separates
    (:meth:`~framework.collision.RobotShape.inseparable`, with a warning naming them) have no row: the exact
    check of :meth:`collisions`, which decides success, still holds them.
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

    def collisions(self, robot: Robot, x: np.ndarray, *, margin: bool = False) -> CollisionReport:
        """The robot's own pairs in contact (closer than the margin, with ``margin``) at ``x`` on the exact
        geometry (coal's fast check)."""
        return self.shape.check(x, self.margin if margin else 0.0, distances=False)

    def hull_pairs(self, robot: Robot) -> tuple[HullPair, ...]:
        """Every checked pair of the robot's own geometries, as convex hulls (those included that the sphere
        rows leave to the exact check)."""
        return self.shape.memo(("self hull pairs", self.margin), lambda: self_pairs(self.shape, self.margin))

    def loose_hulls(self, robot: Robot) -> bool:
        return self.shape.memo(("self hulls loose", self.margin), lambda: any(p.loose for p in self.hull_pairs(robot)))

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        """One row per pair of bodies: their sphere pairs (``SPHERES``), or the spheres of one against the
        other's box or capsule when a geometry pair has one (the larger such solid, used whole: ``SOLIDS`` on
        its frame). Built once per shape, cover and margin (a tracking task makes its terms anew at every
        waypoint)."""
        key = ("self-collision blocks", id(self.cover), self.margin)  # the entry holds the cover: its id stays its
        return self.shape.memo(key, lambda: (self.cover, self._build()))[1]

    def _build(self) -> tuple[Block, ...]:
        solids = self.shape.solids()
        inseparable = self.shape.inseparable(self.cover)
        if inseparable:
            warnings.warn(f"{self.name}: {len(inseparable)} geometry pair(s) whose sphere covers overlap in every "
                          f"sampled collision-free configuration are left to the exact check: "
                          f"{sorted(inseparable)}", stacklevel=2)
        spheres: dict[str, list[int]] = {}
        for k, geometry in enumerate(self.cover.geometries):
            spheres.setdefault(geometry, []).append(k)
        joints = self.cover.joints
        sphere_pairs: dict[tuple[int, int], list[tuple[int, int]]] = {}
        solid_sides: dict[tuple[str, int], set[int]] = {}
        for a, b in self.shape.pairs:
            if (a, b) in inseparable:
                continue
            if a in solids and (b not in solids or solids[a][3] > solids[b][3]):
                a, b = b, a  # b: the solid, a: the spheres
            if b in solids:
                for i in spheres.get(a, ()):
                    solid_sides.setdefault((b, int(joints[i])), set()).add(i)
                continue
            for i in spheres.get(a, ()):
                for j in spheres.get(b, ()):
                    pair = (i, j) if joints[i] <= joints[j] else (j, i)
                    sphere_pairs.setdefault((int(joints[pair[0]]), int(joints[pair[1]])), []).append(pair)
        blocks = [_spheres_block(self.shape, self.cover, pairs, self.margin) for pairs in sphere_pairs.values()]
        for (name, _), ks in solid_sides.items():
            joint, placement, solid, _ = solids[name]
            blocks.append(_solids_block(self.shape, self.cover, sorted(ks), solid, self.margin,
                                        _geometry_frame(self.shape, name, joint, placement)))
        if not blocks:
            raise TaskError(f"{self.name}: no pair of links to keep apart "
                            f"({len(self.shape.geometry.geometryObjects)} geometries)")
        return tuple(blocks)

    def __repr__(self) -> str:
        return f"SelfCollision({self.shape.robot.name!r}, margin={self.margin:g}, spheres={len(self.cover.radii)})"


class Obstacles(Term):
    """The robot kept ``margin`` [m] clear of a :class:`~framework.scene.Scene`'s obstacles: the spheres of every
    body that moves (not fixed to the world) against every solid.

    Residual: one row per body and solid, the smallest ``sd(c) − r`` over the body's spheres minus the margin
    when negative, else 0 [m] (``sd``: the signed distance of a sphere's centre to the solid). The exact check
    reports the moving geometries against the obstacles (not the robot's own pairs: :class:`SelfCollision` does
    that).
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

    def collisions(self, robot: Robot, x: np.ndarray, *, margin: bool = False) -> CollisionReport:
        """The moving geometries in contact with the obstacles (closer than the margin, with ``margin``) at
        ``x``, on the exact geometry (coal's fast check)."""
        return self.shape.check(x, self.margin if margin else 0.0, scene=self.scene, self_pairs=False,
                                distances=False)

    def hull_pairs(self, robot: Robot) -> tuple[HullPair, ...]:
        """Every moving geometry's convex hull against every obstacle."""
        return obstacle_pairs(self.shape, self.scene, self.margin)  # per term: a scene is a value, not a key

    def loose_hulls(self, robot: Robot) -> bool:
        return self.shape.memo(("moving geometries loose",), lambda: moving_loose(self.shape))

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        """One ``SOLIDS`` row per moving body and solid of the scene (a mesh obstacle's covering spheres are
        solids too). Built once per shape, cover, scene and margin, for the last few scenes (a tracking task makes
        its terms anew at every waypoint, on one scene)."""
        built = self.shape.memo(("obstacle blocks",), dict)
        key = (id(self.cover), id(self.scene), self.margin)  # the entries hold the cover and scene: their ids stay
        entry = built.get(key)
        if entry is None:
            if len(built) >= 8:
                built.clear()
            entry = built[key] = (self.cover, self.scene, self._build())
        return entry[2]

    def _build(self) -> tuple[Block, ...]:
        bodies: dict[int, list[int]] = {}
        for k, joint in enumerate(self.cover.joints):
            if joint != 0:  # fixed to the world: where the user placed it
                bodies.setdefault(int(joint), []).append(k)
        blocks = [_solids_block(self.shape, self.cover, ks, solid, self.margin, None)
                  for ks in bodies.values() for solid in self.scene.solids()]
        if not blocks:
            raise TaskError(f"{self.name}: no moving sphere of the robot to keep clear")
        return tuple(blocks)

    def __repr__(self) -> str:
        return f"Obstacles({self.shape.robot.name!r}, {len(self.scene)} obstacles, margin={self.margin:g})"
