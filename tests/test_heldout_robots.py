"""Robot files this project does not ship, used as a newcomer would: pybullet's data (KUKA iiwa, Panda, xArm6,
laikago) and robotics-toolbox data's xacro sets (KUKA KR6, whose xacro names packages unlike their folders;
Frankie Omni, an arm on an x-θ base) load with their meshes, get groups by role, solve a pose (checked by
Pinocchio's own model of the same URDF text) and record (every mesh in the .rrd)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import framework as fw
from framework.io.recording import Recorder, read_recording
from framework.viz.drawing import RobotDrawing
from tests.conftest import pinocchio_placements

pybullet_data = pytest.importorskip("pybullet_data", reason="the test extra installs pybullet (its robot data)")
rtbdata = pytest.importorskip("rtbdata", reason="the test extra installs rtb-data (robotics-toolbox's robot data)")
PB = Path(pybullet_data.getDataPath())
RTB = Path(rtbdata.__path__[0]) / "xacro"
KUKA = RTB / "kuka_description"

#: name -> (file, load_robot options, frame to solve, expected groups)
ROBOTS = {
    "iiwa": (PB / "kuka_iiwa" / "model.urdf", {}, "lbr_iiwa_link_7", {"arm": 7}),
    "panda": (PB / "franka_panda" / "panda.urdf", {}, "panda_grasptarget", {"arm": 7, "gripper": 1}),
    "xarm6": (PB / "xarm" / "xarm6_robot.urdf", {}, "link6", {"arm": 6}),
    "laikago": (PB / "laikago" / "laikago.urdf", {}, "FL_lower_leg",
                {"front_left_leg": 3, "front_right_leg": 3, "rear_left_leg": 3, "rear_right_leg": 3}),
    "kr6": (KUKA / "kuka_kr6" / "urdf" / "kr6r700sixx.xacro",
            {"package_dirs": {"kuka_kr6_support": KUKA / "kuka_kr6", "kuka_resources": KUKA / "kuka_resources"}},
            "tool0", {"arm": 6}),
    "frankie_omni": (RTB / "qut_frankie_description" / "robots" / "frankieOmni_arm_hand.urdf.xacro",
                     {"package_dirs": [RTB]}, "frankie_hand", {"base": 3, "arm": 7, "gripper": 1}),
}


@pytest.mark.parametrize("name", list(ROBOTS))
def test_a_robot_file_from_elsewhere_loads_solves_and_records(name, tmp_path):
    path, options, frame, groups = ROBOTS[name]
    robot = fw.load_robot(path, **options)
    assert {g: len(i) for g, i in robot.groups.items()} == groups
    assert frame in robot.end_effectors
    drawing = RobotDrawing(robot)
    assert not drawing.missing and sum(v.kind == "mesh" for v in drawing.visuals) >= 3
    x_goal = robot.random_configurations(np.random.default_rng(7), 1)[0]
    target = robot.frame_placement(x_goal, frame)
    problem = fw.Problem(robot, fw.Pose(frame, target))
    result = fw.solve(problem, seed=0)
    assert result.success, result.reason
    reached = pinocchio_placements(robot, result.configuration, [frame])[frame]
    assert np.linalg.norm(reached.translation - target.translation) <= 1e-6
    assert np.linalg.norm(pin.log3(reached.rotation.T @ target.rotation)) <= 1e-6
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no mesh left out, no notice hidden in the file
        with Recorder(tmp_path / f"{name}.rrd", robot) as recorder:
            recorder.log_solution(result, problem=problem)
    recording = read_recording(tmp_path / f"{name}.rrd")
    meshes = [e for e in recording.entities if e.startswith("/world/robot/visuals/")]
    assert len(meshes) == len(drawing.visuals)  # every visual, meshes as meshes


def test_a_package_named_unlike_its_folder_says_what_it_saw():
    """The KR6's xacro includes $(find kuka_kr6_support) from the folder kuka_kr6: given only the folder holding
    it, the error lists where it looked and the closest names, and says how to name it."""
    with pytest.raises(fw.RobotFileError, match="kuka_kr6_support.*not found; searched .*kuka_description.*"
                                                 "closest package names seen: kuka_kr6.*package_dirs="):
        fw.load_robot(ROBOTS["kr6"][0], package_dirs=[KUKA])


def test_show_and_reach_take_the_options_load_robot_takes(capsys):
    """The command line loads a robot as Python does: --package-dir PKG=FOLDER for the KR6's packages, and shows
    its groups by role, end-effectors and frames."""
    from framework.cli import main

    kr6 = str(ROBOTS["kr6"][0])
    assert main(["show", kr6, "--package-dir", f"kuka_kr6_support={KUKA / 'kuka_kr6'}",
                 "--package-dir", f"kuka_resources={KUKA / 'kuka_resources'}"]) == 0
    out = capsys.readouterr().out
    assert "groups: arm (joint_a1" in out and "end-effectors: tool0" in out and "frames (9): base_link" in out
    assert main(["show", kr6]) == 2  # without the packages: the error says what it searched, and how to say it
    assert "kuka_kr6_support" in capsys.readouterr().err
    mixed = ["--package-dir", f"kuka_kr6_support={KUKA / 'kuka_kr6'}", "--package-dir", str(KUKA)]  # one renamed
    assert main(["show", kr6, *mixed]) == 0 and "groups: arm" in capsys.readouterr().out


def test_a_urdf_holding_xacro_and_a_folder_say_what_to_do(tmp_path):
    from tests.fuzz.escapes import ARM

    (tmp_path / "arm.urdf").write_text(ARM.replace("EXTRA", ""))
    with pytest.raises(fw.RobotFileError, match="holds xacro.*name the file .urdf.xacro"):
        fw.load_robot(tmp_path / "arm.urdf")
    with pytest.raises(fw.RobotFileError, match="is a folder: give the URDF or xacro file.*holds arm.urdf"):
        fw.load_robot(tmp_path)


def test_mount_takes_the_loading_options_and_its_groups_follow_the_joints_solved(tmp_path):
    """A mounted arm from a xacro set whose packages are named unlike their folders (package_dirs as a mapping);
    solving only some joints keeps the groups mount makes, reduced to them."""
    options = ROBOTS["kr6"][1]
    arm = fw.Mount(str(ROBOTS["kr6"][0]), "platform", prefix="kr_", end_effectors=["tool0"])
    robot = fw.mount(fw.planar_base_urdf(), [arm], **options)
    assert {g: len(i) for g, i in robot.groups.items()} == {"base": 3, "kr": 6}
    some = fw.mount(fw.planar_base_urdf(), [arm], joints=["base_x", "kr_joint_a1", "kr_joint_a2"], **options)
    assert {g: len(i) for g, i in some.groups.items()} == {"base": 1, "kr": 2}
    assert not RobotDrawing(robot).missing  # the arm's package:// meshes found through the same package_dirs
