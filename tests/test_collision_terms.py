"""SelfCollision and Obstacles: hinges on sphere distances, against a closed form and coal's exact check."""

from __future__ import annotations

import numpy as np
import pytest

import framework as fw
from framework.errors import TaskError
from tests.test_collision import L, R


def test_motion_towards_a_collision_stops_at_the_margin(sphere_arm):
    """Motion towards (0, 0) puts the two spheres on each other; kept apart, the optimum splits the angle
    θ* = 2 asin((2R + margin) / 2L) equally between the joints (closed form), found by DE ranked by Deb's rules."""
    robot, shape, exact = sphere_arm
    margin = 0.01
    free = fw.solve(fw.Problem(robot, 1.0 * fw.Motion("all", [0.0, 0.0])), initial=np.array([1.0, 0.5]))
    assert shape.check(free.configuration).colliding
    problem = fw.Problem(robot, fw.SelfCollision(shape, margin=margin, cover=exact) + fw.Motion("all", [0.0, 0.0]))
    result = fw.solve(problem, "de", seed=0, max_iterations=300, tolerance=1e-6, options={"ranking": "feasibility"})
    half = np.arcsin((2 * R + margin) / (2 * L))
    assert result.success
    np.testing.assert_allclose(np.abs(result.configuration), [half, half], atol=1e-3)
    assert not shape.check(result.configuration, margin=margin - 1e-5).colliding


def test_the_local_engine_leaves_a_collision(sphere_arm):
    robot, shape, exact = sphere_arm
    start = np.array([0.05, 0.02])
    assert shape.check(start).colliding
    result = fw.solve(fw.Problem(robot, fw.SelfCollision(shape, cover=exact) + 0.1 * fw.Motion("all", start)),
                      initial=start, tolerance=1e-9)
    assert result.success and not shape.check(result.configuration).colliding


def test_panda_reaches_targets_without_self_collision(erd):
    """Position targets from random starts with the automatic sphere cover: every answer collision-free by coal
    on the exact meshes (the spheres are larger than the links, so this holds with a margin)."""
    robot = fw.load_robot(erd / "panda_description" / "urdf" / "panda.urdf",
                          joints=[f"panda_joint{i}" for i in range(1, 8)], end_effectors=["panda_hand"])
    shape = fw.RobotShape(robot, srdf=erd / "panda_description" / "srdf" / "panda.srdf")
    problem = fw.Problem(robot, fw.Position("panda_hand", [0.3, 0.0, 0.2]) + fw.SelfCollision(shape))
    rng = np.random.default_rng(0)
    for k in range(8):
        result = fw.solve(problem, seed=k, tolerance=1e-6, initial=robot.random_configurations(rng, 1)[0])
        assert result.success and not shape.check(result.configuration).colliding


def test_sphere_obstacles_are_kept_clear(sphere_arm):
    robot, shape, exact = sphere_arm
    obstacle = np.array([0.0, L, 0.0])  # on the forearm sphere's circle, at θ1 + θ2 = π/2
    problem = fw.Problem(robot, fw.Obstacles(shape, [fw.Sphere(obstacle, 0.05)], margin=0.01, cover=exact)
                         + fw.Motion("all", [np.pi / 4, np.pi / 4]))
    result = fw.solve(problem, "de", seed=0, max_iterations=300, tolerance=1e-6, options={"ranking": "feasibility"})
    world = exact.world_centers(shape, result.configuration)[1]
    assert result.success and np.linalg.norm(world - obstacle) >= R + 0.05 + 0.01 - 1e-6
    with pytest.raises(TaskError, match="no obstacle"):
        fw.Obstacles(shape, [])
    with pytest.raises(TaskError, match="margin"):
        fw.SelfCollision(shape, margin=-1.0, cover=exact)
