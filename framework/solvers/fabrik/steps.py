"""Intermediate configurations between two distant base positions (paper 003, Algorithm 2).

When consecutive M-FABRIK solutions put the base more than a step ``ρ`` [m] apart, the base gets there in steps
of at most ``ρ``, each one a configuration (the base turned by the orientation rule, the arm reaching for the
target by FABRIK from where it is). No step enters or crosses the rejection area.

Deviation from Algorithm 2: *MoveOneStep* heads for the next corner of the shortest collision-free path (a
visibility graph over the corners of the obstacles dilated by the margin and a millimetre) instead of straight
for the goal; where the straight line is free the two coincide. The paper's straight-line rule can stall behind
a concave obstacle (its experiment 4 avoids this by pruning the admissible area by hand); this one always ends,
and reports ``success=False`` when no free path exists. The intermediate base positions need only be free, not
admissible for the target: they start from a base that may not reach it.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass, field

import numpy as np
import shapely

from .environment import CLEARANCE, Environment
from .mfabrik import MFabrik

#: Corners of the visibility graph lie this far [m] outside the rejection area.
CORNER_CLEARANCE = 1e-3


@dataclass(frozen=True)
class Steps:
    """The outcome of Algorithm 2.

    Attributes:
        configurations: ``(k, n)`` intermediate configurations, in order (empty when one step suffices).
        bases: ``(k + 2, 2)`` base positions [m]: the previous one, the intermediate ones, the new one.
        success: a free path exists (else ``configurations`` is empty and ``bases`` holds the two ends).
        reason: ``"direct"``, ``"steps"`` or why no path was found.
    """

    configurations: np.ndarray = field(repr=False)
    bases: np.ndarray = field(repr=False)
    success: bool
    reason: str

    @property
    def longest_step(self) -> float:
        """The largest distance [m] between consecutive base positions (Algorithm 2 keeps it <= ρ)."""
        return float(np.linalg.norm(np.diff(self.bases, axis=0), axis=1).max())


def intermediate_configurations(
    solver: MFabrik, previous: np.ndarray, new: np.ndarray, target: np.ndarray, step: float
) -> Steps:
    """Algorithm 2: configurations taking the base from ``previous`` ``(n,)`` to ``new`` ``(n,)`` in steps of at
    most ``step`` [m], in the solver's environment, the arm reaching for ``target`` ``(3,)`` [m]."""
    if not step > 0:
        raise ValueError(f"the step ρ must be a positive distance [m]; got {step}")
    ix, iy, _ = solver.arm.base
    a = np.array([previous[ix], previous[iy]], dtype=float)
    b = np.array([new[ix], new[iy]], dtype=float)
    n = solver.robot.n
    waypoints = shortest_free_path(solver.environment, a, b)
    if waypoints is None:
        return Steps(np.zeros((0, n)), np.array([a, b]), False, "no collision-free base path between the two")
    bases = [a]
    for corner in waypoints[1:]:
        gap = float(np.linalg.norm(corner - bases[-1]))
        count = max(1, math.ceil(gap / step - 1e-12))
        start = bases[-1]
        bases += [start + (corner - start) * (i / count) for i in range(1, count + 1)]
    configurations, x = [], np.asarray(previous, dtype=float)
    for base in bases[1:-1]:
        x = solver.pose_at(base, target, x)
        configurations.append(x)
    reason = "direct" if len(bases) == 2 else "steps"
    return Steps(np.array(configurations).reshape(-1, n), np.array(bases), True, reason)


def algorithm2(planner: MFabrik, initial: np.ndarray, configurations: np.ndarray, targets: np.ndarray,
               step: float) -> tuple[Steps, ...]:
    """Algorithm 2 along a tracked path: before each set-point, the steps from the previous solution (``initial``
    ``(n,)`` before the first) to its solution ``configurations[k]`` ``(m, n)``, the arm reaching for
    ``targets[k]`` ``(m, 3)`` [m], the base moving at most ``step`` [m] at a time."""
    out, previous = [], np.asarray(initial, dtype=float)
    for x, target in zip(np.asarray(configurations, dtype=float), np.asarray(targets, dtype=float)):
        out.append(intermediate_configurations(planner, previous, x, target, step))
        previous = x
    return tuple(out)


def shortest_free_path(environment: Environment, a: np.ndarray, b: np.ndarray) -> np.ndarray | None:
    """Shortest polyline ``(m, 2)`` [m] from ``a`` to ``b`` that stays in the box and out of the rejection area,
    through corners of the dilated obstacles; None if ``a`` or ``b`` is in the rejection area or none exists."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    x0, x1, y0, y1 = environment.box
    for p in (a, b):
        outside = not (x0 <= p[0] <= x1 and y0 <= p[1] <= y1)
        if outside or (environment.obstacles and shapely.intersects_xy(environment.rejection, p[0], p[1])):
            return None
    if environment.segment_is_free(a, b):
        return np.array([a, b])
    corners = _corners(environment)
    nodes = np.vstack([a, b, corners])
    i, j = np.triu_indices(len(nodes), k=1)
    lines = shapely.linestrings(np.stack([nodes[i], nodes[j]], axis=1))
    free = ~shapely.intersects(environment.rejection, lines)
    graph: list[list[tuple[int, float]]] = [[] for _ in nodes]
    for u, v in zip(i[free], j[free]):
        w = float(np.linalg.norm(nodes[u] - nodes[v]))
        graph[u].append((v, w))
        graph[v].append((u, w))
    order = _dijkstra(graph, 0, 1)
    return None if order is None else nodes[order]


def _corners(environment: Environment) -> np.ndarray:
    """Vertices of the obstacles dilated a little beyond the rejection area, inside the box, outside it."""
    points = []
    for obstacle in environment.obstacles:
        shape = obstacle.dilated(environment.margin + CLEARANCE + CORNER_CLEARANCE, resolution=4)
        points.append(np.asarray(shape.exterior.coords)[:-1])
    if not points:
        return np.zeros((0, 2))
    points = np.vstack(points)
    x0, x1, y0, y1 = environment.box
    inside = (points[:, 0] >= x0) & (points[:, 0] <= x1) & (points[:, 1] >= y0) & (points[:, 1] <= y1)
    points = points[inside]
    keep = ~shapely.intersects_xy(environment.rejection, points[:, 0], points[:, 1])
    return points[keep]


def _dijkstra(graph: list[list[tuple[int, float]]], source: int, goal: int) -> list[int] | None:
    distance, parent = {source: 0.0}, {source: -1}
    queue = [(0.0, source)]
    while queue:
        d, u = heapq.heappop(queue)
        if u == goal:
            path = [u]
            while parent[path[-1]] >= 0:
                path.append(parent[path[-1]])
            return path[::-1]
        if d > distance[u]:
            continue
        for v, w in graph[u]:
            if d + w < distance.get(v, math.inf):
                distance[v], parent[v] = d + w, u
                heapq.heappush(queue, (d + w, v))
    return None
