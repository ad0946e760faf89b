"""Floating bases: a free-flyer as six solved coordinates (x, y, z, yaw, pitch, roll), checked against
Pinocchio's own free-flyer model of the same URDF; locked at a full pose; URDF ``floating`` joints."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import framework as fw
from framework.errors import LimitsError


@pytest.fixture(scope="module")
def talos_path(erd):
    return erd / "talos_data" / "robots" / "talos_reduced.urdf"


def _free_flyer_q(full: pin.Model, robot: fw.Robot, x: np.ndarray) -> np.ndarray:
    """Pinocchio's free-flyer configuration (x, y, z, quaternion, joints) of our coordinates, built here:
    the rotation is Rz(yaw) Ry(pitch) Rx(roll)."""
    q = pin.neutral(full)
    q[:3] = x[:3]
    q[3:7] = pin.Quaternion(pin.rpy.rpyToMatrix(x[5], x[4], x[3])).coeffs()
    for joint in robot.joints[6:]:
        q[full.joints[full.getJointId(joint.name)].idx_q] = x[joint.index]
    return q


def test_talos_whole_body_reach_with_both_feet_held(talos_path):
    """Both soles held at their poses (first priority, with the hand), the left hand 0.5 m forward, motion
    minimized second; every pose checked with Pinocchio's free-flyer model of the original URDF."""
    robot = fw.load_robot(talos_path, floating_base=True)
    assert robot.n == 6 + 32 and robot.joint_names[:6] == ("root_joint_x", "root_joint_y", "root_joint_z",
                                                           "root_joint_yaw", "root_joint_pitch", "root_joint_roll")
    x0 = robot.middle.copy()
    x0[:6] = [0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
    feet = {f: robot.frame_placement(x0, f) for f in ("left_sole_link", "right_sole_link")}
    hand = "gripper_left_base_link"
    target = robot.frame_placement(x0, hand).translation + [0.5, 0.0, 0.0]
    objective = [(1.0, fw.Pose(f, M)) for f, M in feet.items()] + [(1.0, fw.Position(hand, target)),
                                                                    (0.1, fw.Motion("all", x0))]
    result = fw.solve(fw.Problem(robot, objective), "hybrid", tolerance=1e-9, initial=x0)
    assert result.success
    full = pin.buildModelFromUrdf(str(talos_path), pin.JointModelFreeFlyer())
    data = full.createData()
    pin.framesForwardKinematics(full, data, _free_flyer_q(full, robot, result.configuration))
    for frame, M in feet.items():
        oMf = data.oMf[full.getFrameId(frame)]
        assert np.linalg.norm(oMf.translation - M.translation) <= 1e-9
        assert np.linalg.norm(pin.log3(M.rotation.T @ oMf.rotation)) <= 1e-9
    assert np.linalg.norm(data.oMf[full.getFrameId(hand)].translation - target) <= 1e-9
    assert np.abs(result.configuration[:3] - x0[:3]).max() > 0.01  # the base moved to reach


def test_population_fk_of_a_floating_base_equals_pinocchio_free_flyer(talos_path, rng):
    robot = fw.load_robot(talos_path, floating_base=True)
    full = pin.buildModelFromUrdf(str(talos_path), pin.JointModelFreeFlyer())
    data = full.createData()
    frames = ("left_sole_link", "gripper_right_base_link", "torso_2_link")
    X = robot.random_configurations(rng, 10)
    poses = robot.frame_poses(X, frames)
    for b, x in enumerate(X):
        pin.framesForwardKinematics(full, data, _free_flyer_q(full, robot, x))
        for k, frame in enumerate(frames):
            np.testing.assert_allclose(poses.positions[b, k], data.oMf[full.getFrameId(frame)].translation,
                                       atol=1e-12)
            np.testing.assert_allclose(poses.rotations[b, k], data.oMf[full.getFrameId(frame)].rotation, atol=1e-12)


@pytest.mark.parametrize("form", ["7-vector", "SE3", "matrix"])
def test_a_floating_base_locked_at_a_pose(talos_path, form):
    pose = pin.SE3(pin.rpy.rpyToMatrix(0.1, -0.2, 0.7), np.array([0.3, -0.1, 0.9]))
    value = {"7-vector": pin.SE3ToXYZQUAT(pose), "SE3": pose, "matrix": pose.homogeneous}[form]
    robot = fw.load_robot(talos_path, floating_base=True, locked={"root_joint": value},
                          quaternion="xyzw" if form == "7-vector" else None)  # Pinocchio's configuration order
    assert robot.n == 32 and "root_joint_x" not in robot.joint_names
    full = pin.buildModelFromUrdf(str(talos_path), pin.JointModelFreeFlyer())
    data = full.createData()
    q = pin.neutral(full)
    q[:7] = pin.SE3ToXYZQUAT(pose)
    x = robot.middle
    for joint in robot.joints:
        q[full.joints[full.getJointId(joint.name)].idx_q] = x[joint.index]
    pin.framesForwardKinematics(full, data, q)
    M = robot.frame_placement(x, "left_sole_link")
    np.testing.assert_allclose(M.homogeneous, data.oMf[full.getFrameId("left_sole_link")].homogeneous, atol=1e-12)


def test_bad_floating_locks_name_the_joint(talos_path):
    with pytest.raises(LimitsError, match="root_joint"):
        fw.load_robot(talos_path, floating_base=True, locked={"root_joint": [0, 0, 1, 0, 0, 0, 2.0]})
    with pytest.raises(LimitsError, match="root_joint"):
        fw.load_robot(talos_path, floating_base=True, locked={"root_joint": 0.5})


DRONE = """<robot name="drone_arm"><link name="world"/><link name="body"/><link name="arm"/>
  <joint name="fly" type="floating"><parent link="world"/><child link="body"/></joint>
  <joint name="shoulder" type="revolute"><parent link="body"/><child link="arm"/><origin xyz="0 0 -0.1"/>
    <axis xyz="0 1 0"/><limit lower="-1.5" upper="1.5" effort="1" velocity="1"/></joint>
</robot>"""


def test_a_urdf_floating_joint_is_six_coordinates_and_reaches_a_pose():
    robot = fw.robot_from_urdf(DRONE)
    assert robot.joint_names == ("fly_x", "fly_y", "fly_z", "fly_yaw", "fly_pitch", "fly_roll", "shoulder")
    target = pin.SE3(pin.rpy.rpyToMatrix(0.2, 0.3, 1.0), np.array([0.4, -0.3, 0.5]))
    result = fw.solve(fw.Problem(robot, fw.Pose("arm", target)), "hybrid", tolerance=1e-9)
    reached = robot.frame_placement(result.configuration, "arm")
    assert result.success and np.linalg.norm(pin.log6(target.inverse() * reached)) <= 1e-9


def test_center_of_mass_equals_pinocchio_and_its_derivatives_match_differences(talos_path, rng):
    """The centre of mass of the free-flying Talos against ``pinocchio.centerOfMass`` of its free-flyer model;
    Jacobian and second order against central differences; the population value equals the residual view."""
    from framework.costs import Program
    from framework.engine import residuals
    from tests.test_costs import _curvature

    robot = fw.load_robot(talos_path, floating_base=True)
    full = pin.buildModelFromUrdf(str(talos_path), pin.JointModelFreeFlyer())
    data = full.createData()
    term = fw.CenterOfMass([0.1, -0.2, 0.8])
    program = Program(robot, 1.0 * term)
    h = 1e-6
    for x in robot.random_configurations(rng, 3):
        r, J = residuals(program, x)
        com = pin.centerOfMass(full, data, _free_flyer_q(full, robot, x))
        np.testing.assert_allclose(r, com - term.target, atol=1e-12)
        fd = np.column_stack([(residuals(program, x + e)[0] - residuals(program, x - e)[0]) / (2 * h)
                              for e in np.eye(robot.n) * h])
        np.testing.assert_allclose(J, fd, atol=1e-7)
        mu = rng.normal(size=3)
        second = np.column_stack([(residuals(program, x + e)[1].T @ mu - residuals(program, x - e)[1].T @ mu)
                                  / (2 * h) for e in np.eye(robot.n) * h])
        np.testing.assert_allclose(_curvature(program, x, mu), second, atol=1e-6)
        assert fw.Problem(robot, term).values(x[None])[0, 0] == pytest.approx(np.linalg.norm(r), abs=1e-14)
    xy = Program(robot, 1.0 * fw.CenterOfMass([0.1, -0.2, 0.8], axes="yx"))
    np.testing.assert_allclose(residuals(xy, x)[0], r[:2], atol=1e-15)


def test_talos_balanced_reach(talos_path):
    """Standing (every joint at 0, the pelvis 1 m up), both soles held, the centre of mass over the middle of the
    feet, the left hand 0.5 m forward, motion second: checked with Pinocchio's free-flyer model (poses and
    ``centerOfMass``)."""
    robot = fw.load_robot(talos_path, floating_base=True)
    x0 = np.clip(np.zeros(robot.n), robot.lower, robot.upper)
    x0[:6] = [0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
    feet = {f: robot.frame_placement(x0, f) for f in ("left_sole_link", "right_sole_link")}
    middle = 0.5 * (feet["left_sole_link"].translation + feet["right_sole_link"].translation)
    hand = "gripper_left_base_link"
    target = robot.frame_placement(x0, hand).translation + [0.5, 0.0, 0.0]
    objective = [(1.0, fw.Pose(f, M)) for f, M in feet.items()] + [
        (1.0, fw.Position(hand, target)), (1.0, fw.CenterOfMass(middle, axes="xy")), (0.1, fw.Motion("all", x0))]
    result = fw.solve(fw.Problem(robot, objective), "hybrid", tolerance=1e-9, initial=x0)
    assert result.success
    full = pin.buildModelFromUrdf(str(talos_path), pin.JointModelFreeFlyer())
    data = full.createData()
    q = _free_flyer_q(full, robot, result.configuration)
    pin.framesForwardKinematics(full, data, q)
    for frame, M in feet.items():
        assert np.linalg.norm(pin.log6(M.inverse() * data.oMf[full.getFrameId(frame)])) <= 1e-9
    assert np.linalg.norm(data.oMf[full.getFrameId(hand)].translation - target) <= 1e-9
    assert np.linalg.norm(pin.centerOfMass(full, data, q)[:2] - middle[:2]) <= 1e-9
