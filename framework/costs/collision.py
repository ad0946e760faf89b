"""Collision avoidance as task terms on sphere covers: hinges on signed distances, zero when clear.

The spheres of a :class:`~framework.geometry.spheres.SphereCover` sit on the bodies (joints) they move with; each pair of
bodies is one ``SPHERES`` row (the closest sphere pair, held ``margin`` apart), each body against a box or capsule
— a link's own (``geometry[name]`` frames) or an obstacle — one ``SOLIDS`` row (the closest sphere's signed
distance to the solid), so a term has one row per pair of bodies however many spheres cover them, and every
solver reads them through the one term interface (the two row kinds and their kernels:
:mod:`~framework.costs.sphere_rows`). Links' boxes and capsules are used whole on one side of a pair because few
spheres cover a flat box badly. They sit at the first priority level with the task: a collision is as wrong as a
missed target. Each term also has an exact check (:meth:`Term.collisions`, coal on the URDF's geometry), which
decides a solve's success (not the sphere rows), and its pairs as convex hulls (:meth:`Term.hull_pairs`), on which
the engine takes its last steps when the fatter spheres keep it from the task.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import ClassVar

import numpy as np
import pinocchio as pin

from ..errors import TaskError
from ..geometry.collision import RobotShape
from ..geometry.exact_check import ExactCheck
from ..geometry.hulls import HullPair, moving_loose, obstacle_pairs, self_pairs
from ..geometry.scene import Scene
from ..geometry.spheres import SphereCover
from ..model.robot import Robot
from .base import Term, TermEntry
from .program import Block
from .sphere_rows import solids_block, spheres_block


def _geometry_frame(shape: RobotShape, name: str, joint: int, placement: pin.SE3) -> str:
    """A frame at a geometry's placement on its joint (a link's box or capsule), added to the model once."""
    frame = f"geometry[{name}]"
    shape.robot.add_frame(frame, joint, placement)
    return frame


def _body_frames(shape: RobotShape, cover: SphereCover, pair: tuple[int, int]) -> tuple[str, str]:
    """The frames of the bodies carrying the cover's spheres ``pair``."""
    return shape.robot.body_frame(cover.joints[pair[0]]), shape.robot.body_frame(cover.joints[pair[1]])


def _margin(value: float, what: str) -> float:
    if isinstance(value, bool) or not (isinstance(value, (int, float)) and np.isfinite(value) and value >= 0):
        raise TaskError(f"{what} margin must be a distance >= 0 [m]; got {value!r}")
    return float(value)


class SelfCollision(Term):
    """The robot's own links kept ``margin`` [m] apart: the geometry pairs the
    :class:`~framework.geometry.collision.RobotShape` checks (adjacent links and SRDF-disabled pairs left out), through
    their sphere covers (or a link's own box or capsule).

    Residual: one row per pair of bodies, the smallest ``‖c_a − c_b‖ − (r_a + r_b)`` over their sphere pairs
    (or signed distance of a sphere to a box minus its radius) minus the margin when negative, else 0 [m].
    Pairs whose covers no collision-free configuration separates
    (:meth:`~framework.geometry.collision.RobotShape.inseparable`, with a warning naming them) have no row: the exact
    check of :meth:`collisions`, which decides success, still holds them.
    """

    task_type, task_keys = "self_collision", ("margin",)
    #: the entry's keys, for the task-file reference (docs/taskfile.md)
    task_doc: ClassVar[dict[str, str]] = {
        'margin': "clearance [m] kept between the robot's own links (default 0)"
    }
    #: a robot, and an entry of this type for it (checked by tests/test_taskfile_doc.py)
    task_example: ClassVar[tuple[str, str]] = ('youbot_dual_mobile', 'type = "self_collision"\nmargin = 0.01')

    @classmethod
    def from_entry(cls, entry: TermEntry) -> SelfCollision:
        """The task file's collision shape (``[task] srdf``, ``disabled_collisions``, ``free_at``)."""
        return cls(entry.world.shape, margin=entry.number("margin", 0.0), name=entry.name)

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

    def exact_check(self) -> ExactCheck:
        """The robot's own pairs, closer than the margin in contact."""
        return ExactCheck(self.shape, None, self.margin)

    def hull_pairs(self, robot: Robot) -> tuple[HullPair, ...]:
        """Every checked pair of the robot's own geometries, as convex hulls (those included that the sphere
        rows leave to the exact check)."""
        return self.shape.derived(self_pairs, self.margin)

    def loose_hulls(self, robot: Robot) -> bool:
        return self.shape.derived(_any_loose, self.margin)

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        """One row per pair of bodies: their sphere pairs (``SPHERES``), or the spheres of one against the
        other's box or capsule when a geometry pair has one (the larger such solid, used whole: ``SOLIDS`` on
        its frame). Built once per shape, cover and margin (a tracking task makes its terms anew at every
        waypoint)."""
        # the entry holds the cover (an argument): its id stays its own
        return self.shape.derived(_self_blocks, self.cover, self.margin, self.name, key=(id(self.cover), self.margin))[1]

    def _build(self) -> tuple[Block, ...]:
        return _self_blocks(self.shape, self.cover, self.margin, self.name)[1]

    def packed(self, robot: Robot) -> tuple[tuple[Block, ...], tuple]:
        blocks = self.blocks(robot)
        return blocks, _packing(self.shape, blocks)[0]

    def parameters(self, robot: Robot) -> np.ndarray:
        return _packing(self.shape, self.blocks(robot))[1]

    def __repr__(self) -> str:
        return f"SelfCollision({self.shape.robot.name!r}, margin={self.margin:g}, spheres={len(self.cover.radii)})"


def _obstacle_blocks(shape: RobotShape) -> dict:
    """The shape's table of obstacle terms' blocks: ``(id(cover), id(scene), margin) -> (cover, scene, blocks)``."""
    return {}


def _packing(shape: RobotShape, blocks: tuple[Block, ...]) -> tuple[tuple, np.ndarray]:
    """``(signature, parameters)`` of a collision term's ``blocks`` (built once per shape, cover, scene and margin;
    see the terms' ``blocks``): made once for them too (the dual youBot's 47 rows: ~20 µs saved at every
    waypoint of a path whose task makes its terms anew). The parameters are read-only."""
    table = shape.derived(_packings)
    entry = table.get(id(blocks))
    if entry is None or entry[0] is not blocks:  # the entry holds the blocks: their id stays their own
        if len(table) >= 16:
            table.clear()
        params = np.concatenate([b.params for b in blocks], dtype=float, casting="unsafe")
        params.setflags(write=False)
        entry = table[id(blocks)] = (blocks, tuple(b.signature() for b in blocks), params)
    return entry[1], entry[2]


def _packings(shape: RobotShape) -> dict:
    """The shape's table of collision blocks' packings: ``id(blocks) -> (blocks, signature, parameters)``."""
    return {}


def _any_loose(shape: RobotShape, margin: float) -> bool:
    """Whether any of the shape's self hull pairs at ``margin`` is loose."""
    return any(p.loose for p in shape.derived(self_pairs, margin))


def _self_blocks(shape: RobotShape, cover: SphereCover, margin: float, name: str) -> tuple[SphereCover, tuple]:
    """``(cover, blocks)`` of the self-collision term ``name``: one row per pair of bodies (see
    :meth:`SelfCollision.blocks`); the cover is kept with them (its id is their key)."""
    solids = shape.solids()
    inseparable = shape.inseparable(cover)
    if inseparable:
        warnings.warn(f"{name}: {len(inseparable)} geometry pair(s) whose sphere covers overlap in every "
                      f"sampled collision-free configuration are left to the exact check: "
                      f"{sorted(inseparable)}", stacklevel=2)
    spheres: dict[str, list[int]] = {}
    for k, geometry in enumerate(cover.geometries):
        spheres.setdefault(geometry, []).append(k)
    joints = cover.joints
    sphere_pairs: dict[tuple[int, int], list[tuple[int, int]]] = {}
    solid_sides: dict[tuple[str, int], set[int]] = {}
    for a, b in shape.pairs:
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
    blocks = [spheres_block(_body_frames(shape, cover, pairs[0]), cover, pairs, margin) for pairs in sphere_pairs.values()]
    for (geometry_name, _), ks in solid_sides.items():
        joint, placement, solid, _ = solids[geometry_name]
        ks = sorted(ks)
        frames = (shape.robot.body_frame(cover.joints[ks[0]]), _geometry_frame(shape, geometry_name, joint, placement))
        blocks.append(solids_block(frames, cover, ks, solid, margin))
    if not blocks:
        raise TaskError(f"{name}: no pair of links to keep apart "
                        f"({len(shape.geometry.geometryObjects)} geometries)")
    return cover, tuple(blocks)


class Obstacles(Term):
    """The robot kept ``margin`` [m] clear of a :class:`~framework.geometry.scene.Scene`'s obstacles: the spheres of every
    body that moves (not fixed to the world) against every solid.

    Residual: one row per body and solid, the smallest ``sd(c) − r`` over the body's spheres minus the margin
    when negative, else 0 [m] (``sd``: the signed distance of a sphere's centre to the solid). The exact check
    reports the moving geometries against the obstacles (not the robot's own pairs: :class:`SelfCollision` does
    that).
    """

    task_type, task_keys = "obstacles", ("margin",)
    #: the entry's keys, for the task-file reference (docs/taskfile.md)
    task_doc: ClassVar[dict[str, str]] = {
        'margin': "clearance [m] kept from the file's [[obstacles]] (default 0)"
    }
    #: a robot, and an entry of this type for it (checked by tests/test_taskfile_doc.py)
    task_example: ClassVar[tuple[str, str]] = ('puma560', 'type = "obstacles"\nmargin = 0.02\n\n[[obstacles]]\ntype = "box"\ncenter = [0.6, 0.0, -0.1]\nsize = [0.4, 0.4, 0.05]')

    @classmethod
    def from_entry(cls, entry: TermEntry) -> Obstacles:
        """The task file's ``[[obstacles]]``."""
        if not len(entry.world.scene):
            raise TaskError(f"{entry.where}: the task file has no [[obstacles]] entries")
        return cls(entry.world.shape, entry.world.scene, margin=entry.number("margin", 0.0), name=entry.name)

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

    def exact_check(self) -> ExactCheck:
        """The moving geometries against the obstacles, closer than the margin in contact."""
        return ExactCheck(self.shape, self.scene, self.margin)

    def hull_pairs(self, robot: Robot) -> tuple[HullPair, ...]:
        """Every moving geometry's convex hull against every obstacle."""
        return obstacle_pairs(self.shape, self.scene, self.margin)  # per term: a scene is a value, not a key

    def loose_hulls(self, robot: Robot) -> bool:
        return self.shape.derived(moving_loose)

    def blocks(self, robot: Robot) -> tuple[Block, ...]:
        """One ``SOLIDS`` row per moving body and solid of the scene (a mesh obstacle's covering spheres are
        solids too). Built once per shape, cover, scene and margin, for the last few scenes (a tracking task makes
        its terms anew at every waypoint, on one scene)."""
        built = self.shape.derived(_obstacle_blocks)
        key = (id(self.cover), id(self.scene), self.margin)  # the entries hold the cover and scene: their ids stay
        entry = built.get(key)
        if entry is None:
            if len(built) >= 8:
                built.clear()
            entry = built[key] = (self.cover, self.scene, self._build())
        return entry[2]

    packed = SelfCollision.packed
    parameters = SelfCollision.parameters

    def _build(self) -> tuple[Block, ...]:
        bodies: dict[int, list[int]] = {}
        for k, joint in enumerate(self.cover.joints):
            if joint != 0:  # fixed to the world: where the user placed it
                bodies.setdefault(int(joint), []).append(k)
        blocks = [solids_block((self.shape.robot.body_frame(self.cover.joints[ks[0]]),), self.cover, ks, solid,
                               self.margin) for ks in bodies.values() for solid in self.scene.solids()]
        if not blocks:
            raise TaskError(f"{self.name}: no moving sphere of the robot to keep clear")
        return tuple(blocks)

    def __repr__(self) -> str:
        return f"Obstacles({self.shape.robot.name!r}, {len(self.scene)} obstacles, margin={self.margin:g})"
