"""Sphere covers of a robot's collision geometry: a few spheres per geometry whose union holds its surface, the
fast approximation for distances over whole populations (as cuRobo and PyRoki use).

The fitting, per geometry object of a :class:`~framework.geometry.collision.RobotShape`: sample its surface (spheres, boxes,
cylinders and capsules analytically; meshes with trimesh, their vertices included), in its joint's frame; split the
samples into ``count`` clusters (k-means, seeded); each sphere is a cluster's centre with the largest distance to
its points, plus a pad — the largest distance from a sample to its nearest other sample, which bounds how far a
surface point can be from every sample (so points between samples are covered too; the tests check surface points
drawn independently).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
import pinocchio as pin

from ..errors import RobotFileError



class RobotShape(Protocol):
    """What a sphere cover reads of a robot's shape (:class:`~framework.geometry.collision.RobotShape`, which
    imports this module): its robot and its Pinocchio geometry model."""

    robot: Any  # framework.model.robot.Robot
    geometry: Any  # pinocchio.GeometryModel


#: The most spheres :func:`sphere_cover` puts on one geometry.
MAX_PER_GEOMETRY = 64


@dataclass(frozen=True)
class SphereCover:
    """Spheres moving with the robot's joints.

    Attributes:
        joints: ``(m,)`` Pinocchio joint index each sphere moves with (0: fixed in the world).
        centers: ``(m, 3)`` centres in that joint's frame [m].
        radii: ``(m,)`` radii [m].
        geometries: ``(m,)`` the name of the geometry object each sphere covers.
    """

    joints: np.ndarray
    centers: np.ndarray
    radii: np.ndarray
    geometries: tuple[str, ...]

    def world_centers(self, shape: RobotShape, x: np.ndarray) -> np.ndarray:
        """``(m, 3)`` world centres at joint coordinates ``x`` ``(n,)`` (Pinocchio's FK)."""
        model, data = shape.robot.model, shape.robot.model.createData()
        pin.forwardKinematics(model, data, shape.robot.to_pinocchio(np.asarray(x, dtype=float)))
        return np.array([data.oMi[int(j)].act(c) for j, c in zip(self.joints, self.centers)])


def _unit_sphere(count: int, rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=(count, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def surface_points(geometry, count: int, rng: np.random.Generator, mesh_path: str = "",
                   mesh_scale: np.ndarray | None = None) -> np.ndarray:
    """About ``count`` points on the surface of a coal shape, in its own frame ``(k, 3)`` [m]."""
    import coal

    if isinstance(geometry, coal.Sphere):
        return geometry.radius * _unit_sphere(count, rng)
    if isinstance(geometry, coal.Box):
        h = np.asarray(geometry.halfSide, dtype=float)
        areas = np.array([h[1] * h[2], h[0] * h[2], h[0] * h[1]])
        axes = rng.choice(3, size=count, p=areas / areas.sum())
        points = rng.uniform(-h, h, size=(count, 3))
        points[np.arange(count), axes] = h[axes] * rng.choice([-1.0, 1.0], size=count)
        return points
    if isinstance(geometry, (coal.Cylinder, coal.Capsule)):
        r, half = float(geometry.radius), float(geometry.halfLength)
        capsule = isinstance(geometry, coal.Capsule)
        side, ends = 2 * np.pi * r * 2 * half, (4 * np.pi * r * r if capsule else 2 * np.pi * r * r)
        on_side = rng.random(count) < side / (side + ends)
        angle = rng.uniform(0, 2 * np.pi, count)
        points = np.column_stack([r * np.cos(angle), r * np.sin(angle), rng.uniform(-half, half, count)])
        k = int((~on_side).sum())
        if capsule:  # hemispheres on the ends: a sphere split at its equator, the halves moved apart
            cap = r * _unit_sphere(k, rng)
            cap[:, 2] += np.where(cap[:, 2] >= 0, half, -half)
            points[~on_side] = cap
        else:  # discs on the ends
            rho = r * np.sqrt(rng.random(k))
            points[~on_side] = np.column_stack([rho * np.cos(angle[~on_side]), rho * np.sin(angle[~on_side]),
                                                half * rng.choice([-1.0, 1.0], k)])
        return points
    if mesh_path:
        return mesh_surface_points(mesh_path, count, rng, mesh_scale)
    raise RobotFileError(f"collision geometry of type {type(geometry).__name__} cannot be covered by spheres")


def mesh_surface_points(path: str, count: int, rng: np.random.Generator, scale: np.ndarray | None = None
                        ) -> np.ndarray:
    """About ``count`` points on a mesh file's surface and its vertices, scaled by ``scale`` (3,) ``(k, 3)`` [m]."""
    import trimesh

    try:
        mesh = trimesh.load(path, force="mesh")
    except Exception as err:  # trimesh raises many types on unreadable files
        raise RobotFileError(f"cannot read the mesh {path}: {err}") from None
    scale = np.ones(3) if scale is None else np.asarray(scale, dtype=float)
    sampled, _ = trimesh.sample.sample_surface(mesh, count, seed=int(rng.integers(2**31)))
    return np.vstack([np.asarray(sampled), np.asarray(mesh.vertices)]) * scale


def fit_spheres(points: np.ndarray, count: int, rng: np.random.Generator, *, iterations: int = 30
                ) -> tuple[np.ndarray, np.ndarray]:
    """``count`` spheres ``(centres (k, 3), radii (k,))`` whose union holds ``points`` ``(p, 3)`` and the surface
    between them (see the module docstring): k-means++ seeding, Lloyd iterations, radii to the farthest point of
    each cluster plus the sampling pad."""
    from scipy.spatial import cKDTree

    count = max(1, min(count, len(points)))
    centers = [points[rng.integers(len(points))]]
    for _ in range(count - 1):  # k-means++
        d2 = np.min([np.sum((points - c) ** 2, axis=1) for c in centers], axis=0)
        centers.append(points[rng.choice(len(points), p=d2 / d2.sum())] if d2.sum() > 0 else centers[0])
    centers = np.array(centers)
    for _ in range(iterations):
        label = np.argmin(((points[:, None] - centers[None]) ** 2).sum(-1), axis=1)
        moved = np.array([points[label == j].mean(axis=0) if np.any(label == j) else centers[j]
                          for j in range(count)])
        if np.allclose(moved, centers):
            break
        centers = moved
    label = np.argmin(((points[:, None] - centers[None]) ** 2).sum(-1), axis=1)
    pad = float(cKDTree(points).query(points, k=2)[0][:, 1].max()) if len(points) > 1 else 0.0
    radii = np.array([np.linalg.norm(points[label == j] - centers[j], axis=1).max() if np.any(label == j) else 0.0
                      for j in range(count)]) + pad
    # a sphere of radius pad (an empty cluster, or a single point) is inside the union of the others: its point's
    # nearest sample is within pad and lies in a sphere that reaches pad beyond it; all kept if every one is so
    keep = radii > pad if np.any(radii > pad) else np.ones(count, dtype=bool)
    return centers[keep], radii[keep]


def sphere_cover(shape: RobotShape, *, per_geometry: int = 4, max_radius: float | None = 0.08, samples: int = 1500,
                 seed: int = 0) -> SphereCover:
    """Cover every collision geometry of ``shape`` by spheres (see the module docstring; a sphere by itself):
    ``per_geometry`` spheres, doubled (up to 64) while the largest is over ``max_radius`` [m] (a sphere geometry
    is its own cover whatever its size) — a large link
    covered by a few spheres would be much fatter than it is and could keep collision-free configurations out."""
    import coal

    rng = np.random.default_rng(seed)
    joints, centers, radii, names = [], [], [], []
    for g in shape.geometry.geometryObjects:
        if isinstance(g.geometry, coal.Sphere):  # a sphere covers itself
            c, r = g.placement.translation[None].copy(), np.array([float(g.geometry.radius)])
        else:
            local = surface_points(g.geometry, samples, rng, g.meshPath, g.meshScale)
            points = local @ g.placement.rotation.T + g.placement.translation  # in the joint frame
            count = per_geometry
            c, r = fit_spheres(points, count, rng)
            while max_radius is not None and r.max() > max_radius and count < MAX_PER_GEOMETRY:
                count *= 2
                c, r = fit_spheres(points, count, rng)
        joints += [g.parentJoint] * len(r)
        centers.append(c)
        radii.append(r)
        names += [g.name] * len(r)
    return SphereCover(np.array(joints, dtype=np.int64), np.vstack(centers), np.concatenate(radii), tuple(names))
