"""An upright prism over a convex floor polygon: a wall, a pillar, a wedge of floor (paper 003's obstacles), as one
obstacle of a :class:`~framework.geometry.scene.Scene`."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
import pinocchio as pin

from ..errors import TaskError
from .solids import SPHERE, solid_row
from .spheres import fit_spheres


@dataclass(frozen=True)
class Prism:
    """An upright prism: the convex floor polygon ``points`` ``(k, 2)`` [m] (x, y; either turning order) raised from
    height ``bottom`` [m] by ``height`` [m] — a wall, a pillar, a wedge of floor the base may not enter (paper 003's
    obstacles). The kernel sees it as ``spheres`` spheres covering its surface; the exact check uses it whole. A
    non-convex floor shape (an L-shaped wall) is given as several prisms."""

    points: np.ndarray
    height: float
    bottom: float = 0.0
    spheres: int = 16
    name: str = "prism"
    #: Its rows of :meth:`solids` cover its surface: not its exact shape.
    exact: ClassVar[bool] = False

    def __post_init__(self) -> None:
        points = np.asarray(self.points, dtype=float) if _is_numeric(self.points) else None
        if points is None or points.ndim != 2 or points.shape[1] != 2 or len(points) < 3 \
                or not np.isfinite(points).all():
            raise TaskError(f"{self.name} points must be >= 3 floor points [[x, y], ...] [m]; got {self.points!r}")
        area = 0.5 * float(np.sum(points[:, 0] * np.roll(points[:, 1], -1) - np.roll(points[:, 0], -1) * points[:, 1]))
        points = points if area > 0 else points[::-1]
        edges = np.roll(points, -1, axis=0) - points
        following = np.roll(edges, -1, axis=0)
        turns = edges[:, 0] * following[:, 1] - edges[:, 1] * following[:, 0]
        if abs(area) < 1e-12 or (turns < -1e-12).any():
            raise TaskError(f"{self.name} points must outline a convex polygon (give a non-convex floor shape as "
                            f"several prisms); got {np.asarray(self.points).tolist()}")
        object.__setattr__(self, "points", points)
        height = float(self.height) if _is_numeric(self.height) and np.ndim(self.height) == 0 else math.nan
        if not (math.isfinite(height) and height > 0):
            raise TaskError(f"{self.name} height must be a length > 0 [m]; got {self.height!r}")
        object.__setattr__(self, "height", height)
        bottom = float(self.bottom) if isinstance(self.bottom, (int, float)) and not isinstance(self.bottom, bool) \
            else math.nan
        if not math.isfinite(bottom):
            raise TaskError(f"{self.name} bottom must be a height [m]; got {self.bottom!r}")
        object.__setattr__(self, "bottom", bottom)
        if isinstance(self.spheres, bool) or not isinstance(self.spheres, (int, np.integer)) or self.spheres < 1:
            raise TaskError(f"{self.name} spheres must be an integer >= 1; got {self.spheres!r}")

    def vertices(self) -> np.ndarray:
        """``(2k, 3)`` [m]: the bottom ring, then the top ring."""
        k = len(self.points)
        return np.vstack([np.column_stack([self.points, np.full(k, z)]) for z in (self.bottom,
                                                                                  self.bottom + self.height)])

    def triangles(self) -> np.ndarray:
        """``(4k - 4, 3)`` vertex indices of its surface (caps fanned, each side two triangles), outward."""
        k = len(self.points)
        caps = [[0, j + 1, j] for j in range(1, k - 1)] + [[k, k + j, k + j + 1] for j in range(1, k - 1)]
        sides = [t for j in range(k) for t in ([j, (j + 1) % k, k + (j + 1) % k], [j, k + (j + 1) % k, k + j])]
        return np.array(caps + sides, dtype=np.int64)

    def cover(self) -> tuple[np.ndarray, np.ndarray]:
        """``(centres (s, 3), radii (s,))`` [m]: spheres whose union holds its surface."""
        import trimesh

        rng = np.random.default_rng(0)
        mesh = trimesh.Trimesh(self.vertices(), self.triangles(), process=False)
        sampled, _ = trimesh.sample.sample_surface(mesh, 3000, seed=int(rng.integers(2**31)))
        return fit_spheres(np.vstack([np.asarray(sampled), self.vertices()]), int(self.spheres), rng)

    def solids(self) -> np.ndarray:
        centers, radii = self.cover()
        return np.array([solid_row(SPHERE, np.eye(3), c, (r, 0.0, 0.0)) for c, r in zip(centers, radii)])

    def rerun(self, rr, color) -> list[tuple[str, Any]]:
        return [("", rr.Mesh3D(vertex_positions=self.vertices(), triangle_indices=self.triangles(),
                               albedo_factor=color))]

    def meshcat(self, g) -> list[tuple[str, Any, np.ndarray]]:
        return [("", g.TriangularMeshGeometry(self.vertices(), self.triangles()), np.eye(4))]

    def footprint(self) -> np.ndarray | None:
        return self.points.copy()

    def round_footprint(self) -> tuple[float, float, float] | None:
        """None: its shadow is no disc."""
        return None

    def coal(self) -> tuple[Any, pin.SE3]:
        import coal

        points = coal.StdVec_Vec3s()
        points.extend(list(self.vertices()))
        return coal.Convex.convexHull(points, False, ""), pin.SE3.Identity()


def _is_numeric(value: Any) -> bool:
    try:
        np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return False
    return True

