"""Collisions on the exact geometry: the URDF's ``<collision>`` elements (boxes, cylinders, spheres, meshes) as
Pinocchio's geometry model, distances by coal.

Pairs checked: every two geometries on bodies that can move relative to each other (links merged into one body by
fixed or locked joints never are), except adjacent bodies (a joint between them) and the pairs an SRDF disables.
Locked joints' links are part of the shape (a locked torso still collides)::

    shape = RobotShape(robot, srdf="robot.srdf")
    report = shape.check(x)            # CollisionReport: contacts closer than the margin, the smallest distance
    report.colliding, report.contacts  # [Contact("l_forearm", "r_forearm", -0.012), ...]
    shape.check(x, scene=scene)        # and every geometry that moves against the scene's obstacles

With a scene, the pairs are the robot's own plus every geometry not fixed to the world (joint 0) against every
obstacle: what is fixed to the world stays where the user placed it, whatever the configuration.

Meshes are found from ``package://`` paths in ``package_dirs`` and in every folder above the robot file (an
installed ``example-robot-data`` resolves so).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from .broad_phase import BoundingSpheres, bounding_spheres
from ..errors import RobotFileError, TaskError
from ..model.robot import Robot, derived
from .scene import Scene
from .solids import CAPSULE, holding_capsule, solid_row
from .spheres import SphereCover, sphere_cover

#: Penetrations shallower than this [m] are touching, not collisions: coal's GJK / EPA resolve distances between
#: primitives to about 1e-6 m, so a configuration on a collision term's boundary reads as slightly inside.
TOUCH = 1e-5
#: Pairs from which the fast check first asks the broad phase which pairs are near (:mod:`framework.geometry.broad_phase`,
#: one compiled call, ~4 µs): below it, coal's pass over every pair (one call into C++) costs less (two spheres' pair:
#: 6.2 µs against 7.2 with the broad phase; the Panda's own 44 pairs of meshes: 44 µs against 7.7). Against a scene
#: with a sphere, box, capsule or half-space the broad phase is asked whatever the count: it measures those solids
#: exactly, and few pairs are near (PR2 over a table, 31 pairs: 22 near by bounding spheres, 0.4 by the table's box).
BROAD_PHASE_PAIRS = 4


@dataclass(frozen=True)
class Contact:
    """Two geometries closer than the margin: their names and the distance between them [m] (negative: depth of
    penetration, as coal reports it)."""

    a: str
    b: str
    distance: float


@dataclass(frozen=True)
class CollisionReport:
    """The pairs closer than ``margin`` [m] at a configuration, closest first, and the smallest distance of all
    pairs checked (NaN when not measured: a fast check without contacts)."""

    contacts: tuple[Contact, ...]
    min_distance: float
    margin: float

    @property
    def colliding(self) -> bool:
        """Whether any pair is closer than the margin (penetrating, with the default margin 0)."""
        return bool(self.contacts)


class RobotShape:
    """The collision geometry of a robot and the pairs to check (see the module docstring).

    Args:
        robot: the robot; its URDF's ``<collision>`` elements are read against its Pinocchio model.
        srdf: an SRDF file whose ``<disable_collisions>`` pairs are not checked.
        package_dirs: folders holding ROS packages, for ``package://`` mesh paths.
        always: configurations sampled (seeded) to find the pairs in contact in every one of them — geometries
            overlapping by construction (two links meeting at a wrist), which no configuration separates; they are
            not checked, as MoveIt's setup assistant disables them. 0 keeps them.
        disabled: pairs of link names not checked, as an SRDF's ``<disable_collisions link1 link2>`` (without
            writing one).
        free_at: configurations ``(n,)`` or ``(k, n)`` declared collision-free: the pairs in contact at any of
            them are not checked (MoveIt's "default" rule, which real files need where their collision geometry
            overlaps at the robot's own rest pose: iCub's thighs and torso in example-robot-data; not applied
            unasked, since in other files such a pose is a real contact — the DH youBot folded at zero).

    Attributes:
        unchecked: why pairs that could collide are not checked — ``"always"``, ``"disabled"``, ``"free_at"``
            (the SRDF's and adjacent bodies' aside) — each a tuple of geometry-name pairs.
    """

    def __init__(self, robot: Robot, *, srdf: str | Path | None = None, package_dirs: Sequence[str | Path] = (),
                 always: int = 50, disabled: Sequence[tuple[str, str]] = (), free_at: np.ndarray | None = None):
        self.robot = robot
        folders = [str(p) for p in package_dirs]
        if robot.source:
            folders += [str(p) for p in Path(robot.source).resolve().parents]
        try:
            geometry = pin.buildGeomFromUrdfString(robot.model, robot.urdf, pin.GeometryType.COLLISION,
                                                   package_dirs=folders)
        except (ValueError, RuntimeError) as err:
            raise RobotFileError(f"cannot read the collision geometry of {robot.name!r}: {err}") from None
        if geometry.ngeoms == 0:
            raise RobotFileError(f"robot {robot.name!r} has no <collision> geometry")
        model = robot.model
        objects = geometry.geometryObjects
        for i in range(geometry.ngeoms):
            for j in range(i + 1, geometry.ngeoms):
                a, b = objects[i].parentJoint, objects[j].parentJoint
                if a != b and model.parents[a] != b and model.parents[b] != a:
                    geometry.addCollisionPair(pin.CollisionPair(i, j))
        if srdf is not None:
            if not Path(srdf).is_file():
                raise RobotFileError(f"SRDF file {srdf} does not exist")
            pin.removeCollisionPairs(model, geometry, str(srdf))
        self.geometry = geometry
        self._data = model.createData()
        self._geometry_data = geometry.createData()
        self.unchecked: dict[str, tuple[tuple[str, str], ...]] = {}
        if disabled:
            links = self._pair_links()
            named = set()
            for pair in disabled:
                if not (isinstance(pair, (tuple, list)) and len(pair) == 2):
                    raise TaskError(f"a disabled collision pair is two link names; got {pair!r}")
                for link in pair:
                    robot.frame_id(link)  # (raises naming close matches)
                named.add(frozenset(pair))
            self._drop("disabled", [frozenset(ab) in named for ab in links])
        if always > 0:
            self._remove_always_colliding(always)
        if free_at is not None:
            X = robot.check_population(free_at, "free_at configuration")
            contact = np.zeros(len(geometry.collisionPairs), dtype=bool)
            for x in X:
                contact |= self._in_contact(x)
            self._drop("free_at", contact)
        self._covers: dict[tuple, SphereCover] = {}
        self._margined: dict[tuple[int, float, float], tuple[pin.GeometryModel, pin.GeometryData]] = {}
        self._hulls: dict[int, object] = {}
        self._memo: dict[tuple, object] = {}
        self._inseparable: dict[tuple, tuple[SphereCover, frozenset[tuple[str, str]]]] = {}
        self._scenes: dict[tuple[int, bool], tuple] = {}  # (id(scene), self pairs) -> _model's entry
        self._fast_checks: dict[tuple, tuple] = {}  # (id(scene), self pairs, margins) -> _fast's entry
        self._broad: dict[int, tuple[pin.GeometryModel, BoundingSpheres]] = {}
        self._hull_models: dict[int, tuple[pin.GeometryModel, tuple | None]] = {}

    def _remove_always_colliding(self, samples: int) -> None:
        rng = np.random.default_rng(0)
        always = np.ones(len(self.geometry.collisionPairs), dtype=bool)
        for x in self.robot.random_configurations(rng, samples):
            always &= self._in_contact(x)
            if not always.any():
                return
        self._drop("always", always)

    def _in_contact(self, x: np.ndarray) -> np.ndarray:
        """``bool (pairs,)``: which checked pairs coal's collision test finds in contact at ``x`` ``(n,)``."""
        pin.computeCollisions(self.robot.model, self._data, self.geometry, self._geometry_data,
                              self.robot.to_pinocchio(x), False)
        return np.array([r.isCollision() for r in self._geometry_data.collisionResults], dtype=bool)

    def _pair_links(self) -> list[tuple[str, str]]:
        """The link (frame) names of each checked pair's two geometries."""
        objects, frames = self.geometry.geometryObjects, self.robot.model.frames
        return [(frames[objects[p.first].parentFrame].name, frames[objects[p.second].parentFrame].name)
                for p in self.geometry.collisionPairs]

    def _drop(self, reason: str, mask: Sequence[bool]) -> None:
        """Stop checking the pairs where ``mask`` is true, recorded in :attr:`unchecked` under ``reason``."""
        objects, pairs = self.geometry.geometryObjects, self.geometry.collisionPairs
        dropped = [int(k) for k in np.flatnonzero(np.asarray(mask, dtype=bool))]
        if not dropped:
            return
        self.unchecked[reason] = self.unchecked.get(reason, ()) + tuple(
            (objects[pairs[k].first].name, objects[pairs[k].second].name) for k in dropped)
        for k in reversed(dropped):
            self.geometry.removeCollisionPair(pairs[k])
        self._geometry_data = self.geometry.createData()

    def cover(self, *, per_geometry: int = 4, max_radius: float | None = 0.08, samples: int = 1500,
              seed: int = 0) -> SphereCover:
        """The sphere cover of every geometry (:func:`framework.geometry.spheres.sphere_cover`), computed once per
        setting."""
        key = (per_geometry, max_radius, samples, seed)
        if key not in self._covers:
            self._covers[key] = sphere_cover(self, per_geometry=per_geometry, max_radius=max_radius,
                                             samples=samples, seed=seed)
        return self._covers[key]

    def inseparable(self, cover: SphereCover, *, samples: int = 40, seed: int = 0) -> frozenset[tuple[str, str]]:
        """The checked geometry pairs whose sphere covers overlap in every one of ``samples`` collision-free
        configurations (seeded uniform draws that coal's exact check finds clear): covers fatter than the gap
        between two links that never meet (PR2's shoulder pans: covers overlapping by 12 cm where the meshes stay
        6 cm apart). No configuration separates them in the sphere model, so a collision term that kept them would
        make every problem infeasible; collision terms leave them to the exact check (which still decides
        success). Computed once per cover; empty when fewer than 10 clear configurations turn up in
        ``20 * samples`` draws."""
        key = (id(cover), samples, seed)
        cached = self._inseparable.get(key)
        if cached is not None and cached[0] is cover:
            return cached[1]
        rng = np.random.default_rng(seed)
        spheres: dict[str, list[int]] = {}
        for k, name in enumerate(cover.geometries):
            spheres.setdefault(name, []).append(k)
        pairs = [(a, b) for a, b in self.pairs if a in spheres and b in spheres]
        overlapping = np.ones(len(pairs), dtype=bool)
        clear = 0
        for _ in range(20 * samples):
            x = self.robot.random_configurations(rng, 1)[0]
            if self.check(x, distances=False).colliding:
                continue
            clear += 1
            centers = cover.world_centers(self, x)
            for p, (a, b) in enumerate(pairs):
                if overlapping[p]:
                    i, j = spheres[a], spheres[b]
                    gap = np.linalg.norm(centers[i][:, None] - centers[j][None], axis=2) \
                        - cover.radii[i][:, None] - cover.radii[j][None]
                    overlapping[p] = gap.min() < 0.0
            if clear >= samples or not overlapping.any():
                break
        found = frozenset(pair for pair, o in zip(pairs, overlapping) if o) if clear >= 10 else frozenset()
        self._inseparable[key] = (cover, found)
        return found

    def solids(self) -> dict[str, tuple[int, pin.SE3, np.ndarray, float]]:
        """Geometry name -> ``(joint, placement in the joint, solid parameters (16,), volume [m³])`` of every box,
        capsule and cylinder (a cylinder as the capsule holding it): the kernel's signed distance to them is exact
        (see :func:`framework.geometry.solids.solid_distance`), so they need no sphere cover on one side of a pair."""
        import coal

        from .solids import BOX, CAPSULE

        out = {}
        for g in self.geometry.geometryObjects:
            shape = g.geometry
            if isinstance(shape, coal.Box):
                dims, solid = np.asarray(shape.halfSide, dtype=float), BOX
                volume = float(np.prod(2 * dims))
            elif isinstance(shape, (coal.Capsule, coal.Cylinder)):
                dims, solid = np.array([shape.radius, shape.halfLength, 0.0]), CAPSULE
                volume = float(np.pi * shape.radius ** 2 * (2 * shape.halfLength + 4 / 3 * shape.radius))
            else:
                continue
            out[g.name] = (int(g.parentJoint), g.placement, solid_row(solid, np.eye(3), np.zeros(3), dims), volume)
        return out

    def derived(self, make, *args, key=None):
        """``make(self, *args)``, built once per shape, ``make`` and ``args`` (or ``key`` in their place): what a
        collision term derives from the shape (its hull pairs, its blocks); the function is part of the key."""
        return derived(self._memo, self, make, args, key)

    def hull(self, index: int):
        """The convex coal geometry of geometry object ``index``: a mesh's convex hull (built once, qhull), a
        primitive as it is. It holds the geometry: hulls apart mean the geometries are."""
        hull = self._hulls.get(index)
        if hull is None:
            geometry = self.geometry.geometryObjects[index].geometry
            if _is_mesh(geometry):
                geometry = geometry.clone()  # the exact check keeps its own mesh untouched
                geometry.buildConvexHull(False, "Qt")
                geometry = geometry.convex
            geometry.computeLocalAABB()
            hull = self._hulls[index] = geometry
        return hull

    def _margin_data(self, geometry: pin.GeometryModel, data: pin.GeometryData, margins: tuple[float, float, int]
                     ) -> pin.GeometryData:
        """``data`` for margins 0; else a data of ``geometry`` whose collision requests have coal's security margin
        (pairs closer than it collide) ``margins[0]`` [m] for the first ``margins[2]`` pairs (the robot's own) and
        ``margins[1]`` for the others (against a scene), made once per geometry and margins (setting a margin costs
        ~0.4 µs per pair)."""
        own_margin, scene_margin, own = margins
        if own_margin == 0.0 and scene_margin == 0.0:
            return data

        def make() -> pin.GeometryData:
            margined = geometry.createData()
            for k, request in enumerate(margined.collisionRequests):
                request.security_margin = own_margin if k < own else scene_margin
            return margined

        return _kept(self._margined, (id(geometry), own_margin, scene_margin), geometry, make)

    def _bounding_spheres(self, geometry: pin.GeometryModel,
                          obstacles: dict[int, np.ndarray] | None = None) -> BoundingSpheres:
        """The broad phase of ``geometry`` (the robot's own model, or one with a scene whose exact obstacles'
        solid rows are ``obstacles``, by geometry index), made once per model. Links' boxes and cylinders are
        measured as their solids (:meth:`solids`), meshes as a capsule holding their convex hull
        (:func:`~framework.geometry.solids.holding_capsule`)."""
        def make() -> BoundingSpheres:
            links = {name: solid_row(int(row[0]), placement.rotation, placement.translation, row[13:16])
                     for name, (_, placement, row, _) in self.solids().items()}  # in the body's frame
            solids = {k: links[g.name] for k, g in enumerate(geometry.geometryObjects) if g.name in links}
            for k in range(len(self.geometry.geometryObjects)):  # the robot's meshes (a scene's come after them)
                g = geometry.geometryObjects[k]
                if k not in solids and _is_mesh(g.geometry):
                    held = holding_capsule(np.array(self.hull(k).points()))  # in the geometry's frame
                    solids[k] = solid_row(CAPSULE, g.placement.rotation @ held[1:10].reshape(3, 3),
                                          g.placement.act(held[10:13]), held[13:16])
            return bounding_spheres(self.robot, geometry, {**solids, **(obstacles or {})})

        return _kept(self._broad, id(geometry), geometry, make)

    def broad_phase(self, scene: Scene | None = None, *, self_pairs: bool = True
                    ) -> tuple[BoundingSpheres, tuple[tuple[str, str], ...]]:
        """The fast check's broad phase (:meth:`check`) over the robot's own pairs (with ``self_pairs``) and, with
        ``scene``, its moving geometries against the obstacles; and those pairs' geometry names, in its order."""
        model = self._model(scene, self_pairs)
        if model is None:
            raise TaskError("a broad phase needs pairs: the robot's own (self_pairs) or a scene's")
        geometry, _, obstacles, _ = model
        objects = geometry.geometryObjects
        return self._bounding_spheres(geometry, obstacles), tuple(
            (objects[p.first].name, objects[p.second].name) for p in geometry.collisionPairs)

    def _narrow_phase(self, geometry: pin.GeometryModel, data: pin.GeometryData, hulls: tuple | None,
                      q: np.ndarray, near: list[int]) -> list[int]:
        """The pairs among ``near`` that coal's collision test flags on the exact geometry at ``q`` (``data``, and
        the hull model's data in ``hulls``: with the check's margins). A pair with a mesh is tested first on the
        convex hulls (:meth:`hull`): hulls apart by the margin, the meshes they hold are, and two hulls cost coal
        ~1.5 µs against ~8 µs for two of PR2's meshes."""
        if hulls is None:
            pin.updateGeometryPlacements(self.robot.model, self._data, geometry, data, q)
            return [k for k in near if pin.computeCollision(geometry, data, k)]
        model, hull_data, exact = hulls
        pin.updateGeometryPlacements(self.robot.model, self._data, model, hull_data, q)
        flagged = [k for k in near if pin.computeCollision(model, hull_data, k)]
        if not flagged:  # (the exact geometry is placed for those flagged only: coal measures their distances next)
            return flagged
        pin.updateGeometryPlacements(self.robot.model, self._data, geometry, data)  # the joints placed above
        return [k for k in flagged if exact[k] or pin.computeCollision(geometry, data, k)]

    def _hull_model(self, geometry: pin.GeometryModel
                    ) -> tuple[pin.GeometryModel, pin.GeometryData, list[bool]] | None:
        """``geometry`` (the robot's own model, or one with a scene) with the robot's meshes as their convex hulls,
        its data, and for each pair whether the hulls are its exact geometry (no mesh); ``None`` when the robot
        has no mesh. Made once per model."""
        def make():
            # a scene's model: the robot's geometries, then the obstacles (as they are)
            meshes = {k for k, g in enumerate(self.geometry.geometryObjects) if _is_mesh(g.geometry)}
            if not meshes:
                return None
            model = geometry.copy()
            for k in meshes:
                model.geometryObjects[k].geometry = self.hull(k)
            exact = [p.first not in meshes and p.second not in meshes for p in geometry.collisionPairs]
            return model, model.createData(), exact

        return _kept(self._hull_models, id(geometry), geometry, make)

    def _model(self, scene: Scene | None, self_pairs: bool
               ) -> tuple[pin.GeometryModel, pin.GeometryData, dict[int, np.ndarray] | None, int] | None:
        """The geometry model of a check: the robot's own (``scene`` None), or with the scene's obstacles added
        (fixed in the world): the robot's own pairs first (with ``self_pairs``), then every moving geometry against
        every obstacle; its data; the solid rows of the obstacles whose exact shape is one, by geometry index; and
        the count of the robot's own pairs. ``None``: no pair (neither). A scene's is kept for the last few asked."""
        if scene is None:
            return (self.geometry, self._geometry_data, None, len(self.geometry.collisionPairs)) if self_pairs \
                else None
        entry = self._scenes.get((id(scene), self_pairs))
        if entry is not None and entry[0] is scene:  # the entry holds the scene: its id stays its own
            return entry[1:]
        geometry = self.geometry.copy()
        if not self_pairs:
            geometry.removeAllCollisionPairs()
        own = len(geometry.collisionPairs)
        robot_geometries = [i for i, g in enumerate(geometry.geometryObjects) if g.parentJoint != 0]
        solids = {}
        for obstacle in scene:
            shape, placement = obstacle.coal()
            k = geometry.addGeometryObject(pin.GeometryObject(f"obstacle:{obstacle.name}", 0, 0, placement, shape))
            for i in robot_geometries:
                geometry.addCollisionPair(pin.CollisionPair(i, k))
            if obstacle.exact:
                solids[k] = obstacle.solids()[0]
        if len(self._scenes) >= 8:
            self._scenes.clear()
        entry = self._scenes[(id(scene), self_pairs)] = (scene, geometry, geometry.createData(), solids, own)
        return entry[1:]

    @property
    def pairs(self) -> tuple[tuple[str, str], ...]:
        """The geometry pairs checked, by name."""
        objects = self.geometry.geometryObjects
        return tuple((objects[p.first].name, objects[p.second].name) for p in self.geometry.collisionPairs)

    def check(self, x: np.ndarray, margin: float = 0.0, scene: Scene | None = None, *,
              self_pairs: bool = True, distances: bool = True, scene_margin: float | None = None) -> CollisionReport:
        """Distances at joint coordinates ``x`` ``(n,)`` of the robot's own pairs (unless ``self_pairs`` is
        False) and, with ``scene``, of the moving geometries to its obstacles (named ``obstacle:<name>``); pairs
        closer than their margin [m] — ``margin`` for the robot's own, ``scene_margin`` (default ``margin``)
        against the scene — are contacts; at margin 0, pairs penetrating by :data:`TOUCH` or more, or at distance
        exactly 0 (coal's distance between intersecting meshes, which has no depth). Both kinds of pairs are
        checked in one pass (the geometries placed once, one broad phase).

        ``distances=False`` is the fast check: coal's collision test (with the margin as its security margin:
        pairs closer than it count) on every pair — with :data:`BROAD_PHASE_PAIRS` pairs or more, or against a
        scene's solids, on the pairs whose bounding spheres (or solids) come within the margin (the others cannot:
        :mod:`framework.geometry.broad_phase`), pairs with a mesh on their convex hulls first — and distances only for the
        pairs it flags: about 50x faster on meshes. The report's ``min_distance`` is then the closest flagged
        pair's, or NaN (not measured) when there is none.
        """
        scene_margin = margin if scene_margin is None else scene_margin
        x = self.robot.check_population(x)[0]
        if not distances:
            geometry, data, spheres, hulls, own, within, reported = self._fast(scene, self_pairs, margin, scene_margin)
            if geometry is None:  # no pair
                return CollisionReport((), float("nan"), reported)
            if spheres is not None:  # an obstacle's solid, or many pairs: few pairs near
                near = spheres.near_pairs(x, within).tolist()
                flagged = self._narrow_phase(geometry, data, hulls, self.robot.to_pinocchio(x[None], checked=True)[0],
                                             near) if near else []
            else:
                any_contact = pin.computeCollisions(self.robot.model, self._data, geometry, data,
                                                    self.robot.to_pinocchio(x[None], checked=True)[0], False)
                flagged = [k for k, r in enumerate(data.collisionResults) if r.isCollision()] if any_contact else []
            if not flagged:
                return CollisionReport((), float("nan"), reported)
            found = [(k, float(pin.computeDistance(geometry, data, k).min_distance)) for k in flagged]
        else:
            for m in (margin, scene_margin):
                _check_margin(m)
            model = self._model(scene, self_pairs)
            if model is None:  # no pair
                return CollisionReport((), float("inf"), float(margin))
            geometry, data, _, own = model
            pin.computeDistances(self.robot.model, self._data, geometry, data, self.robot.to_pinocchio(x))
            found = [(k, float(r.min_distance)) for k, r in enumerate(data.distanceResults)]
        objects, pairs = geometry.geometryObjects, geometry.collisionPairs
        contacts, smallest = [], np.inf
        for k, d in found:
            smallest = min(smallest, d)
            m = margin if k < own else scene_margin
            if (d < m) if m > 0 else (d <= -TOUCH or d == 0.0):
                contacts.append(Contact(objects[pairs[k].first].name, objects[pairs[k].second].name, d))
        if not distances and not contacts:
            smallest = float("nan")
        return CollisionReport(tuple(sorted(contacts, key=lambda c: c.distance)), float(smallest),
                               float(min(margin, scene_margin) if own else scene_margin))

    def _fast(self, scene: Scene | None, self_pairs: bool, margin: float, scene_margin: float) -> tuple:
        """What the fast check reads for these arguments, made once (for the last few asked): the geometry model
        (``None``: no pair), its data with the margins, the broad phase (``None``: coal's pass over every pair),
        the hull model (:meth:`_hull_model`, its data with the margins), the count of the robot's own pairs, the
        broad phase's margin and the report's."""
        key = (id(scene), self_pairs, margin, scene_margin)
        entry = self._fast_checks.get(key)
        if entry is not None and entry[0] is scene:  # the entry holds the scene: its id stays its own
            return entry[1:]
        for m in (margin, scene_margin):
            _check_margin(m)
        model = self._model(scene, self_pairs)
        if model is None:
            return None, None, None, None, 0, 0.0, float(margin)
        geometry, data, obstacles, own = model
        margins = (float(margin), float(scene_margin), own)
        spheres = self._bounding_spheres(geometry, obstacles) \
            if len(geometry.collisionPairs) >= BROAD_PHASE_PAIRS or obstacles else None
        hulls = self._hull_model(geometry)
        if hulls is not None:
            hulls = (hulls[0], self._margin_data(hulls[0], hulls[1], margins), hulls[2])
        if len(self._fast_checks) >= 16:
            self._fast_checks.clear()
        entry = self._fast_checks[key] = (scene, geometry, self._margin_data(geometry, data, margins), spheres, hulls,
                                          own, max(margin, scene_margin),
                                          float(min(margin, scene_margin) if own else scene_margin))
        return entry[1:]


def _check_margin(margin: float) -> None:
    """Raise unless ``margin`` is a distance >= 0 [m]."""
    if not (math.isfinite(margin) and margin >= 0.0):
        raise TaskError(f"a collision check's margin must be a distance >= 0 [m]; got {margin!r}")


def _kept(cache: dict, key: object, geometry: pin.GeometryModel, make: Callable[[], Any]) -> Any:
    """``make()`` for ``geometry``, kept in ``cache`` under ``key`` (holding ``id(geometry)``; the entry holds the
    model too, so a new model that reuses a freed one's id is not served its entry); at most 17 entries."""
    entry = cache.get(key)
    if entry is None or entry[0] is not geometry:
        if len(cache) > 16:
            cache.clear()
        entry = cache[key] = (geometry, make())
    return entry[1]


def _is_mesh(geometry) -> bool:
    """Whether a coal geometry is a triangle mesh (a BVH model: not convex in general)."""
    import coal

    return isinstance(geometry, coal.BVHModelBase)
