"""Obstacles on the floor, the rejection area around them, and the admissible area of one target (paper 003).

The obstacles are the shadows of a :class:`~framework.geometry.scene.Scene`'s (:meth:`Environment.from_scene`):
discs (:class:`Circle`) and convex polygons (:class:`Polygon`) in the floor plane.

The *rejection area* is every obstacle dilated by a safety margin (the paper: 20 cm); the base's reference point
must stay out of it. The *navigable area* is a box (the base's search bounds by default) minus the rejection
area; it may fall apart into several pieces. The *admissible area* of a target is where the base can still reach
it (a :class:`~framework.solvers.fabrik.regions.BaseReach` annulus) within the piece of the navigable area the base starts
in (paper 003: "checking the connectivity between the navigable and the admissible areas").

Polygons (shapely) approximate circles with ``4·resolution`` sides, always on the safe side: the rejection area
contains the exact dilated obstacles, the reach annulus lies inside the exact one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import shapely
import shapely.geometry as sg
from shapely.ops import unary_union

from ...errors import TaskError
from ...geometry.scene import Scene
from .regions import AnnulusInBox, BaseReach, PolygonRegion, Region

#: Extra distance [m] kept from the rejection area, so points computed on its border are outside it.
CLEARANCE = 1e-6


@dataclass(frozen=True)
class Circle:
    """A round obstacle: centre ``(x, y)`` [m] and radius [m]."""

    centre: tuple[float, float]
    radius: float

    def shape(self, resolution: int = 16) -> shapely.Geometry:
        return sg.Point(*self.centre).buffer(self.radius, quad_segs=resolution)

    def dilated(self, margin: float, resolution: int = 16) -> shapely.Geometry:
        """A polygon containing every point closer than ``margin`` [m] to the obstacle."""
        return sg.Point(*self.centre).buffer(
            (self.radius + margin) / _widen(resolution), quad_segs=resolution
        )

    def distance(self, x: float, y: float) -> float:
        """Exact distance [m] from ``(x, y)`` to the obstacle (0 inside)."""
        return max(0.0, math.hypot(x - self.centre[0], y - self.centre[1]) - self.radius)


@dataclass(frozen=True)
class Polygon:
    """A polygonal obstacle (an L-shaped wall, ...): vertices ``((x, y), ...)`` [m] in order."""

    vertices: tuple[tuple[float, float], ...]

    def __post_init__(self) -> None:
        if len(self.vertices) < 3 or not sg.Polygon(self.vertices).is_valid:
            raise TaskError(
                f"an obstacle polygon needs >= 3 vertices and no self-crossing; got {self.vertices}"
            )

    def shape(self, resolution: int = 16) -> shapely.Geometry:
        return sg.Polygon(self.vertices)

    def dilated(self, margin: float, resolution: int = 16) -> shapely.Geometry:
        return self.shape().buffer(margin / _widen(resolution), quad_segs=resolution)

    def distance(self, x: float, y: float) -> float:
        return float(self.shape().distance(sg.Point(x, y)))


Obstacle = Circle | Polygon


def _widen(resolution: int) -> float:
    """Circumscribing factor of a ``4·resolution``-gon: its sides touch the circle of radius ``r·cos(π/4res)``."""
    return math.cos(math.pi / (4 * resolution))


@dataclass(frozen=True, eq=False)
class Environment:
    """Obstacles, the safety margin, and the box the base may move in.

    Attributes:
        obstacles: circles and polygons in the floor plane.
        margin: safety distance [m] between the base's reference point and any obstacle (paper 003: 0.2).
        bounds: ``((xmin, xmax), (ymin, ymax))`` [m] of the navigable box, or None for the whole plane.
        resolution: polygon sides per quarter circle.
    """

    obstacles: tuple[Obstacle, ...] = ()
    margin: float = 0.2
    bounds: tuple[tuple[float, float], tuple[float, float]] | None = None
    resolution: int = 16

    def __post_init__(self) -> None:
        object.__setattr__(self, "obstacles", tuple(self.obstacles))
        if not (self.margin >= 0 and math.isfinite(self.margin)):
            raise TaskError(f"the safety margin must be a finite distance >= 0 [m]; got {self.margin}")
        if self.bounds is not None:
            (x0, x1), (y0, y1) = self.bounds
            if not (x0 < x1 and y0 < y1):
                raise TaskError(
                    f"navigable bounds must be ((xmin, xmax), (ymin, ymax)) with min < max; got {self.bounds}"
                )

    @classmethod
    def from_scene(cls, scene: Scene, *, margin: float = 0.2,
                   bounds: tuple[tuple[float, float], tuple[float, float]] | None = None) -> Environment:
        """The floor obstacles of a :class:`~framework.geometry.scene.Scene` (the one description the IK terms use):
        each obstacle's shadow — a disc where it is one (a ball, an upright capsule), else a convex polygon
        containing it (a prism's own floor polygon); a floor plane casts none."""
        shadows: list[Obstacle] = []
        for o in scene:
            disc = o.round_footprint()
            if disc is not None:
                shadows.append(Circle((disc[0], disc[1]), disc[2]))
                continue
            polygon = o.footprint()
            if polygon is not None:
                shadows.append(Polygon(tuple(map(tuple, np.asarray(polygon, dtype=float)))))
        return cls(tuple(shadows), margin=margin, bounds=bounds)

    @cached_property
    def key(self) -> tuple:
        """What defines the environment (its shadows, margin, box and resolution), as a hashable value."""
        return (self.obstacles, self.margin, self.bounds, self.resolution)

    # ------------------------------------------------------------------ areas
    @cached_property
    def rejection(self) -> shapely.Geometry:
        """The rejection area: the union of the obstacles dilated by ``margin`` (a polygon containing it)."""
        return unary_union([o.dilated(self.margin, self.resolution) for o in self.obstacles])

    @cached_property
    def box(self) -> tuple[float, float, float, float]:
        """``(xmin, xmax, ymin, ymax)`` [m] of the navigable box (``±inf`` when unbounded)."""
        if self.bounds is None:
            return (-math.inf, math.inf, -math.inf, math.inf)
        (x0, x1), (y0, y1) = self.bounds
        return (float(x0), float(x1), float(y0), float(y1))

    @cached_property
    def navigable(self) -> shapely.Geometry:
        """The navigable area: the box minus the rejection area (kept ``CLEARANCE`` away from it)."""
        x0, x1, y0, y1 = self.box
        if not math.isfinite(x0 + x1 + y0 + y1):
            bx0, by0, bx1, by1 = self.rejection.bounds if self.obstacles else (0.0, 0.0, 0.0, 0.0)
            x0, x1, y0, y1 = bx0 - 1e3, bx1 + 1e3, by0 - 1e3, by1 + 1e3
        keep_out = unary_union([o.dilated(self.margin + CLEARANCE, self.resolution) for o in self.obstacles])
        area = sg.box(x0, y0, x1, y1).difference(keep_out)
        shapely.prepare(area)
        return area

    @cached_property
    def pieces(self) -> tuple[shapely.Geometry, ...]:
        """The connected pieces of the navigable area."""
        area = self.navigable
        return tuple(area.geoms) if hasattr(area, "geoms") else (area,)

    def piece_of(self, x: float, y: float) -> shapely.Geometry | None:
        """The piece of the navigable area holding ``(x, y)``, or None if it is in no piece."""
        for piece in self.pieces:
            if shapely.intersects_xy(piece, x, y):
                return piece
        return None

    def admissible(self, reach: BaseReach, start: tuple[float, float] | None = None) -> Region:
        """The admissible area: ``reach`` within the navigable piece holding ``start`` (the whole navigable area
        when ``start`` is None or in no piece)."""
        if not self.obstacles and reach.wedge is None:
            return AnnulusInBox(reach, self.box)
        piece = self.piece_of(*start) if start is not None else None
        return PolygonRegion(
            reach.polygon(self.resolution).intersection(piece if piece is not None else self.navigable)
        )

    # ------------------------------------------------------------------ exact tests
    def clearance(self, x: float, y: float) -> float:
        """Exact distance [m] from ``(x, y)`` to the nearest obstacle (``inf`` without obstacles)."""
        return min((o.distance(x, y) for o in self.obstacles), default=math.inf)

    def in_rejection(self, x: float, y: float) -> bool:
        """Is ``(x, y)`` closer than ``margin`` to an obstacle (exact, not the polygon)?"""
        return self.clearance(x, y) < self.margin

    def segment_is_free(self, a: np.ndarray, b: np.ndarray) -> bool:
        """Does the segment ``a -> b`` (``(2,)`` [m]) stay in the box and out of the rejection polygon?"""
        x0, x1, y0, y1 = self.box
        for p in (a, b):
            if not (x0 <= p[0] <= x1 and y0 <= p[1] <= y1):
                return False
        return not self.obstacles or not self.rejection.intersects(sg.LineString([tuple(a), tuple(b)]))
