"""Robot model API: loading, joint coordinates, groups, locking, composing, and errors on bad input."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import framework as fw
from tests.test_kinematics import PLANAR_URDF, assert_matches_pinocchio


def test_mobile_dual_youbot_model():
    robot = fw.load_robot("youbot_dual_mobile")
    assert robot.n == 13
    assert robot.end_effectors == ("arm1_ee", "arm2_ee")
    assert robot.group("base").tolist() == [0, 1, 2]
    assert len(robot.group("arm1")) == 5 and len(robot.group("arm2")) == 5
    assert set(robot.group("arm1")).isdisjoint(robot.group("arm2"))
    np.testing.assert_allclose(robot.lower[:3], [-1.5, -1.5, -np.pi])
    np.testing.assert_allclose(np.degrees(robot.lower[3:8]), [-169, -65, -150, -102.5, -167.5])
    np.testing.assert_allclose(np.degrees(robot.upper[8:13]), [169, 90, 146, 102.5, 167.5])


def test_conversions_round_trip_through_pinocchio(rng):
    robot = fw.robot_from_urdf(PLANAR_URDF)
    X = robot.random_configurations(rng, 50)
    Q = robot.to_pinocchio(X)
    assert Q.shape == (50, robot.model.nq)
    np.testing.assert_allclose(robot.from_pinocchio(Q), X, atol=1e-15)
    for q in Q:  # every converted q is a valid Pinocchio configuration (unit cos/sin pairs)
        assert pin.isNormalized(robot.model, q)


def test_coordinate_jacobian_matches_finite_differences(rng):
    """Pinocchio's frame Jacobian mapped to joint coordinates equals finite differences of our FK."""
    robot = fw.robot_from_urdf(PLANAR_URDF)
    data = robot.model.createData()
    fid = robot.frame_id("tip")
    for x in robot.random_configurations(rng, 5):
        q = robot.to_pinocchio(x)
        J = pin.computeFrameJacobian(robot.model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
        J = J @ robot.coordinate_jacobian(x)
        h = 1e-6
        E = np.eye(robot.n) * h
        fd = (robot.frame_poses(x + E, "tip").positions[:, 0] - robot.frame_poses(x - E, "tip").positions[:, 0]) / (2 * h)
        np.testing.assert_allclose(J[:3], fd.T, atol=1e-8)


def test_locked_joints_give_the_full_model_kinematics(erd, rng):
    """Solving for the arms of a dual-arm mobile robot, the rest locked, equals the full model at those values."""
    full = fw.load_robot(erd / "tiago_description" / "robots" / "tiago_dual.urdf")
    arms = [f"arm_{side}_{i}_joint" for side in ("left", "right") for i in range(1, 8)]
    robot = fw.load_robot(
        erd / "tiago_description" / "robots" / "tiago_dual.urdf",
        joints=["torso_lift_joint", *arms],
        locked={"head_1_joint": 0.3},
        end_effectors=["arm_left_7_link", "arm_right_7_link"],
    )
    assert robot.n == 15
    assert robot.locked["head_1_joint"] == 0.3
    assert set(robot.groups) == {"torso", "left_arm", "right_arm"}  # not "base": the lift is vertical
    assert robot.joint_names[robot.group("torso")[0]] == "torso_lift_joint"
    X = robot.random_configurations(rng, 20)
    Xf = np.zeros((20, full.n))
    for name, value in robot.locked.items():
        Xf[:, full.joint(name).index] = value
    for j in robot.joints:
        Xf[:, full.joint(j.name).index] = X[:, j.index]
    frames = ["arm_left_7_link", "arm_right_7_link", "xtion_rgb_optical_frame"]
    np.testing.assert_allclose(robot.frame_poses(X, frames).positions, full.frame_poses(Xf, frames).positions, atol=1e-12)


def test_mount_equals_composed_transforms(rng):
    """A mobile dual arm built in code: EE pose = planar base · mount · the arm's own FK."""
    robot = fw.mount(
        fw.planar_base_urdf(),
        [
            fw.Mount("youbot_arm", parent="platform", xyz=(0.15, 0, 0.14), prefix="arm1_"),
            fw.Mount("youbot_arm", parent="platform", xyz=(-0.15, 0, 0.14), rpy=(0, 0, np.pi), prefix="arm2_"),
        ],
        name="my_mobile_dual",
    )
    arm = fw.load_robot("youbot_arm")
    assert robot.n == 3 + 2 * arm.n
    assert robot.end_effectors == tuple("arm%d_%s" % (i, arm.end_effectors[0]) for i in (1, 2))
    X = robot.random_configurations(rng, 100)
    poses = robot.frame_poses(X)
    for b, x in enumerate(X):
        base = pin.SE3(pin.utils.rotate("z", x[2]), np.array([x[0], x[1], 0.0]))
        for i, (rpy_z, dx) in enumerate([(0.0, 0.15), (np.pi, -0.15)]):
            mount = pin.SE3(pin.utils.rotate("z", rpy_z), np.array([dx, 0.0, 0.14]))
            ee = base * mount * arm.frame_placement(x[robot.group(f"arm{i + 1}")], arm.end_effectors[0])
            np.testing.assert_allclose(poses.positions[b, i], ee.translation, atol=1e-12)
            np.testing.assert_allclose(poses.rotations[b, i], ee.rotation, atol=1e-12)
    assert_matches_pinocchio(robot, rng)


def test_bounds_override_and_default_bounds_of_unbounded_joints():
    robot = fw.robot_from_urdf(PLANAR_URDF, unbounded_translation=3.0)
    np.testing.assert_allclose(robot.lower[:3], [-3.0, -3.0, -np.pi])
    narrowed = robot.with_bounds({"base.x": (-0.5, 0.5), "twist": (-1.0, 1.0)})
    assert narrowed.lower[0] == -0.5 and narrowed.upper[4] == 1.0
    assert robot.lower[0] == -3.0  # the original is unchanged
    with pytest.raises(fw.LimitsError, match="twist"):
        robot.with_bounds({"twist": (1.0, -1.0)})


def test_empty_urdf_limits_are_named_together_and_bounds_or_locks_make_the_robot_usable(rng):
    # a <limit> without lower/upper declares [0, 0] (URDF's defaults), as real files do for wheels
    text = PLANAR_URDF.replace('lower="-2" upper="2" ', "").replace('lower="-0.2" upper="0.5" ', "")
    with pytest.raises(fw.LimitsError) as raised:
        fw.robot_from_urdf(text)
    message = str(raised.value)
    assert "2 coordinates are empty" in message and "'slide'" in message and "'twist'" in message
    assert "locked=" in message and "bounds=" in message
    # the override is applied before the robot checks its bounds
    robot = fw.robot_from_urdf(text, bounds={"twist": (-1.0, 1.5), "slide": (0.0, 0.4)})
    assert (robot.lower[3], robot.upper[3], robot.lower[4], robot.upper[4]) == (0.0, 0.4, -1.0, 1.5)
    reference = fw.robot_from_urdf(PLANAR_URDF)  # the same kinematics, other bounds
    x = reference.random_configurations(rng, 5)
    np.testing.assert_allclose(robot.frame_poses(x).positions, reference.frame_poses(x).positions, atol=1e-12)
    locked = fw.robot_from_urdf(text, locked={"slide": 0.1}, bounds={"twist": (-1.0, 1.0)})
    assert locked.joint_names == ("base", "twist")
    with pytest.raises(fw.UnknownJointError, match="did you mean 'twist'"):
        fw.robot_from_urdf(text, bounds={"twists": (-1.0, 1.0)})
    with pytest.raises(fw.LimitsError, match="'twist' are inverted"):  # an inverted override is still refused
        fw.robot_from_urdf(text, bounds={"twist": (1.0, -1.0), "slide": (0.0, 0.4)})


def test_xacro_file_with_arguments(tmp_path):
    path = fw.resources.data_dir("robots") / "examples" / "two_link.urdf.xacro"
    short = fw.load_robot(path, xacro_args={"l1": "0.2", "l2": "0.1"})
    long = fw.load_robot(path)
    x = np.zeros((1, short.n))
    ee = short.end_effectors[0]
    assert np.linalg.norm(short.frame_poses(x, ee).positions) < np.linalg.norm(long.frame_poses(x, ee).positions)


# ---------------------------------------------------------------------- bad input


def test_missing_file(tmp_path):
    with pytest.raises(fw.RobotFileError, match="does not exist"):
        fw.load_robot(tmp_path / "nothing.urdf")


def test_malformed_xml(tmp_path):
    path = tmp_path / "bad.urdf"
    path.write_text("<robot name='x'><link name='a'></robot>")
    with pytest.raises(fw.RobotFileError, match="malformed XML"):
        fw.load_robot(path)


def test_not_a_urdf(tmp_path):
    path = tmp_path / "bad.urdf"
    path.write_text("<sdf><model/></sdf>")
    with pytest.raises(fw.RobotFileError, match="not a URDF"):
        fw.load_robot(path)


def test_xacro_error(tmp_path):
    path = tmp_path / "bad.urdf.xacro"
    path.write_text(
        '<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro"><link name="${undefined_property}"/></robot>'
    )
    with pytest.raises(fw.RobotFileError, match="xacro failed"):
        fw.load_robot(path)


def test_unknown_robot_name():
    with pytest.raises(fw.UnknownRobotError, match="youbot_dual_mobile"):
        fw.load_robot("youbot_dual_mobil")


def test_unknown_frame_suggests_close_names():
    robot = fw.load_robot("youbot_dual_mobile")
    with pytest.raises(fw.UnknownFrameError, match="arm1_ee"):
        robot.frame_poses(robot.middle, "arm1_e")
    with pytest.raises(fw.UnknownFrameError):
        fw.load_robot("youbot_arm", end_effectors=["gripper"])


def test_unknown_joint_and_group():
    with pytest.raises(fw.UnknownJointError):
        fw.load_robot("youbot_arm", joints=["joint7"])
    with pytest.raises(fw.UnknownJointError, match="arm3"):
        fw.load_robot("youbot_dual_mobile").group("arm3")


@pytest.mark.parametrize("shape", [(13,), (4, 13)])
def test_accepted_population_shapes(shape):
    robot = fw.load_robot("youbot_dual_mobile")
    assert robot.frame_poses(np.zeros(shape)).positions.shape == (1 if len(shape) == 1 else 4, 2, 3)


@pytest.mark.parametrize("shape", [(12,), (4, 12), (2, 3, 13), ()])
def test_wrong_population_shape(shape):
    robot = fw.load_robot("youbot_dual_mobile")
    with pytest.raises(fw.ConfigurationError, match=r"\(pop, 13\)"):
        robot.frame_poses(np.zeros(shape))


def test_nan_in_population():
    robot = fw.load_robot("youbot_dual_mobile")
    X = np.zeros((5, 13))
    X[3, 4] = np.nan
    with pytest.raises(fw.ConfigurationError, match="NaN"):
        robot.frame_poses(X)


def test_inverted_limits_in_a_urdf():
    text = PLANAR_URDF.replace('lower="-2" upper="2"', 'lower="2" upper="-2"')
    with pytest.raises(fw.LimitsError, match="twist"):
        fw.robot_from_urdf(text)


def test_mount_errors():
    with pytest.raises(fw.RobotFileError, match="no link 'deck'"):
        fw.mount(fw.planar_base_urdf(), [fw.Mount("youbot_arm", parent="deck")])
    with pytest.raises(fw.RobotFileError, match="prefix"):
        fw.mount(fw.planar_base_urdf(), [fw.Mount("youbot_arm", "platform"), fw.Mount("youbot_arm", "platform")])


UNALIGNED_URDF = """<robot name="unaligned">
  <link name="base"/><link name="l1"/><link name="l2"/><link name="ee"/>
  <joint name="roll" type="continuous"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.1"/>
    <axis xyz="0 -1 0"/></joint>
  <joint name="slide" type="prismatic"><parent link="l1"/><child link="l2"/><origin xyz="0.2 0 0"/>
    <axis xyz="0.6 0 0.8"/><limit lower="-0.1" upper="0.3" effort="1" velocity="1"/></joint>
  <joint name="tilt" type="revolute"><parent link="l2"/><child link="ee"/><origin xyz="0.3 0 0"/>
    <axis xyz="0 0.6 0.8"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
</robot>"""


def test_unaligned_and_negative_axes_load_and_match_pinocchio(tmp_path, rng):
    """A continuous joint about -y, a prismatic and a revolute joint along oblique axes: the axes are read from
    Pinocchio's motion subspace; FK equals Pinocchio's and a reachable target is reached."""
    path = tmp_path / "unaligned.urdf"
    path.write_text(UNALIGNED_URDF)
    robot = fw.load_robot(path)
    assert [j.kind for j in robot.joints] == [fw.JointKind.CONTINUOUS, fw.JointKind.PRISMATIC, fw.JointKind.REVOLUTE]
    np.testing.assert_allclose(robot.joints[0].axis, [0, -1, 0])
    for x in robot.random_configurations(rng, 20):
        np.testing.assert_allclose(robot.frame_poses(x, "ee").positions[0, 0],
                                   robot.frame_placement(x, "ee").translation, atol=1e-13)
    goal = robot.random_configurations(rng, 1)[0]
    result = fw.solve(fw.Problem(robot, fw.Position("ee", robot.frame_placement(goal, "ee").translation)))
    assert result.success
