"""Sphere covers: every surface point of every collision geometry — drawn independently of the fit, four times
as many — lies within the union of its spheres; few spheres per geometry; world centres follow the joints."""

from __future__ import annotations

import numpy as np
import pytest

import framework as fw
from framework.geometry.collision import RobotShape
from framework.geometry.spheres import fit_spheres, sphere_cover, surface_points

PRIMITIVES = """<robot name="shapes">
  <link name="a"><collision><origin xyz="0.1 0 0" rpy="0.3 0 0"/><geometry><box size="0.3 0.1 0.05"/></geometry>
    </collision></link>
  <link name="b"><collision><origin xyz="0 0.2 0"/><geometry><cylinder radius="0.04" length="0.3"/></geometry>
    </collision><collision><geometry><sphere radius="0.07"/></geometry></collision></link>
  <link name="c"><collision><geometry><capsule radius="0.03" length="0.2"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="b"/><child link="c"/><origin xyz="0 0.4 0"/><axis xyz="1 0 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>"""


def _uncovered(shape: RobotShape, cover, seed: int) -> float:
    """The largest distance [m] by which an independently drawn surface point lies outside every sphere of its
    geometry (0 when all are inside)."""
    rng = np.random.default_rng(seed)
    worst = 0.0
    for g in shape.geometry.geometryObjects:
        local = surface_points(g.geometry, 6000, rng, g.meshPath, g.meshScale)
        points = local @ g.placement.rotation.T + g.placement.translation
        mine = np.array([name == g.name for name in cover.geometries])
        gaps = np.linalg.norm(points[:, None] - cover.centers[mine][None], axis=-1) - cover.radii[mine][None]
        worst = max(worst, float(gaps.min(axis=1).max()))
    return worst


def test_primitives_are_covered():
    shape = RobotShape(fw.robot_from_urdf(PRIMITIVES))
    cover = sphere_cover(shape, per_geometry=4, max_radius=None, samples=1500)
    assert len(cover.radii) <= 4 * shape.geometry.ngeoms
    assert _uncovered(shape, cover, seed=99) <= 1e-12  # a sphere covers itself: its surface points at r, to rounding


@pytest.mark.parametrize("path", ["panda_description/urdf/panda.urdf", "pr2_description/urdf/pr2.urdf"])
def test_meshes_of_real_robots_are_covered(erd, path):
    shape = RobotShape(fw.load_robot(erd / path))
    cover = sphere_cover(shape, per_geometry=4, max_radius=None, samples=1500)
    assert _uncovered(shape, cover, seed=7) <= 0.0


def test_a_single_sphere_fits_a_sphere_and_world_centres_follow_the_joints():
    rng = np.random.default_rng(0)
    points = 0.2 * surface_points(__import__("coal").Sphere(1.0), 3000, rng) + [1.0, 2.0, 3.0]
    centers, radii = fit_spheres(points, 1, rng)
    np.testing.assert_allclose(centers[0], [1.0, 2.0, 3.0], atol=0.01)
    assert 0.2 <= radii[0] <= 0.25  # the radius plus at most the sampling pad
    robot = fw.robot_from_urdf(PRIMITIVES)
    shape = RobotShape(robot)
    cover = sphere_cover(shape)
    x = np.array([0.4, -0.7])
    world = cover.world_centers(shape, x)
    for k, (joint, center) in enumerate(zip(cover.joints, cover.centers)):
        frame = robot.model.names[int(joint)]
        M = robot.frame_placement(x, frame) if joint > 0 else None
        expected = center if M is None else M.rotation @ center + M.translation
        np.testing.assert_allclose(world[k], expected, atol=1e-12)


def test_a_radius_bound_doubles_the_spheres_until_it_holds():
    """max_radius: spheres are added (doubling, up to 64) until none is larger; the cover still holds the
    surface. A 4-sphere cover of these primitives has spheres over 6 cm (shown), the bounded one none."""
    shape = RobotShape(fw.robot_from_urdf(PRIMITIVES))
    loose = sphere_cover(shape, per_geometry=4, max_radius=None)
    tight = sphere_cover(shape, per_geometry=4, max_radius=0.06)
    assert loose.radii.max() > 0.06
    counts = {g: tight.geometries.count(g) for g in set(tight.geometries) if g != "b_1"}  # b_1: a sphere, itself
    for g, count in counts.items():
        radii = tight.radii[[k for k, name in enumerate(tight.geometries) if name == g]]
        assert radii.max() <= 0.06 or count >= 64
    assert _uncovered(shape, tight, seed=5) <= 1e-12
