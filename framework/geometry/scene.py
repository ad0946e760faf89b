"""Obstacles in the robot's world: spheres, boxes, capsules, half-spaces (a floor, a wall), meshes and upright
prisms over floor polygons.

One description serves every consumer: the :class:`~framework.costs.Obstacles` term reads each solid's parameters
for the compiled signed-distance kernel (``SOLIDS`` blocks, :func:`framework.geometry.solids.solid_distance`),
the exact check builds coal geometry from it (:meth:`framework.geometry.collision.RobotShape.check` with ``scene=``),
recordings and meshcat draw it (each obstacle's ``rerun`` / ``meshcat`` method), M-FABRIK plans its base around
their shadows on the floor (``footprint``, :meth:`framework.solvers.fabrik.Environment.from_scene`), and task files give
it as ``[[obstacles]]`` tables::

    table = Box(center=[0.6, 0.0, 0.35], size=[0.8, 1.2, 0.05])
    scene = Scene((table, Plane(point=[0, 0, 0], normal=[0, 0, 1]), Sphere([0.4, 0.2, 0.8], 0.1)))

Units are metres; a rotation is any form :mod:`framework.model.rotations` reads (4 numbers with
``quaternion="xyzw"`` or ``"wxyz"``; task files: ``rpy`` in radians, or ``rotation`` with ``quaternion``). A mesh is approximated by spheres covering its surface for the
kernel (the fitting of :mod:`framework.geometry.spheres`) and used whole by the exact check; so is a prism.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import pinocchio as pin

from ..errors import TaskError
from ..model.rotations import rotation_from
from .prism import Prism
from .solids import BOX, CAPSULE, HALFSPACE, SPHERE, solid_row
from .spheres import fit_spheres, mesh_surface_points
from ..validate import check_table

#: Extent of a half-space's stand-in box for the exact check [m]: wide and deep beside any robot.
HALFSPACE_EXTENT = 200.0


def _vector(value: Any, size: int, what: str) -> np.ndarray:
    try:
        v = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise TaskError(f"{what} must be {size} numbers; got {value!r}") from None
    if v.shape != (size,) or not np.isfinite(v).all():
        raise TaskError(f"{what} must be {size} finite numbers; got {value!r}")
    return v


def _positive(value: Any, what: str, *, zero: bool = False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise TaskError(f"{what} must be a number [m]; got {value!r}") from None
    if not np.isfinite(v) or v < 0 or (v == 0 and not zero):
        raise TaskError(f"{what} must be a finite number {'>=' if zero else '>'} 0 [m]; got {value!r}")
    return v


def _rotation(shape: Any, what: str) -> None:
    """``shape.rotation`` made a validated matrix (the identity when not given; 4 numbers in ``shape.quaternion``
    order), and ``shape.quaternion`` cleared (the rotation is a matrix now)."""
    value = np.eye(3) if shape.rotation is None else rotation_from(shape.rotation, what, shape.quaternion)
    object.__setattr__(shape, "rotation", value)
    object.__setattr__(shape, "quaternion", None)


def _ring(center: np.ndarray, radius: float, sides: int = 32) -> np.ndarray:
    """A horizontal ``sides``-gon around a ball's shadow, circumscribed (its sides touch the circle) ``(sides, 3)``."""
    angles = np.linspace(0, 2 * np.pi, sides, endpoint=False)
    r = radius / np.cos(np.pi / sides)
    return np.column_stack([center[0] + r * np.cos(angles), center[1] + r * np.sin(angles), np.zeros(sides)])


def _hull(points: np.ndarray) -> np.ndarray:
    """The convex hull ``(k, 2)`` of points' (x, y), counter-clockwise."""
    from scipy.spatial import ConvexHull

    xy = np.asarray(points, dtype=float)[:, :2]
    return xy[ConvexHull(xy).vertices]


def _placement(rotation: np.ndarray, center: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = rotation, center
    return T


def _xyzw(rr, rotation: np.ndarray):
    return rr.Quaternion(xyzw=pin.Quaternion(np.asarray(rotation)).coeffs())


@dataclass(frozen=True)
class Sphere:
    """A ball of ``radius`` [m] at ``center`` (3,) [m]."""

    center: np.ndarray
    radius: float
    name: str = "sphere"
    #: Its one row of :meth:`solids` is its exact shape (the exact check's broad phase measures it).
    exact: ClassVar[bool] = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", _vector(self.center, 3, f"{self.name} center"))
        object.__setattr__(self, "radius", _positive(self.radius, f"{self.name} radius"))

    def solids(self) -> np.ndarray:
        """Kernel parameters ``(1, 16)``."""
        return solid_row(SPHERE, np.eye(3), self.center, (self.radius, 0.0, 0.0))[None]

    def rerun(self, rr, color) -> list[tuple[str, Any]]:
        """``(sub-entity, rerun archetype)`` pairs that draw it."""
        return [("", rr.Ellipsoids3D(centers=[self.center], half_sizes=[[self.radius] * 3], colors=[color],
                                     fill_mode="solid"))]

    def meshcat(self, g) -> list[tuple[str, Any, np.ndarray]]:
        """``(sub-path, meshcat geometry, 4x4 placement)`` triples that draw it."""
        return [("", g.Sphere(self.radius), _placement(np.eye(3), self.center))]

    def footprint(self) -> np.ndarray | None:
        """Its shadow on the floor (x, y): a convex polygon ``(k, 2)`` [m] containing it (M-FABRIK's obstacles)."""
        return _hull(_ring(self.center, self.radius))

    def round_footprint(self) -> tuple[float, float, float] | None:
        """Its shadow when a disc: ``(x, y, radius)`` [m] (exact, where :meth:`footprint` is a polygon)."""
        return float(self.center[0]), float(self.center[1]), self.radius

    def coal(self) -> tuple[Any, pin.SE3]:
        """The exact geometry and its placement in the world."""
        import coal

        return coal.Sphere(self.radius), pin.SE3(np.eye(3), self.center)


@dataclass(frozen=True)
class Box:
    """A box of edge lengths ``size`` (3,) [m] centred at ``center`` (3,) [m], turned by ``rotation``."""

    center: np.ndarray
    size: np.ndarray
    rotation: np.ndarray | None = None
    name: str = "box"
    #: the order of ``rotation`` given as 4 numbers: ``"xyzw"`` or ``"wxyz"`` (:mod:`~framework.model.rotations`)
    quaternion: str | None = None
    #: Its one row of :meth:`solids` is its exact shape (the exact check's broad phase measures it).
    exact: ClassVar[bool] = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", _vector(self.center, 3, f"{self.name} center"))
        size = _vector(self.size, 3, f"{self.name} size")
        if (size <= 0).any():
            raise TaskError(f"{self.name} size must be three edge lengths > 0 [m]; got {size.tolist()}")
        object.__setattr__(self, "size", size)
        _rotation(self, f"{self.name} rotation")

    def solids(self) -> np.ndarray:
        return solid_row(BOX, self.rotation, self.center, self.size / 2)[None]

    def rerun(self, rr, color) -> list[tuple[str, Any]]:
        return [("", rr.Boxes3D(centers=[self.center], half_sizes=[self.size / 2], quaternions=[_xyzw(rr, self.rotation)],
                                colors=[color], fill_mode="solid"))]

    def meshcat(self, g) -> list[tuple[str, Any, np.ndarray]]:
        return [("", g.Box(self.size.tolist()), _placement(self.rotation, self.center))]

    def footprint(self) -> np.ndarray | None:
        corners = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)]) * self.size / 2
        return _hull(corners @ self.rotation.T + self.center)

    def round_footprint(self) -> tuple[float, float, float] | None:
        """None: its shadow is no disc."""
        return None

    def coal(self) -> tuple[Any, pin.SE3]:
        import coal

        return coal.Box(*self.size), pin.SE3(self.rotation, self.center)


@dataclass(frozen=True)
class Capsule:
    """A capsule: the points within ``radius`` [m] of a segment of ``length`` [m] along the local z axis through
    ``center`` (3,) [m], turned by ``rotation``."""

    center: np.ndarray
    radius: float
    length: float
    rotation: np.ndarray | None = None
    name: str = "capsule"
    #: the order of ``rotation`` given as 4 numbers: ``"xyzw"`` or ``"wxyz"`` (:mod:`~framework.model.rotations`)
    quaternion: str | None = None
    #: Its one row of :meth:`solids` is its exact shape (the exact check's broad phase measures it).
    exact: ClassVar[bool] = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", _vector(self.center, 3, f"{self.name} center"))
        object.__setattr__(self, "radius", _positive(self.radius, f"{self.name} radius"))
        object.__setattr__(self, "length", _positive(self.length, f"{self.name} length", zero=True))
        _rotation(self, f"{self.name} rotation")

    def solids(self) -> np.ndarray:
        return solid_row(CAPSULE, self.rotation, self.center, (self.radius, self.length / 2, 0.0))[None]

    def rerun(self, rr, color) -> list[tuple[str, Any]]:
        end = self.center - self.rotation[:, 2] * self.length / 2  # rerun places a capsule by one end
        return [("", rr.Capsules3D(lengths=[self.length], radii=[self.radius], translations=[end],
                                   quaternions=[_xyzw(rr, self.rotation)], colors=[color], fill_mode="solid"))]

    def meshcat(self, g) -> list[tuple[str, Any, np.ndarray]]:
        """A cylinder (meshcat's run along y: turned onto z) and a sphere on each end."""
        R, axis = self.rotation, self.rotation[:, 2]
        along_z = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])
        return [("/body", g.Cylinder(self.length, self.radius), _placement(R @ along_z, self.center)),
                ("/end0", g.Sphere(self.radius), _placement(R, self.center - axis * self.length / 2)),
                ("/end1", g.Sphere(self.radius), _placement(R, self.center + axis * self.length / 2))]

    def footprint(self) -> np.ndarray | None:
        axis = self.rotation[:, 2] * self.length / 2
        return _hull(np.vstack([_ring(self.center - axis, self.radius), _ring(self.center + axis, self.radius)]))

    def round_footprint(self) -> tuple[float, float, float] | None:
        """An upright capsule's shadow, a disc ``(x, y, radius)`` [m]; None when tilted."""
        if abs(self.rotation[2, 2]) < 1 - 1e-12:
            return None
        return float(self.center[0]), float(self.center[1]), self.radius

    def coal(self) -> tuple[Any, pin.SE3]:
        import coal

        return coal.Capsule(self.radius, self.length), pin.SE3(self.rotation, self.center)


@dataclass(frozen=True)
class Plane:
    """The half-space behind a plane through ``point`` (3,) [m] with outward ``normal`` (3,): a floor
    (``normal = [0, 0, 1]``) or a wall. Everything on the normal's side is free."""

    point: np.ndarray
    normal: np.ndarray
    name: str = "plane"
    #: Its one row of :meth:`solids` is its exact shape (the exact check's broad phase measures it).
    exact: ClassVar[bool] = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "point", _vector(self.point, 3, f"{self.name} point"))
        normal = _vector(self.normal, 3, f"{self.name} normal")
        if np.linalg.norm(normal) < 1e-9:
            raise TaskError(f"{self.name} normal must not be zero")
        object.__setattr__(self, "normal", normal / np.linalg.norm(normal))

    @property
    def rotation(self) -> np.ndarray:
        """A rotation whose z axis is the normal."""
        return pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), self.normal).toRotationMatrix()

    def solids(self) -> np.ndarray:
        return solid_row(HALFSPACE, self.rotation, self.point, (0.0, 0.0, 0.0))[None]

    def rerun(self, rr, color) -> list[tuple[str, Any]]:
        """A 2 m square slab 1 mm thick whose top face is the plane, around its point."""
        R = self.rotation
        return [("", rr.Boxes3D(centers=[self.point - R[:, 2] * 5e-4], half_sizes=[[1.0, 1.0, 5e-4]],
                                quaternions=[_xyzw(rr, R)], colors=[color], fill_mode="solid"))]

    def meshcat(self, g) -> list[tuple[str, Any, np.ndarray]]:
        R = self.rotation
        return [("", g.Box([2.0, 2.0, 1e-3]), _placement(R, self.point - R[:, 2] * 5e-4))]

    def footprint(self) -> np.ndarray | None:
        """None for a floor or a ceiling (horizontal); a wall's shadow is unbounded: an error."""
        if abs(self.normal[2]) > 1 - 1e-9:
            return None
        raise TaskError(f"{self.name}: a tilted or vertical plane has no bounded footprint on the floor; "
                        "use a box for a wall")

    def round_footprint(self) -> tuple[float, float, float] | None:
        """None: its shadow is no disc."""
        return None

    def coal(self) -> tuple[Any, pin.SE3]:
        """A wide, deep box whose top face is the plane (coal's half-spaces have no distance to meshes)."""
        import coal

        R = self.rotation
        return (coal.Box(HALFSPACE_EXTENT, HALFSPACE_EXTENT, HALFSPACE_EXTENT / 2),
                pin.SE3(R, self.point - R[:, 2] * HALFSPACE_EXTENT / 4))


@dataclass(frozen=True)
class Mesh:
    """A triangle mesh from ``path`` (STL, OBJ, DAE, ...; scaled by ``scale`` (3,)) placed at ``center`` with
    ``rotation``. The kernel sees it as ``spheres`` spheres covering its surface; the exact check uses it whole."""

    path: str | Path
    center: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rotation: np.ndarray | None = None
    scale: np.ndarray = field(default_factory=lambda: np.ones(3))
    spheres: int = 16
    name: str = "mesh"
    #: the order of ``rotation`` given as 4 numbers: ``"xyzw"`` or ``"wxyz"`` (:mod:`~framework.model.rotations`)
    quaternion: str | None = None
    #: Its rows of :meth:`solids` cover its surface: not its exact shape.
    exact: ClassVar[bool] = False

    def __post_init__(self) -> None:
        if not Path(self.path).is_file():
            raise TaskError(f"{self.name}: mesh file {self.path} does not exist")
        object.__setattr__(self, "center", _vector(self.center, 3, f"{self.name} center"))
        _rotation(self, f"{self.name} rotation")
        scale = _vector(self.scale, 3, f"{self.name} scale")
        if (scale <= 0).any():
            raise TaskError(f"{self.name} scale must be three factors > 0; got {scale.tolist()}")
        object.__setattr__(self, "scale", scale)
        if isinstance(self.spheres, bool) or not isinstance(self.spheres, (int, np.integer)) or self.spheres < 1:
            raise TaskError(f"{self.name} spheres must be an integer >= 1; got {self.spheres!r}")

    def cover(self) -> tuple[np.ndarray, np.ndarray]:
        """``(centres (k, 3), radii (k,))`` in the world: spheres whose union holds the mesh's surface."""
        rng = np.random.default_rng(0)
        local = mesh_surface_points(str(self.path), 3000, rng, self.scale)
        centers, radii = fit_spheres(local @ self.rotation.T + self.center, int(self.spheres), rng)
        return centers, radii

    def solids(self) -> np.ndarray:
        centers, radii = self.cover()
        return np.array([solid_row(SPHERE, np.eye(3), c, (r, 0.0, 0.0)) for c, r in zip(centers, radii)])

    def rerun(self, rr, color) -> list[tuple[str, Any]]:
        import trimesh

        mesh = trimesh.load(str(self.path), force="mesh")
        mesh.apply_scale(self.scale)
        return [("", rr.Transform3D(translation=self.center, mat3x3=self.rotation)),
                ("/mesh", rr.Mesh3D(vertex_positions=mesh.vertices, triangle_indices=mesh.faces,
                                    albedo_factor=color))]

    def meshcat(self, g) -> list[tuple[str, Any, np.ndarray]]:
        import trimesh

        mesh = trimesh.load(str(self.path), force="mesh")
        mesh.apply_scale(self.scale)
        return [("", g.TriangularMeshGeometry(np.asarray(mesh.vertices), np.asarray(mesh.faces)),
                 _placement(self.rotation, self.center))]

    def footprint(self) -> np.ndarray | None:
        import trimesh

        vertices = np.asarray(trimesh.load(str(self.path), force="mesh").vertices) * self.scale
        return _hull(vertices @ self.rotation.T + self.center)

    def round_footprint(self) -> tuple[float, float, float] | None:
        """None: its shadow is no disc."""
        return None

    def coal(self) -> tuple[Any, pin.SE3]:
        import coal

        loader = coal.MeshLoader()
        try:
            geometry = loader.load(str(self.path), np.asarray(self.scale, dtype=float))
        except Exception as err:  # coal raises RuntimeError or assimp's errors on unreadable files
            raise TaskError(f"{self.name}: cannot read the mesh {self.path}: {err}") from None
        return geometry, pin.SE3(self.rotation, self.center)


Obstacle = Sphere | Box | Capsule | Plane | Mesh | Prism
KINDS: dict[str, type] = {"sphere": Sphere, "box": Box, "capsule": Capsule, "plane": Plane, "mesh": Mesh,
                          "prism": Prism}
KINDS_TUPLE = tuple(KINDS.values())


@dataclass(frozen=True)
class Scene:
    """The obstacles of a world (a tuple of :data:`Obstacle`)."""

    obstacles: tuple[Obstacle, ...] = ()

    def __post_init__(self) -> None:
        obstacles = tuple(self.obstacles) if not isinstance(self.obstacles, KINDS_TUPLE) else (self.obstacles,)
        for k, o in enumerate(obstacles):
            if not isinstance(o, KINDS_TUPLE):
                raise TaskError(f"obstacle {k} must be a Sphere, Box, Capsule, Plane, Mesh or Prism; got {o!r}")
        names = [o.name for o in obstacles]
        repeated = sorted({n for n in names if names.count(n) > 1})
        if repeated:  # reports and recordings name obstacles; give each its own
            obstacles = tuple(_renamed(o, f"{o.name}{names[:k].count(o.name) + 1}") if o.name in repeated else o
                              for k, o in enumerate(obstacles))
        object.__setattr__(self, "obstacles", obstacles)

    def __len__(self) -> int:
        return len(self.obstacles)

    def __iter__(self):
        return iter(self.obstacles)

    def solids(self) -> np.ndarray:
        """``(k, 16)`` kernel parameters of every solid (a mesh gives one sphere per row of its cover)."""
        rows = [o.solids() for o in self.obstacles]
        return np.vstack(rows) if rows else np.zeros((0, 16))

    @classmethod
    def from_tables(cls, tables: Sequence[Mapping[str, Any]], where: str = "obstacles",
                    folder: Path | None = None) -> Scene:
        """A scene from task-file tables: ``{type = "box", center = [...], size = [...], rpy = [...]}`` (keys by
        type in :data:`TABLES`); a mesh path is relative to ``folder``."""
        if not isinstance(tables, (list, tuple)):
            raise TaskError(f"{where} must be a list of tables ([[obstacles]]); got {tables!r}")
        return cls(tuple(_from_table(t, f"{where}[{k}]", folder) for k, t in enumerate(tables)))


_ROTATION = {"rpy": "list", "rotation": "list", "quaternion": "text"}
#: An ``[[obstacles]]`` table by type: its required keys and every key's value kind (:mod:`framework.validate`).
TABLES: dict[str, tuple[tuple[str, ...], dict[str, str]]] = {
    "sphere": (("center", "radius"), {"center": "list", "radius": "number"}),
    "box": (("center", "size"), {"center": "list", "size": "list", **_ROTATION}),
    "capsule": (("center", "radius", "length"), {"center": "list", "radius": "number", "length": "number",
                                                 **_ROTATION}),
    "plane": (("point", "normal"), {"point": "list", "normal": "list"}),
    "mesh": (("path",), {"path": "text", "center": "list", "scale": "list", "spheres": "integer", **_ROTATION}),
    "prism": (("points", "height"), {"points": "list", "height": "number", "bottom": "number", "spheres": "integer"}),
}


def _from_table(table: Any, where: str, folder: Path | None) -> Obstacle:
    if not isinstance(table, Mapping):
        raise TaskError(f"{where} must be a table; got {table!r}")
    kind = table.get("type")
    if kind not in KINDS:
        raise TaskError(f"{where}: type must be one of {sorted(KINDS)}; got {kind!r}")
    required, schema = TABLES[kind]
    check_table(table, {"type": "text", "name": "text", **schema}, where)
    missing = [k for k in required if k not in table]
    if missing:
        raise TaskError(f"{where} ({kind}) needs {', '.join(missing)}")
    if "rpy" in table and ("rotation" in table or "quaternion" in table):
        raise TaskError(f"{where}: give either rpy or rotation (with quaternion for 4 numbers), not both")
    args = {k: v for k, v in table.items() if k not in ("type", "name", "rpy")}
    if "rpy" in table:
        args["rotation"] = pin.rpy.rpyToMatrix(_vector(table["rpy"], 3, f"{where} rpy"))
    if kind == "mesh" and folder is not None and not Path(args["path"]).is_absolute():
        args["path"] = str(folder / args["path"])
    return KINDS[kind](**args, name=table.get("name", kind))


def _renamed(obstacle: Obstacle, name: str) -> Obstacle:
    from dataclasses import replace

    return replace(obstacle, name=name)
