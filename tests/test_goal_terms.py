"""Goal terms beyond positions and orientations — Direction (an axis along a direction) and JointTarget (a
posture) — against Pinocchio, finite differences and the solver's strict success."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import framework as fw
from framework.costs import Program
from framework.engine import residuals
from framework.errors import TaskError

from tests.test_costs import _curvature


@pytest.fixture(scope="module")
def robot() -> fw.Robot:
    return fw.load_robot("youbot_dual_mobile")  # planar base (x, y, θ) + two 5R arms


def _angle(robot, x, frame, axis, direction) -> float:
    """The angle between the frame's axis and the direction, by Pinocchio FK."""
    w = robot.frame_placement(x, frame).rotation @ (axis / np.linalg.norm(axis))
    d = np.asarray(direction) / np.linalg.norm(direction)
    return float(np.arctan2(np.linalg.norm(np.cross(w, d)), w @ d))  # accurate at every angle (arccos is not)


def test_direction_residual_norm_is_the_angle_and_its_jacobian_matches_differences(robot, rng):
    h = 1e-7
    for axis in ([0, 0, 1], [1, 1, 0]):
        term = fw.Direction("arm2_ee", [0.3, -1.0, 0.2], axis=axis)
        program = Program(robot, 1.0 * term)
        for x in robot.random_configurations(rng, 4):
            r, J = residuals(program, x)
            assert np.linalg.norm(r) == pytest.approx(_angle(robot, x, "arm2_ee", np.array(axis, float),
                                                            term.direction), abs=1e-12)
            fd = np.column_stack([(residuals(program, x + e)[0] - residuals(program, x - e)[0]) / (2 * h)
                                  for e in np.eye(robot.n) * h])
            np.testing.assert_allclose(J, fd, atol=2e-6)
            assert fw.Problem(robot, term).values(x[None])[0, 0] == pytest.approx(np.linalg.norm(r), abs=1e-14)


@pytest.mark.parametrize("angle", [0.0, 1e-9, 1e-4, 2e-3, 1.0, 3.0, np.pi - 1e-7])
def test_direction_at_small_and_large_angles(robot, angle):
    """Series branch (< 1e-3 rad), general branch and near the opposite direction: ‖r‖ = θ."""
    x = robot.middle
    w = robot.frame_placement(x, "arm1_ee").rotation[:, 2]
    side = np.cross(w, [0.3, 0.5, 0.8])
    side /= np.linalg.norm(side)
    direction = np.cos(angle) * w + np.sin(angle) * side
    r, _ = residuals(Program(robot, 1.0 * fw.Direction("arm1_ee", direction)), x)
    assert np.linalg.norm(r) == pytest.approx(angle, abs=1e-9)


def test_direction_curvature_on_target(robot, rng):
    """Σ μ·∇²r (second-order kinematics) against differences of Jᵀμ where the axis is on its direction."""
    h = 1e-6
    for x in robot.random_configurations(rng, 3):
        w = robot.frame_placement(x, "arm2_ee").rotation @ np.array([1.0, 0.0, 0.0])
        program = Program(robot, 1.0 * fw.Direction("arm2_ee", w, axis=[1, 0, 0]))
        mu = rng.standard_normal(2)
        fd = np.column_stack([(residuals(program, x + e)[1].T @ mu - residuals(program, x - e)[1].T @ mu) / (2 * h)
                              for e in np.eye(robot.n) * h])
        np.testing.assert_allclose(_curvature(program, x, mu), fd, atol=1e-6)


def test_direction_leaves_the_rotation_about_the_axis_free():
    """Pointing the tool only: from the solution of the full orientation (which also points it), the motion
    minimized on the direction alone is lower — the rotation about the axis is free — and the axis is on its
    direction to 1e-9 rad by Pinocchio."""
    arm = fw.load_robot("puma560")
    rng = np.random.default_rng(2)
    gains = []
    for q in arm.random_configurations(rng, 5):
        M = arm.frame_placement(q, "ee")
        motion = 0.1 * fw.Motion("all", arm.middle)
        oriented = fw.solve(fw.Problem(arm, fw.Orientation("ee", M.rotation) + motion), tolerance=1e-9)
        assert oriented.success
        pointed = fw.solve(fw.Problem(arm, fw.Direction("ee", M.rotation[:, 2]) + motion), tolerance=1e-9,
                           initial=oriented.configuration)
        assert pointed.success
        assert _angle(arm, pointed.configuration, "ee", np.array([0.0, 0, 1]), M.rotation[:, 2]) <= 1e-9
        gains.append(oriented.terms["motion[all]"] - pointed.terms["motion[all]"])
    assert min(gains) >= -1e-12 and max(gains) > 1e-3


def test_joint_target_is_a_task_reached_first(robot):
    arm1 = robot.group("arm1")
    posture = robot.middle.copy()
    posture[arm1] = [0.3, 1.0, -0.8, 1.2, 0.5]
    problem = fw.Problem(robot, fw.JointTarget("arm1", posture) + fw.Position("arm2_ee", [0.4, 0.3, 0.3])
                         + 0.1 * fw.Motion("all", robot.middle))
    result = fw.solve(problem, tolerance=1e-10)
    assert result.success
    np.testing.assert_allclose(result.configuration[arm1], posture[arm1], atol=1e-10)
    assert set(result.errors) == {"joints[arm1]", "position[arm2_ee]"}
    assert problem.program.task_angular == (True, False)  # revolute joints: the angular tolerance
    base = fw.JointTarget("base", [0.1, 0.2, 0.3])
    assert fw.Problem(robot, base).program.task_angular == (False,)  # x, y in metres: the linear one
    assert [robot.coordinate_is_linear(i) for i in robot.group("base")] == [True, True, False]


@pytest.mark.parametrize("direction", [[0, 0, 0], [np.nan, 0, 1], [1, 0], "up"])
def test_bad_directions(direction):
    with pytest.raises(TaskError, match="direction"):
        fw.Direction("ee", direction)


def test_direction_matches_pinocchio_orientation_error_on_a_real_arm(erd, rng):
    """UR5 from example-robot-data: the residual norm equals the angle from Pinocchio's log3 of the minimal
    rotation between the tool axis and the direction."""
    arm = fw.load_robot(erd / "ur_description" / "urdf" / "ur5_robot.urdf")
    d = np.array([0.2, 0.9, -0.4]) / np.linalg.norm([0.2, 0.9, -0.4])
    program = Program(arm, 1.0 * fw.Direction("tool0", d, axis=[0, 0, 1]))
    for x in arm.random_configurations(rng, 5):
        w = arm.frame_placement(x, "tool0").rotation[:, 2]
        axis = np.cross(d, w)
        R = pin.exp3(np.arctan2(np.linalg.norm(axis), d @ w) * axis / np.linalg.norm(axis))  # d → w
        np.testing.assert_allclose(R @ d, w, atol=1e-12)
        assert np.linalg.norm(residuals(program, x)[0]) == pytest.approx(np.linalg.norm(pin.log3(R)), abs=1e-12)


def test_new_terms_in_a_task_file(tmp_path):
    from framework.io.taskfile import load_task

    path = tmp_path / "point.toml"
    path.write_text("""
[task]
name = "point the tool"
robot = "puma560"
[[terms]]
type = "direction"
frame = "ee"
direction = "d"
axis = [0, 0, 1]
[[terms]]
type = "joint_target"
group = "joint6"
target = [0.5]
[[terms]]
type = "distance"
frame = "ee"
to_point = [0, 0, 0]
at_least = 0.3
[[terms]]
type = "motion"
group = "arm"
weight = 0.1
[[cases]]
name = "down"
d = [0, 0, -1]
""")
    case = load_task(path).cases[0]
    result = fw.solve(case.problem, tolerance=1e-9)
    assert result.success and set(result.errors) == {"direction[ee]", "joints[joint6]", "distance[ee, point]"}
    assert _fk_distance(case.problem.robot, result.configuration, "ee", [0, 0, 0]) >= 0.3 - 1e-9
    robot = case.problem.robot
    assert _angle(robot, result.configuration, "ee", np.array([0, 0, 1.0]), [0, 0, -1]) <= 1e-9
    assert result.configuration[robot.group("joint6")][0] == pytest.approx(0.5, abs=1e-9)


def _fk_distance(robot, x, a, b) -> float:
    pa = robot.frame_placement(x, a).translation
    pb = robot.frame_placement(x, b).translation if isinstance(b, str) else np.asarray(b)
    return float(np.linalg.norm(pa - pb))


@pytest.mark.parametrize("make", [
    lambda: fw.Distance("arm1_ee", "arm2_ee", exactly=0.3),
    lambda: fw.Distance("arm1_ee", [0.3, 0.1, 0.4], at_most=0.2),
    lambda: fw.Distance("arm2_ee", [0.3, 0.1, 0.4], at_least=2.0),
], ids=["frames exactly", "point at most", "point at least"])
def test_distance_residual_jacobian_and_curvature(robot, rng, make):
    term = make()
    lo, hi = term.bounds
    program = Program(robot, 1.0 * term)
    h = 1e-6
    for x in robot.random_configurations(rng, 4):
        r, J = residuals(program, x)
        d = _fk_distance(robot, x, term.frame, term.to_frame or term.point)
        assert r[0] == pytest.approx(d - hi if d > hi else (d - lo if d < lo else 0.0), abs=1e-12)
        fd = np.column_stack([(residuals(program, x + e)[0] - residuals(program, x - e)[0]) / (2 * h)
                              for e in np.eye(robot.n) * h])
        np.testing.assert_allclose(J, fd, atol=2e-6)
        mu = rng.standard_normal(1)  # the distance's second order is exact wherever the hinge is active
        fdH = np.column_stack([(residuals(program, x + e)[1].T @ mu - residuals(program, x - e)[1].T @ mu) / (2 * h)
                               for e in np.eye(robot.n) * h])
        np.testing.assert_allclose(_curvature(program, x, mu), fdH, atol=2e-6)


def test_distance_inside_its_band_costs_nothing_and_two_hands_keep_apart(robot):
    x = robot.middle
    d = _fk_distance(robot, x, "arm1_ee", "arm2_ee")
    program = Program(robot, 1.0 * fw.Distance("arm1_ee", "arm2_ee", at_least=d - 0.01, at_most=d + 0.01))
    r, J = residuals(program, x)
    assert r[0] == 0.0 and not J.any()
    problem = fw.Problem(robot, fw.Position("arm1_ee", [0.5, -0.2, 0.45]) + fw.Distance("arm1_ee", "arm2_ee",
                         exactly=0.3) + 0.1 * fw.Motion("all", robot.middle))
    result = fw.solve(problem, tolerance=1e-10)
    assert result.success
    assert _fk_distance(robot, result.configuration, "arm1_ee", "arm2_ee") == pytest.approx(0.3, abs=1e-10)


def test_bad_distances():
    with pytest.raises(TaskError, match="needs at_least"):
        fw.Distance("ee", [0, 0, 0])
    with pytest.raises(TaskError, match="0 <= at_least <= at_most"):
        fw.Distance("ee", [0, 0, 0], at_least=0.5, at_most=0.2)
    with pytest.raises(TaskError, match="exactly= alone"):
        fw.Distance("ee", [0, 0, 0], exactly=0.5, at_most=0.6)
    with pytest.raises(TaskError, match="no point to move"):
        fw.Distance("a", "b", exactly=0.1).set_target([0, 0, 0])


def test_cone_residual_jacobian_and_solve():
    arm = fw.load_robot("puma560")
    rng = np.random.default_rng(4)
    term = fw.Cone("ee", [0, 0, -1], 0.3)
    program = Program(arm, 1.0 * term)
    h = 1e-7
    inside = 0
    for x in arm.random_configurations(rng, 12):
        r, J = residuals(program, x)
        theta = _angle(arm, x, "ee", np.array([0, 0, 1.0]), [0, 0, -1])
        assert r[0] == pytest.approx(max(theta - 0.3, 0.0), abs=1e-12)
        inside += theta <= 0.3
        fd = np.column_stack([(residuals(program, x + e)[0] - residuals(program, x - e)[0]) / (2 * h)
                              for e in np.eye(arm.n) * h])
        np.testing.assert_allclose(J, fd, atol=2e-6)
    result = fw.solve(fw.Problem(arm, term + fw.Position("ee", [0.4, 0.1, 0.2]) + 0.1 * fw.Motion("all", arm.middle)),
                      tolerance=1e-9)
    assert result.success
    assert _angle(arm, result.configuration, "ee", np.array([0, 0, 1.0]), [0, 0, -1]) <= 0.3 + 1e-9
    with pytest.raises(TaskError, match="max_angle"):
        fw.Cone("ee", [0, 0, 1], -0.1)


def test_relative_pose_against_pinocchio_differences_and_a_two_hand_grasp(robot, rng):
    """Two hands holding one object: the pose of hand 2 in hand 1 against Pinocchio's relative placement; its
    Jacobian against differences; both value views; solved with hand 1 on a target, checked by Pinocchio."""
    offset = pin.SE3(pin.utils.rpyToMatrix(0.3, -0.2, 1.0), np.array([0.1, 0.25, -0.05]))
    term = fw.RelativePose("arm1_ee", "arm2_ee", offset)
    program = Program(robot, 1.0 * term)
    h = 1e-7
    for x in robot.random_configurations(rng, 4):
        r, J = residuals(program, x)
        T = robot.frame_placement(x, "arm1_ee").inverse() * robot.frame_placement(x, "arm2_ee")
        np.testing.assert_allclose(r, np.r_[T.translation - offset.translation,
                                            pin.log3(offset.rotation.T @ T.rotation)], atol=1e-12)
        fd = np.column_stack([(residuals(program, x + e)[0] - residuals(program, x - e)[0]) / (2 * h)
                              for e in np.eye(robot.n) * h])
        np.testing.assert_allclose(J, fd, atol=2e-6)
        value = fw.Problem(robot, term).values(x[None])[0, 0]
        assert value == pytest.approx(np.linalg.norm(r[:3]) + np.sin(min(np.linalg.norm(r[3:]), np.pi) / 2), abs=1e-13)
    problem = fw.Problem(robot, fw.Position("arm1_ee", [0.5, -0.2, 0.4]) + term + 0.1 * fw.Motion("all", robot.middle))
    result = fw.solve(problem, tolerance=1e-9)
    assert result.success
    T = robot.frame_placement(result.configuration, "arm1_ee").inverse() * robot.frame_placement(
        result.configuration, "arm2_ee")
    assert np.linalg.norm(T.translation - offset.translation) <= 1e-9
    assert np.linalg.norm(pin.log3(offset.rotation.T @ T.rotation)) <= 1e-9


def test_relative_pose_in_a_task_file(tmp_path):
    from framework.io.taskfile import load_task

    path = tmp_path / "hold.toml"
    path.write_text("""
[task]
name = "hold a box"
robot = "youbot_dual_mobile"
[[terms]]
type = "position"
frame = "arm1_ee"
target = [0.5, -0.2, 0.4]
[[terms]]
type = "relative_pose"
frame_a = "arm1_ee"
frame_b = "arm2_ee"
offset = [0, 0.3, 0]
offset_rotation = "Rz(pi)"
[[terms]]
type = "motion"
group = "all"
weight = 0.1
""")
    problem = load_task(path).cases[0].problem
    result = fw.solve(problem, tolerance=1e-9)
    robot = problem.robot
    T = robot.frame_placement(result.configuration, "arm1_ee").inverse() * robot.frame_placement(
        result.configuration, "arm2_ee")
    assert result.success and np.allclose(T.translation, [0, 0.3, 0], atol=1e-9)
    np.testing.assert_allclose(T.rotation, pin.utils.rotate("z", np.pi), atol=1e-9)


def test_look_at_residual_jacobian_both_views_and_solve(robot, rng):
    """LookAt: the residual's norm is 2 sin(θ/2) of the angle θ between the frame axis and the line of sight,
    by Pinocchio FK; its Jacobian against central differences; population value = residual view; solved with
    the hand on a target, checked by Pinocchio."""
    point = np.array([1.2, -0.4, 0.9])
    h = 1e-7
    for axis in ([0, 0, 1], [1, -1, 0.5]):
        term = fw.LookAt("arm1_ee", point, axis=axis)
        program = Program(robot, 1.0 * term)
        for x in robot.random_configurations(rng, 4):
            r, J = residuals(program, x)
            M = robot.frame_placement(x, "arm1_ee")
            theta = _angle(robot, x, "arm1_ee", np.array(axis, float), point - M.translation)
            assert np.linalg.norm(r) == pytest.approx(2 * np.sin(theta / 2), abs=1e-12)
            fd = np.column_stack([(residuals(program, x + e)[0] - residuals(program, x - e)[0]) / (2 * h)
                                  for e in np.eye(robot.n) * h])
            np.testing.assert_allclose(J, fd, atol=2e-6)
            assert fw.Problem(robot, term).values(x[None])[0, 0] == pytest.approx(np.linalg.norm(r), abs=1e-14)
    term = fw.LookAt("arm2_ee", point, axis=[1, 0, 0])
    result = fw.solve(fw.Problem(robot, term + fw.Position("arm2_ee", [0.4, -0.3, 0.45])
                                 + 0.1 * fw.Motion("all", robot.middle)), tolerance=1e-9)
    M = robot.frame_placement(result.configuration, "arm2_ee")
    assert result.success and _angle(robot, result.configuration, "arm2_ee", np.array([1.0, 0, 0]),
                                     point - M.translation) <= 1e-8
    with pytest.raises(TaskError, match="look-at point"):
        fw.LookAt("arm1_ee", [np.nan, 0, 0])
