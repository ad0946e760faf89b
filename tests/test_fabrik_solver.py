"""M-FABRIK behind ``solve()``: ``solve(problem, "mfabrik")`` gives what the M-FABRIK / FABRIK planners give when
called directly (same configurations), the common result type with strict success by Pinocchio's FK, an Obstacles
term's scene keeps the base out of the shadows, ``tracking.track`` drives it along a path, and what it cannot take
is named."""

from __future__ import annotations

import numpy as np
import pytest

import framework as fw
from framework.errors import SolverError
from framework.solvers.fabrik import Fabrik, MFabrik, PlanarChain
from framework.tracking.trajectory import Trajectory


def _targets(robot: fw.Robot, frame: str, count: int, seed: int) -> np.ndarray:
    X = robot.random_configurations(np.random.default_rng(seed), count)
    return robot.frame_poses(X, frame).positions[:, 0]


@pytest.mark.parametrize(("name", "planner"), [("youbot_mobile", "m-fabrik"), ("youbot_arm", "fabrik")])
def test_solve_equals_the_planner_called_directly(name, planner):
    """The same start (the box middle), seed and tolerance: the same configuration as MFabrik / Fabrik's own
    solve, success iff Pinocchio's FK puts the frame within the tolerance of the target."""
    robot = fw.load_robot(name)
    frame = robot.end_effectors[0]
    direct = (MFabrik.from_robot(robot, frame, seed=5) if planner == "m-fabrik"
              else Fabrik(PlanarChain.from_robot(robot, frame), seed=5))
    successes = 0
    for target in _targets(robot, frame, 15, 1):
        result = fw.solve(fw.Problem(robot, fw.Position(frame, target)), "mfabrik", seed=5, tolerance=1e-6)
        expected = direct.solve(target, robot.middle, tolerance=1e-6)
        np.testing.assert_array_equal(result.configuration, expected.configuration)
        error = np.linalg.norm(robot.frame_placement(result.configuration, frame).translation - target)
        assert result.success == (error <= 1e-6)
        assert result.settings["method"] == planner
        successes += result.success
    assert successes >= 12  # targets are FK of random configurations: reachable (M-FABRIK's rate there: ~100 %)


@pytest.mark.parametrize(("margin", "least"), [(0.25, 0), (0.45, 3)])
def test_an_obstacles_term_keeps_the_base_out_of_the_shadows(margin, least):
    """A box on the floor near the targets: every base position M-FABRIK reaches from is at least the base margin
    away from the box's shadow (a rectangle: closed-form distance). M-FABRIK keeps the base's reference point
    clear; the exact check, which decides success, finds the platform (0.58 x 0.38 m) in the box when that margin
    is under the platform's half diagonal (0.25 m: no success), and no contact with 0.45 m."""
    robot = fw.load_robot("youbot_mobile")
    frame = robot.end_effectors[0]
    shape = fw.RobotShape(robot)
    box = fw.Box([0.8, 0.0, 0.3], [0.3, 0.6, 0.6])
    reached = 0
    for target in ([1.4, 0.0, 0.3], [1.3, 0.3, 0.25], [1.5, -0.2, 0.35]):
        problem = fw.Problem(robot, fw.Position(frame, target) + fw.Obstacles(shape, [box]))
        result = fw.solve(problem, "mfabrik", seed=0, options={"base_margin": margin})
        x, y = result.configuration[robot.group("base")[:2]]
        dx, dy = max(abs(x - 0.8) - 0.15, 0.0), max(abs(y) - 0.3, 0.0)
        assert np.hypot(dx, dy) >= margin - 1e-6
        assert result.errors["position[arm_ee]"] <= 1e-6  # M-FABRIK reached the target either way
        reached += result.success
    assert reached == least


def test_tracking_drives_mfabrik_along_a_path():
    """``tracking.track(..., solver="mfabrik")``: every waypoint reached by Pinocchio's FK, each solve warm-started
    from the previous solution (the base moves about as far as the waypoints are apart, ~5 cm, at the median)."""
    robot = fw.load_robot("youbot_mobile")
    frame = robot.end_effectors[0]
    s = np.linspace(0, 1, 25)
    path = Trajectory(np.column_stack([0.5 + 1.0 * s, 0.3 * np.sin(3 * s), 0.3 + 0.1 * s]), name="line")
    from framework.tracking import track

    result = track(robot, path, solver="mfabrik", tolerance=1e-5, seed=0)
    Q = result.configurations
    reached = robot.frame_poses(Q, frame).positions[:, 0]
    assert np.linalg.norm(reached - path.positions, axis=1).max() <= 1e-5
    base = Q[:, robot.group("base")[:2]]
    steps = np.linalg.norm(np.diff(base, axis=0), axis=1)
    assert np.median(steps) <= 0.08 and steps.max() <= 0.5


def test_what_mfabrik_cannot_take_is_named():
    robot = fw.load_robot("youbot_mobile")
    frame = robot.end_effectors[0]
    pose = fw.Pose(frame, fw.Robot.frame_placement(robot, robot.middle, frame))
    with pytest.raises(SolverError, match="one Position task term"):
        fw.solve(fw.Problem(robot, pose), "mfabrik")
    with pytest.raises(SolverError, match="time_budget"):
        fw.solve(fw.Problem(robot, fw.Position(frame, [1, 0, 0.3])), "mfabrik", time_budget=1.0)
    with pytest.raises(SolverError, match="orientation"):
        fw.solve(fw.Problem(robot, fw.Position(frame, [1, 0, 0.3])), "mfabrik", options={"orientation": "up"})
    arm = fw.load_robot("youbot_arm")
    with pytest.raises(SolverError, match="mobile base only"):
        fw.solve(fw.Problem(arm, fw.Position(arm.end_effectors[0], [0.3, 0, 0.3])
                            + fw.Obstacles(fw.RobotShape(arm), [fw.Box([1, 1, 0], [0.1, 0.1, 0.1])])), "mfabrik")
