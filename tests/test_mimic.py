"""Mimic joints (URDF ``<mimic>``) follow their leader and are never search coordinates: PR2's gripper fingers
against Pinocchio's FK of the full model with the coupling applied here from the URDF text."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest

import framework as fw
from framework.errors import UnknownJointError


def _couplings(urdf: str) -> dict[str, tuple[str, float, float]]:
    out = {}
    for joint in ET.fromstring(urdf).findall("joint"):
        mimic = joint.find("mimic")
        if mimic is not None:
            out[joint.get("name")] = (mimic.get("joint"), float(mimic.get("multiplier", 1)),
                                      float(mimic.get("offset", 0)))
    return out


@pytest.fixture(scope="module")
def pr2(erd):
    return fw.load_robot(erd / "pr2_description" / "urdf" / "pr2.urdf")


def test_pr2_gripper_fingers_follow_their_leader(pr2, rng):
    couplings = _couplings(pr2.urdf)
    assert len(couplings) == 10 and {m.name for m in pr2.mimics} == set(couplings)
    assert not set(couplings) & set(pr2.joint_names)  # never search coordinates
    full = pin.buildModelFromXML(pr2.urdf)
    data = full.createData()
    frames = ["l_gripper_r_finger_tip_link", "l_gripper_l_finger_tip_link", "r_gripper_r_parallel_link",
              "l_gripper_tool_frame"]
    X = pr2.random_configurations(rng, 20)
    poses, J = pr2.frame_jacobians(X, frames)
    for b, x in enumerate(X):
        values = {j.name: x[j.index] for j in pr2.joints}
        values.update({n: m * values[lead] + o for n, (lead, m, o) in couplings.items()})
        q = pin.neutral(full)
        for name, value in values.items():
            jm = full.joints[full.getJointId(name)]
            q[jm.idx_q:jm.idx_q + jm.nq] = [np.cos(value), np.sin(value)] if jm.nq == 2 else [value]
        pin.framesForwardKinematics(full, data, q)
        for k, frame in enumerate(frames):
            oMf = data.oMf[full.getFrameId(frame)]
            np.testing.assert_allclose(poses.positions[b, k], oMf.translation, atol=1e-12)
            np.testing.assert_allclose(poses.rotations[b, k], oMf.rotation, atol=1e-12)
    # the leader's Jacobian column carries its mimic joints' motion: central differences
    leader = pr2.joint("l_gripper_l_finger_joint").index
    h, x = 1e-6, X[0]
    step = np.zeros(pr2.n)
    step[leader] = h
    P = pr2.frame_poses(np.array([x + step, x - step]), frames)
    np.testing.assert_allclose(J[0, :, :3, leader], (P.positions[0] - P.positions[1]) / (2 * h), atol=1e-8)


def test_a_frame_moved_by_mimic_joints_is_reached(pr2, rng):
    """A finger tip's position, reachable by construction, through the leader of the fingers."""
    x_true = pr2.random_configurations(rng, 1)[0]
    target = pr2.frame_placement(x_true, "l_gripper_r_finger_tip_link")
    result = fw.solve(fw.Problem(pr2, fw.Pose("l_gripper_r_finger_tip_link", target)), "hybrid", tolerance=1e-9)
    reached = pr2.frame_placement(result.configuration, "l_gripper_r_finger_tip_link")
    assert result.success and np.linalg.norm(reached.translation - target.translation) <= 1e-9


def test_mimic_joints_are_not_solved_or_locked_by_name(pr2, erd):
    path = erd / "pr2_description" / "urdf" / "pr2.urdf"
    with pytest.raises(UnknownJointError, match="mimics 'l_gripper_l_finger_joint'"):
        fw.load_robot(path, joints=["l_gripper_r_finger_joint"])
    # locking the leader locks its mimic joints at the coupled value
    locked = fw.load_robot(path, locked={"l_gripper_l_finger_joint": 0.3})
    assert "l_gripper_r_finger_joint" not in {m.name for m in locked.mimics}
    tip = locked.frame_placement(locked.middle, "l_gripper_r_finger_tip_link")
    free = pr2.middle.copy()
    free[pr2.joint("l_gripper_l_finger_joint").index] = 0.3
    common = [pr2.joint(j.name).index for j in locked.joints]
    free[common] = locked.middle
    np.testing.assert_allclose(tip.translation, pr2.frame_placement(free, "l_gripper_r_finger_tip_link").translation,
                               atol=1e-12)


BROKEN_MIMIC_URDF = """<robot name="broken_mimic">
  <link name="base"/><link name="upper"/><link name="lower"/><link name="tip"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="lower"/>
    <origin xyz="0.3 0 0"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" velocity="1"/>
    <mimic joint="ghost" multiplier="2"/></joint>
  <joint name="wrist" type="revolute"><parent link="lower"/><child link="tip"/>
    <origin xyz="0.2 0 0"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" velocity="1"/>
    <mimic joint="elbow"/></joint>
</robot>"""


def test_a_mimic_of_a_joint_the_model_lacks_is_named_and_loads_locked(rng):
    """A file whose <mimic> names a joint it does not have (example-robot-data's alex_psyonic_hands.urdf does) is
    refused with every such follower named (here 'wrist' through 'elbow'); locking them loads it as it is, the
    locked values where the file's kinematics put them (Pinocchio's FK of the full model)."""
    with pytest.raises(fw.RobotFileError, match=r"2 joints mimic .*'elbow' mimics 'ghost'.*'wrist' mimics 'ghost'"
                                                r".*locked="):
        fw.robot_from_urdf(BROKEN_MIMIC_URDF)
    with pytest.raises(fw.RobotFileError, match=r"1 joint mimic.*'wrist' mimics 'ghost'; lock it"):
        fw.robot_from_urdf(BROKEN_MIMIC_URDF, locked={"elbow": 0.4})
    robot = fw.robot_from_urdf(BROKEN_MIMIC_URDF, locked={"elbow": 0.4, "wrist": -0.7})
    assert robot.joint_names == ("shoulder",) and not robot.mimics
    full = pin.buildModelFromXML(BROKEN_MIMIC_URDF)
    data = full.createData()
    for shoulder in rng.uniform(-2, 2, 5):
        q = np.array([shoulder, 0.4, -0.7])
        pin.framesForwardKinematics(full, data, q)
        np.testing.assert_allclose(robot.frame_placement(np.array([shoulder]), "tip").homogeneous,
                                   data.oMf[full.getFrameId("tip")].homogeneous, atol=1e-12)
