"""Property tests over random URDF trees (``trees.py``): every tree loads; population FK equals Pinocchio's FK of
the same URDF; frame Jacobians equal central finite differences; the hybrid reaches poses that are reachable by
construction (the FK of a random configuration). The references are in ``references.py``."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import framework as fw
from tests.fuzz.references import fk_difference, jacobian_difference, reach_reachable_pose
from tests.fuzz.trees import trees

FUZZ = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)


@FUZZ
@given(trees())
def test_population_fk_equals_pinocchio(tree):
    robot = fw.robot_from_urdf(tree.urdf)
    assert robot.n == len(tree.movable) and sorted(robot.joint_names) == sorted(tree.movable)
    assert {m.name: (m.leader, m.multiplier, m.offset) for m in robot.mimics} == tree.mimic
    model = pin.buildModelFromXML(tree.urdf)
    frames = tuple(f"l{i}" for i in range(len(model.frames)) if model.existFrame(f"l{i}"))
    X = robot.random_configurations(np.random.default_rng(tree.seed), 5)
    assert fk_difference(tree, robot, X, frames) <= 1e-12


@FUZZ
@given(trees())
def test_frame_jacobians_equal_finite_differences(tree):
    robot = fw.robot_from_urdf(tree.urdf)
    X = robot.random_configurations(np.random.default_rng(tree.seed), 1)
    assert jacobian_difference(robot, X, tree.leaves) <= 1e-7


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)
@given(st.integers(0, 2**31 - 1))
def test_hybrid_reaches_reachable_poses(seed):
    """Strict: the reported success is true AND Pinocchio's FK of the answer is within 1e-9 m / 1e-9 rad (the
    rate over 400 trees is in docs/reliability.md; this samples 40)."""
    success, position, angle = reach_reachable_pose(seed)
    assert success and position <= 1e-9 and angle <= 1e-9, (seed, position, angle)


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)
@given(trees())
def test_chained_tracking_is_one_solve_per_waypoint(tree):
    """On random trees (mimic, continuous, prismatic joints): a path of a leaf frame (FK of a straight joint-space
    segment), tracked with compiled stretches, gives bit for bit what one solve per waypoint gives."""
    from framework.costs.problem import Problem
    from framework.tracking import FIRST_GLOBAL_ITERATIONS, TrackingTask, track
    from framework.tracking.trajectory import Trajectory

    robot = fw.robot_from_urdf(tree.urdf)
    rng = np.random.default_rng(tree.seed)
    a, b = robot.random_configurations(rng, 2)
    frame = tree.leaves[0]
    path = Trajectory(np.array([robot.frame_placement(a + (b - a) * s, frame).translation
                                for s in np.linspace(0.0, 0.3, 8)]), name="segment")
    spec = TrackingTask(frame=frame, motion=0.01)
    result = track(robot, path, spec, solver="hybrid", seed=tree.seed, max_iterations=300, tolerance=1e-4,
                   progress=False)
    generator, previous = np.random.default_rng(tree.seed), robot.middle.copy()
    problem = Problem(robot, spec.objective(robot, 0, path.positions[0], None, previous))
    for k in range(path.K):
        spec.update(problem.objective, path.positions[k], None, previous)
        first = {"global_iterations": FIRST_GLOBAL_ITERATIONS} if k == 0 else None
        one = fw.solve(problem, "hybrid", seed=generator, max_iterations=300, tolerance=1e-4, initial=previous[None],
                       options=first)
        assert np.array_equal(result.configurations[k], one.configuration), k
        assert result.success[k] == one.success
        previous = one.configuration
