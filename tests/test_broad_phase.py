"""The exact check's broad phase: each bounding sphere holds its geometry (sampled surface points and mesh
vertices), every pair coal finds closer than a margin is among the near pairs (configurations on the boundary of a
contact, PR2's meshes, the youBot's spheres and box, every obstacle kind), and the broad phase leaves most pairs
out."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import framework as fw
from framework.geometry.broad_phase import bounding_sphere, bounding_spheres
from framework.geometry.spheres import mesh_surface_points, surface_points

PR2_JOINTS = ["torso_lift_joint", "l_shoulder_pan_joint", "l_shoulder_lift_joint", "l_elbow_flex_joint",
              "r_shoulder_pan_joint", "r_shoulder_lift_joint", "r_elbow_flex_joint"]


@pytest.fixture(scope="module")
def pr2(erd):
    robot = fw.load_robot(erd / "pr2_description" / "urdf" / "pr2.urdf", joints=PR2_JOINTS)
    return robot, fw.RobotShape(robot)


@pytest.fixture(scope="module")
def youbot():
    robot = fw.load_robot("youbot_dual_mobile")
    return robot, fw.RobotShape(robot)


def test_bounding_spheres_hold_their_geometry(pr2, youbot, rng):
    """Surface points of every PR2 mesh (its vertices included, at the mesh's scale) and of the youBot's spheres
    and box lie within their geometry's bounding sphere."""
    import coal

    kinds = set()
    for _, shape in (pr2, youbot):
        for g in shape.geometry.geometryObjects:
            center, radius = bounding_sphere(g.geometry)
            if isinstance(g.geometry, coal.BVHModelBase):
                points = mesh_surface_points(g.meshPath, 500, rng, np.asarray(g.meshScale))
            else:
                points = surface_points(g.geometry, 500, rng)
            kinds.add(type(g.geometry).__name__)
            assert np.linalg.norm(points - center, axis=1).max() <= radius * (1 + 1e-12) + 1e-12, g.name
    assert {"Sphere", "Box"} <= kinds and any("BVH" in k for k in kinds)
    for solid in (coal.Cylinder(0.1, 0.6), coal.Capsule(0.05, 0.4)):
        center, radius = bounding_sphere(solid)
        assert np.linalg.norm(surface_points(solid, 2000, rng) - center, axis=1).max() <= radius + 1e-12
    assert bounding_sphere(coal.Halfspace(np.array([0.0, 0.0, 1.0]), 0.0))[1] == np.inf


def test_holding_capsules_hold_their_mesh_and_prune_pairs_spheres_keep(pr2, rng):
    """Surface points of every PR2 mesh (at its scale, in its body's frame) lie within the capsule the broad phase
    holds it in; and at configurations with the arms apart, the capsules leave out pairs the bounding spheres keep
    (PR2's forearms and upper arms are long: a sphere holds a lot of air around them)."""
    import coal

    robot, shape = pr2
    spheres = shape._bounding_spheres(shape.geometry)
    rows = spheres.solids.reshape(-1, 16)
    meshes = 0
    for k, g in enumerate(shape.geometry.geometryObjects):
        if not isinstance(g.geometry, coal.BVHModelBase):
            continue
        meshes += 1
        local = mesh_surface_points(g.meshPath, 400, rng, np.asarray(g.meshScale))
        points = local @ g.placement.rotation.T + g.placement.translation
        R, c, (radius, half) = rows[k, 1:10].reshape(3, 3), rows[k, 10:13], rows[k, 13:15]
        q = (points - c) @ R  # in the capsule's frame
        along = q[:, 2] - np.clip(q[:, 2], -half, half)
        assert np.sqrt(q[:, 0] ** 2 + q[:, 1] ** 2 + along ** 2).max() <= radius + 1e-9, g.name
    assert meshes > 20
    only_spheres = bounding_spheres(robot, shape.geometry)
    X = list(robot.random_configurations(rng, 20)) + [robot.middle]
    kept = sum(spheres.near_pairs(x, 0.0).size for x in X)
    assert kept < 0.7 * sum(only_spheres.near_pairs(x, 0.0).size for x in X)


def _close_pairs(robot, geometry, x, margin) -> set[int]:
    """The pairs coal's distance computation (every pair) finds closer than ``margin``."""
    data = geometry.createData()
    pin.computeDistances(robot.model, robot.model.createData(), geometry, data, robot.to_pinocchio(x))
    return {k for k, r in enumerate(data.distanceResults) if r.min_distance < margin}


def _coal_clear(robot, geometry):
    """``clear(x)``: whether coal's collision test on every pair (no broad phase, no distances) finds no contact."""
    data, geometry_data = robot.model.createData(), geometry.createData()
    return lambda x: not pin.computeCollisions(robot.model, data, geometry, geometry_data, robot.to_pinocchio(x), True)


def _on_contact_boundaries(robot, clear, rng, count):
    """Configurations where a pair just touches: bisection between a clear configuration and random ones in
    contact (``clear(x)``: whether coal finds no contact)."""
    x0 = robot.middle if clear(robot.middle) else next(x for x in robot.random_configurations(rng, 200) if clear(x))
    out = []
    for x1 in robot.random_configurations(rng, 10 * count):
        if clear(x1):
            continue
        a, b = 0.0, 1.0
        for _ in range(30):
            t = (a + b) / 2
            a, b = (t, b) if clear(x0 + t * (x1 - x0)) else (a, t)
        out.append(x0 + a * (x1 - x0))
        if len(out) == count:
            break
    return out


@pytest.mark.parametrize("which", ["pr2", "youbot"])
def test_near_pairs_hold_every_pair_closer_than_the_margin(which, pr2, youbot, rng):
    robot, shape = pr2 if which == "pr2" else youbot
    spheres = shape._bounding_spheres(shape.geometry)  # links' boxes and cylinders measured as solids
    configurations = _on_contact_boundaries(robot, _coal_clear(robot, shape.geometry), rng, 8)
    configurations += list(robot.random_configurations(rng, 8))
    checked = 0
    for x in configurations:
        for margin in (0.0, 0.02):
            close = _close_pairs(robot, shape.geometry, x, margin)
            near = set(spheres.near_pairs(x, margin).tolist())
            assert close <= near, sorted(close - near)
            checked += len(close)
    assert checked > 0  # contacts were there to miss


def test_near_pairs_against_every_obstacle_kind(youbot, rng, tmp_path):
    """The scene's model (the robot's moving geometries against a box, sphere, capsule, half-space and mesh): every
    pair coal finds within the margin is near, and the fast check reports what the distances on every pair do."""
    import trimesh

    path = tmp_path / "block.stl"
    trimesh.creation.box(extents=[0.3, 0.2, 0.2]).export(path)
    robot, shape = youbot
    scene = fw.Scene((fw.Box([0.6, 0.0, 0.3], [0.4, 0.6, 0.05], name="table"), fw.Sphere([0.3, 0.4, 0.5], 0.1),
                      fw.Capsule([0.0, -0.5, 0.4], 0.05, 0.4), fw.Plane([0, 0, 0.02], [0, 0, 1]),
                      fw.Mesh(path, center=[0.2, 0.0, 0.7])))
    geometry, _, obstacles, _ = shape._model(scene, False)
    assert len(obstacles) == 4  # the mesh is no solid: its bounding sphere
    spheres = shape._bounding_spheres(geometry, obstacles)
    assert spheres.radii.max() > 100  # the plane: a large box under the robot, whose sphere is near every body
    only_spheres = bounding_spheres(robot, geometry)
    fewer = 0
    clear = lambda x: not shape.check(x, scene=scene, self_pairs=False).colliding  # noqa: E731
    configurations = _on_contact_boundaries(robot, clear, rng, 8) + list(robot.random_configurations(rng, 4))
    for x in configurations:
        for margin in (0.0, 0.03):
            close = _close_pairs(robot, geometry, x, margin)
            near = set(spheres.near_pairs(x, margin).tolist())
            assert close <= near, sorted(close - near)
            fewer += len(near) < only_spheres.near_pairs(x, margin).size
            fast = shape.check(x, margin, scene=scene, self_pairs=False, distances=False)
            full = shape.check(x, margin, scene=scene, self_pairs=False)
            assert {(c.a, c.b) for c in fast.contacts} == {(c.a, c.b) for c in full.contacts}
    assert fewer == 2 * len(configurations)  # the solids prune what the spheres keep (the plane's pairs, at least)


def test_the_broad_phase_leaves_most_pairs_out(pr2, youbot):
    """At the middle of the box (arms apart) few pairs are near: a broad phase keeping every pair (the trivial
    one) would be as correct and save nothing."""
    for robot, shape in (pr2, youbot):
        near = bounding_spheres(robot, shape.geometry).near_pairs(robot.middle, 0.0)
        assert near.size < 0.25 * len(shape.pairs), (robot.name, near.size, len(shape.pairs))


def test_own_pairs_and_a_scene_checked_in_one_pass_as_each_alone(youbot, rng):
    """One pass over the robot's own pairs and a scene's, each at its own margin (one broad phase, the geometries
    placed once): the same contacts as each kind of pair checked alone with distances on every pair (coal, no broad
    phase); and a problem's exact check of a SelfCollision and an Obstacles term is that union."""
    robot, shape = youbot
    scene = fw.Scene((fw.Box([0.5, 0.0, 0.3], [0.3, 0.6, 0.05], name="table"), fw.Sphere([0.2, 0.3, 0.5], 0.1)))
    X = robot.random_configurations(rng, 40)
    kinds = set()
    for x in X:
        for margin, scene_margin in ((0.0, 0.0), (0.01, 0.04), (0.04, 0.0)):
            one = shape.check(x, margin, scene, distances=False, scene_margin=scene_margin)
            alone = {(c.a, c.b) for c in shape.check(x, margin).contacts} \
                | {(c.a, c.b) for c in shape.check(x, scene_margin, scene, self_pairs=False).contacts}
            assert {(c.a, c.b) for c in one.contacts} == alone
            kinds |= {b.startswith("obstacle:") for _, b in alone}
        problem = fw.Problem(robot, fw.SelfCollision(shape, margin=0.01) + fw.Obstacles(shape, scene, margin=0.04))
        for margins in (False, True):
            terms = {(c.a, c.b) for _, t in problem.objective for c in t.collisions(robot, x, margin=margins).contacts}
            assert {(c.a, c.b) for c in problem.collisions(x, margins=margins).contacts} == terms
    assert kinds == {False, True}  # random configurations: contacts of both kinds
