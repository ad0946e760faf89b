"""Population forward kinematics against Pinocchio's own forwardKinematics + updateFramePlacements."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import framework as fw
from framework.model.joints import JointKind


def pinocchio_poses(robot: fw.Robot, X: np.ndarray, frames: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Reference: one Pinocchio call per configuration, ``(pop, k, 3)`` and ``(pop, k, 3, 3)``."""
    data = robot.model.createData()
    ids = [robot.frame_id(f) for f in frames]
    P = np.empty((len(X), len(ids), 3))
    R = np.empty((len(X), len(ids), 3, 3))
    for b, q in enumerate(robot.to_pinocchio(X)):
        pin.forwardKinematics(robot.model, data, q)
        pin.updateFramePlacements(robot.model, data)
        for k, fid in enumerate(ids):
            P[b, k] = data.oMf[fid].translation
            R[b, k] = data.oMf[fid].rotation
    return P, R


def assert_matches_pinocchio(robot: fw.Robot, rng: np.random.Generator, frames=None, count=1000) -> None:
    frames = list(frames or robot.end_effectors)
    X = robot.random_configurations(rng, count)
    poses = robot.frame_poses(X, frames)
    P, R = pinocchio_poses(robot, X, frames)
    assert poses.positions.shape == (count, len(frames), 3)
    np.testing.assert_allclose(poses.positions, P, rtol=0, atol=1e-12)
    np.testing.assert_allclose(poses.rotations, R, rtol=0, atol=1e-12)


def test_every_shipped_robot_matches_pinocchio(rng):
    for name in fw.robot_index():
        robot = fw.load_robot(name)
        assert_matches_pinocchio(robot, rng)


def test_ur5_from_example_robot_data(erd, rng):
    robot = fw.load_robot(erd / "ur_description" / "urdf" / "ur5_robot.urdf")
    assert robot.n == 6
    assert_matches_pinocchio(robot, rng, frames=["tool0", "wrist_1_link", "shoulder_link"])


def test_baxter_dual_arm_from_example_robot_data(erd, rng):
    robot = fw.load_robot(erd / "baxter_description" / "urdf" / "baxter.urdf")
    frames = ["left_gripper", "right_gripper"] if robot.model.existFrame("left_gripper") else robot.end_effectors
    assert_matches_pinocchio(robot, rng, frames=frames)


def test_tiago_dual_mobile_with_continuous_joints(erd, rng):
    """Every joint of a dual-arm mobile robot: continuous wheels (nq = 2 in Pinocchio), prismatic torso, arms."""
    robot = fw.load_robot(erd / "tiago_description" / "robots" / "tiago_dual.urdf")
    kinds = {j.kind for j in robot.joints}
    assert JointKind.CONTINUOUS in kinds and JointKind.PRISMATIC in kinds
    assert robot.model.nq > robot.n  # cos/sin storage of continuous joints
    assert_matches_pinocchio(robot, rng, count=200)


PLANAR_URDF = """<robot name="planar_test">
  <link name="world"/><link name="body"/><link name="slider"/><link name="tip"/>
  <joint name="base" type="planar"><parent link="world"/><child link="body"/>
    <origin xyz="0.1 -0.2 0.3" rpy="0.1 0.2 0.3"/><axis xyz="0 0 1"/></joint>
  <joint name="slide" type="prismatic"><parent link="body"/><child link="slider"/>
    <origin xyz="0.3 0 0.1" rpy="0 0.4 0"/><axis xyz="0.6 0 0.8"/><limit lower="-0.2" upper="0.5" effort="1" velocity="1"/></joint>
  <joint name="twist" type="revolute"><parent link="slider"/><child link="tip"/>
    <origin xyz="0 0.2 0" rpy="0.5 0 0"/><axis xyz="0 0.6 0.8"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
</robot>"""


def test_planar_joint_and_unaligned_axes(rng):
    robot = fw.robot_from_urdf(PLANAR_URDF)
    assert [j.kind for j in robot.joints] == [JointKind.PLANAR, JointKind.PRISMATIC, JointKind.REVOLUTE]
    assert robot.n == 5 and robot.model.nq == 6
    assert robot.coordinate_names[:3] == ("base.x", "base.y", "base.theta")
    assert_matches_pinocchio(robot, rng, frames=["tip", "slider", "body"])


def test_large_populations_agree_with_batches(rng):
    robot = fw.load_robot("youbot_dual_mobile")
    X = robot.random_configurations(rng, 2000)
    whole = robot.frame_poses(X)
    parts = [robot.frame_poses(X[i : i + 100]) for i in range(0, 2000, 100)]
    np.testing.assert_array_equal(whole.positions, np.concatenate([p.positions for p in parts]))


def test_single_configuration_and_named_access():
    robot = fw.load_robot("youbot_dual_mobile")
    x = robot.middle
    poses = robot.frame_poses(x)
    assert poses.positions.shape == (1, 2, 3)
    ref = robot.frame_placement(x, "arm2_ee")
    np.testing.assert_allclose(poses.position("arm2_ee")[0], ref.translation, atol=1e-12)
    np.testing.assert_allclose(poses.rotation("arm2_ee")[0], ref.rotation, atol=1e-12)
    with pytest.raises(fw.UnknownFrameError):
        poses.position("arm3_ee")


@pytest.mark.parametrize("name", ["youbot_dual_mobile", "stanford_arm", "baxter_dual"])
def test_population_jacobians_equal_pinocchio(name, rng):
    robot = fw.load_robot(name)
    X = robot.random_configurations(rng, 50)
    poses, J = robot.frame_jacobians(X)
    data = robot.model.createData()
    for b, x in enumerate(X):
        q = robot.to_pinocchio(x)
        for k, frame in enumerate(robot.end_effectors):
            ref = pin.computeFrameJacobian(robot.model, data, q, robot.frame_id(frame), pin.LOCAL_WORLD_ALIGNED)
            np.testing.assert_allclose(J[b, k], ref @ robot.coordinate_jacobian(x), atol=1e-12)
    np.testing.assert_allclose(poses.positions, robot.frame_poses(X).positions, atol=0)


def test_population_jacobians_with_planar_and_unaligned_joints(rng):
    robot = fw.robot_from_urdf(PLANAR_URDF)
    X = robot.random_configurations(rng, 30)
    _, J = robot.frame_jacobians(X, ["tip", "slider"])
    data = robot.model.createData()
    for b, x in enumerate(X):
        for k, frame in enumerate(["tip", "slider"]):
            ref = pin.computeFrameJacobian(robot.model, data, robot.to_pinocchio(x), robot.frame_id(frame),
                                           pin.LOCAL_WORLD_ALIGNED)
            np.testing.assert_allclose(J[b, k], ref @ robot.coordinate_jacobian(x), atol=1e-12)
