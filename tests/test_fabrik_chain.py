"""Chains FABRIK supports: structure detected from the model, plane geometry against Pinocchio, angle recovery."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import framework as fw
from framework.solvers.fabrik import PlanarChain, UnsupportedChainError

#: A planar 3R arm (axes along y, motion in the xz-plane) with an offset shoulder and a tool frame: 0.4, 0.3, 0.2 m.
PLANAR_3R = """<?xml version="1.0"?>
<robot name="planar3r">
  <link name="base"/><link name="l1"/><link name="l2"/><link name="l3"/><link name="tool"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0.1 0.05 0.2" rpy="0 0 0"/><axis xyz="0 1 0"/><limit lower="-2.5" upper="2.5" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.4 0.02 0" rpy="0 0 0"/><axis xyz="0 -1 0"/><limit lower="-2.5" upper="2.5" effort="1" velocity="1"/></joint>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>
    <origin xyz="0.3 0 0" rpy="0 0 0"/><axis xyz="0 1 0"/><limit lower="-2.5" upper="2.5" effort="1" velocity="1"/></joint>
  <joint name="tool_joint" type="fixed"><parent link="l3"/><child link="tool"/>
    <origin xyz="0.2 -0.03 0" rpy="0 0 0"/></joint>
</robot>
"""


def world_points(chain: PlanarChain, x: np.ndarray) -> np.ndarray:
    """The chain's points in the world, by our planar kinematics: ``(K+1, 3)``."""
    robot = chain.robot
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, robot.to_pinocchio(x))
    phi = chain.yaw_turn(x[chain.yaw]) if chain.yaw is not None else 0.0
    local = chain.to_root(chain.points(x[list(chain.planar)]), phi)
    return np.array([data.oMi[chain.root].act(p) for p in local])


def pinocchio_points(chain: PlanarChain, x: np.ndarray) -> np.ndarray:
    """The same points from Pinocchio: planar joint axes met with the end-effector's plane, then the end-effector."""
    robot = chain.robot
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, robot.to_pinocchio(x))
    tip = data.oMf[robot.frame_id(chain.frame)].translation
    points = []
    for index in chain.planar:
        joint = next(j for j in robot.joints if j.index == index)
        m = data.oMi[joint.pin_id]
        axis = m.rotation @ joint.axis
        # the foot of the tip on the axis
        points.append(m.translation + axis * (axis @ (tip - m.translation)))
    return np.array([*points, tip])


@pytest.mark.parametrize(
    ("name", "yaw", "planar", "passive"),
    [
        ("youbot_arm", 0, (1, 2, 3), (4,)),
        ("puma560", 0, (1, 2), (3, 4, 5)),
        ("planar3r", None, (0, 1, 2), ()),
    ],
)
def test_structure_is_read_from_the_model(name, yaw, planar, passive):
    robot = fw.robot_from_urdf(PLANAR_3R) if name == "planar3r" else fw.load_robot(name)
    chain = PlanarChain.from_robot(robot)
    assert (chain.yaw, chain.planar, chain.passive) == (yaw, planar, passive)


def test_youbot_geometry_comes_from_the_dh_table():
    chain = PlanarChain.from_robot(fw.load_robot("youbot_arm"))
    np.testing.assert_allclose(chain.lengths, [0.155, 0.135, 0.2175], atol=1e-12)
    np.testing.assert_allclose(chain.shoulder, [0.033, 0.147], atol=1e-12)
    assert abs(chain.lateral) < 1e-12
    puma = PlanarChain.from_robot(fw.load_robot("puma560"))
    assert abs(abs(puma.lateral) - 0.15) < 1e-12  # the Puma's shoulder offset d3
    np.testing.assert_allclose(puma.lengths, [0.4318, np.hypot(0.0203, 0.4318)], atol=1e-12)


@pytest.mark.parametrize("name", ["youbot_arm", "puma560", "planar3r", "youbot_mobile"])
def test_plane_kinematics_match_pinocchio(name, rng):
    robot = fw.robot_from_urdf(PLANAR_3R) if name == "planar3r" else fw.load_robot(name)
    chain = PlanarChain.from_robot(robot, joints="arm" if name == "youbot_mobile" else None)
    for x in robot.random_configurations(rng, 50):
        np.testing.assert_allclose(world_points(chain, x), pinocchio_points(chain, x), atol=1e-12)


@pytest.mark.parametrize("name", ["youbot_arm", "puma560", "planar3r"])
def test_angles_recovered_from_pinocchio_joint_positions(name, rng):
    """Joint positions from Pinocchio, written in the plane, give back the joint angles (clipped to limits)."""
    robot = fw.robot_from_urdf(PLANAR_3R) if name == "planar3r" else fw.load_robot(name)
    chain = PlanarChain.from_robot(robot)
    for x in robot.random_configurations(rng, 50):
        phi = chain.yaw_turn(x[chain.yaw]) if chain.yaw is not None else 0.0
        e_x, _ = chain.axes(phi)
        rel = pinocchio_points(chain, x) - chain.origin  # root = world for these arms
        points = np.stack([rel @ e_x, rel @ chain.e_y], axis=1)
        np.testing.assert_allclose(chain.angles(points), x[list(chain.planar)], atol=1e-10)


def test_yaw_headings_put_the_target_in_the_plane(rng):
    robot = fw.load_robot("puma560")  # the plane is 0.15 m off the yaw axis
    chain = PlanarChain.from_robot(robot)
    for target in rng.uniform(-0.8, 0.8, (200, 3)):
        w = target - chain.origin
        r = np.linalg.norm(w - chain.e_y * (w @ chain.e_y))  # distance from the yaw axis
        for phi in chain.yaw_headings(target):  # off the plane only if too near the axis, then by the least
            assert abs(chain.plane_target(target, phi)[2]) == pytest.approx(
                max(abs(chain.lateral) - r, 0), abs=1e-12
            )


def test_angles_are_clipped_to_limits():
    chain = PlanarChain.from_robot(fw.load_robot("youbot_arm"))
    folded = chain.points(np.zeros(3))
    folded[2:] = folded[1] + (folded[1] - folded[2:])  # fold the elbow back: 180 deg, beyond joint 3's limits
    q = chain.angles(folded)
    assert np.all(q >= chain.lower - 1e-12) and np.all(q <= chain.upper + 1e-12)
    assert np.isclose(q[1], chain.lower[1]) or np.isclose(q[1], chain.upper[1])


@pytest.mark.parametrize(
    ("name", "kwargs", "message"),
    [
        ("baxter_arm", {}, "not parallel"),
        ("stanford_arm", {}, "prismatic"),
        ("youbot_mobile", {}, "prismatic"),
        ("youbot_mobile", {"joints": ["arm_joint1", "arm_joint3", "arm_joint4"]}, "inside the chain"),
    ],
)
def test_unsupported_chains_are_refused_by_name(name, kwargs, message):
    with pytest.raises(UnsupportedChainError, match=message):
        PlanarChain.from_robot(fw.load_robot(name), **kwargs)
