"""Regions of the floor plane where a mobile base may stand, with the two queries M-FABRIK asks of them.

``contains(x, y)``: may the base stand at ``(x, y)`` [m]? ``nearest(x, y)``: the closest point where it may
(Algorithm 1's *MoveToAdmArea*). :class:`AnnulusInBox` answers both in closed form (no obstacles: the common case,
and the fast one); :class:`PolygonRegion` answers them with shapely for any polygonal area (obstacles removed).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Protocol

import shapely
import shapely.geometry as sg
from shapely.ops import nearest_points

#: Slack [m] of membership tests on boundary points computed in floating point.
SLACK = 1e-9


class Region(Protocol):
    """A closed set of base positions in the floor plane [m]."""

    @property
    def is_empty(self) -> bool: ...

    def contains(self, x: float, y: float) -> bool: ...

    def nearest(self, x: float, y: float) -> tuple[float, float]: ...

    def geometry(self) -> shapely.Geometry: ...


@dataclass(frozen=True)
class BaseReach:
    """Base positions from which the arm can reach a target, ignoring obstacles: an annulus, maybe cut to a wedge.

    Attributes:
        centre: ``(x, y)`` centre of the annulus [m].
        inner, outer: radii [m].
        wedge: ``(start, end)`` [rad] directions from the centre the base may lie in (counter-clockwise from
            ``start`` to ``end``), or None for all directions.
    """

    centre: tuple[float, float]
    inner: float
    outer: float
    wedge: tuple[float, float] | None = None

    def polygon(self, resolution: int = 16) -> shapely.Geometry:
        """The region as a polygon that lies inside the exact one (outer circle inscribed, inner circumscribed)."""
        cx, cy = self.centre
        ring = sg.Point(cx, cy).buffer(self.outer, quad_segs=resolution)
        if self.inner > 1e-9:  # GEOS cannot buffer by a subnormal radius
            ring = ring.difference(
                sg.Point(cx, cy).buffer(
                    self.inner / math.cos(math.pi / (4 * resolution)), quad_segs=resolution
                )
            )
        if self.wedge is not None:
            start, end = self.wedge
            span = (end - start) % (2 * math.pi)
            n = max(2, math.ceil(span / (math.pi / 32)))
            radius = 2 * self.outer + 1.0
            arc = [
                (cx + radius * math.cos(start + span * i / n), cy + radius * math.sin(start + span * i / n))
                for i in range(n + 1)
            ]
            ring = ring.intersection(sg.Polygon([(cx, cy), *arc]))
        return ring


@dataclass(frozen=True)
class AnnulusInBox:
    """An annulus intersected with an axis-aligned box (``±inf`` bounds allowed), in closed form.

    Attributes:
        reach: the annulus (without a wedge).
        box: ``(xmin, xmax, ymin, ymax)`` [m].
    """

    reach: BaseReach
    box: tuple[float, float, float, float] = (-math.inf, math.inf, -math.inf, math.inf)

    @property
    def is_empty(self) -> bool:
        """Empty iff the distances from the centre to the box's points miss ``[inner, outer]``."""
        (cx, cy), (x0, x1, y0, y1) = self.reach.centre, self.box
        if self.reach.inner > self.reach.outer or x0 > x1 or y0 > y1:
            return True
        near = math.hypot(cx - min(max(cx, x0), x1), cy - min(max(cy, y0), y1))
        far = math.hypot(max(abs(cx - x0), abs(cx - x1)), max(abs(cy - y0), abs(cy - y1)))
        return near > self.reach.outer or far < self.reach.inner

    def contains(self, x: float, y: float) -> bool:
        (cx, cy), (x0, x1, y0, y1) = self.reach.centre, self.box
        r = math.hypot(x - cx, y - cy)
        return (
            self.reach.inner - SLACK <= r <= self.reach.outer + SLACK
            and x0 - SLACK <= x <= x1 + SLACK
            and y0 - SLACK <= y <= y1 + SLACK
        )

    def nearest(self, x: float, y: float) -> tuple[float, float]:
        """Closest point: among the radial projections, the feet on the box edges, the box corners and the
        circle-edge crossings (every point where the distance to ``(x, y)`` can be least on the boundary)."""
        if self.contains(x, y):
            return x, y
        (cx, cy), (x0, x1, y0, y1) = self.reach.centre, self.box
        radii = (self.reach.inner, self.reach.outer)
        r = math.hypot(x - cx, y - cy)
        ux, uy = ((x - cx) / r, (y - cy) / r) if r > 0 else (1.0, 0.0)
        # Inside the box, only the annulus excludes the point: its radial projection, if that is in the box too.
        if x0 <= x <= x1 and y0 <= y <= y1:
            R = min(max(r, self.reach.inner), self.reach.outer)
            px, py = cx + R * ux, cy + R * uy
            if x0 <= px <= x1 and y0 <= py <= y1:
                return px, py
        candidates = [(cx + R * ux, cy + R * uy) for R in radii]
        candidates.append((min(max(x, x0), x1), min(max(y, y0), y1)))
        for xe in (x0, x1):
            if math.isfinite(xe):
                candidates.append((xe, min(max(y, y0), y1)))
                candidates += [(xe, yc) for yc in _crossings(cx, cy, radii, xe)]
        for ye in (y0, y1):
            if math.isfinite(ye):
                candidates.append((min(max(x, x0), x1), ye))
                candidates += [(xc, ye) for xc in _crossings(cy, cx, radii, ye)]
        candidates += [(a, b) for a in (x0, x1) for b in (y0, y1) if math.isfinite(a) and math.isfinite(b)]
        inside = [p for p in candidates if self.contains(*p)]
        if not inside:
            return x, y
        px, py = min(inside, key=lambda p: (p[0] - x) ** 2 + (p[1] - y) ** 2)
        return min(max(px, x0), x1), min(max(py, y0), y1)

    def geometry(self) -> shapely.Geometry:
        bounds = [b if math.isfinite(b) else math.copysign(1e3, b) for b in self.box]
        return self.reach.polygon().intersection(sg.box(bounds[0], bounds[2], bounds[1], bounds[3]))


def _crossings(cu: float, cv: float, radii: tuple[float, float], line: float):
    """Where the line ``u = line`` crosses the circles of centre ``(cu, cv)``: their ``v`` coordinates."""
    for R in radii:
        d = line - cu
        if R > 0 and abs(d) <= R:
            half = math.sqrt(R * R - d * d)
            yield cv - half
            yield cv + half


@dataclass(frozen=True, eq=False)
class PolygonRegion:
    """Any polygonal region (shapely geometry), prepared for fast membership tests."""

    shape: shapely.Geometry = field(repr=False)

    def __post_init__(self) -> None:
        shapely.prepare(self.shape)

    @property
    def is_empty(self) -> bool:
        return self.shape.is_empty or self.shape.area <= 0.0

    def contains(self, x: float, y: float) -> bool:
        return bool(shapely.intersects_xy(self.shape, x, y))

    def nearest(self, x: float, y: float) -> tuple[float, float]:
        if self.contains(x, y):
            return x, y
        point = nearest_points(self.shape, sg.Point(x, y))[0]
        return point.x, point.y

    def geometry(self) -> shapely.Geometry:
        return self.shape
