"""Xacro files are data: escape attempts fail with our error and no side effect; ROS packages without ROS."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import framework as fw
from framework.errors import RobotFileError

from tests.fuzz.escapes import ARM, ESCAPES


def _arm(tmp_path: Path, extra: str = "", name: str = "arm.urdf.xacro") -> Path:
    path = tmp_path / name
    path.write_text(ARM.replace("EXTRA", extra))
    return path


def test_plain_xacro_still_expands(tmp_path):
    robot = fw.load_robot(_arm(tmp_path), xacro_args={"length": 0.5})
    assert robot.frame_placement(robot.middle, "tip").translation == pytest.approx([0, 0, 0.5])


@pytest.mark.parametrize("attempt", list(ESCAPES), ids=list(ESCAPES))
def test_escape_attempts_fail_with_our_error_and_no_side_effect(tmp_path, attempt):
    marker = tmp_path / "pwned"
    expression = ESCAPES[attempt]
    extra = f'<link name="probe"><visual><origin xyz="{expression} 0 0"/></visual></link>'
    with pytest.raises(RobotFileError):
        fw.load_robot(_arm(tmp_path, extra))
    assert not marker.exists()


def test_the_known_shell_escape_runs_nothing(tmp_path):
    marker = tmp_path / "pwned"
    payload = ("${[c for c in python.type.mro(python.type)[1].__subclasses__() if c.__name__ == 'Popen'][0]"
               f"(['touch', '{marker}'])}}")
    with pytest.raises(RobotFileError):
        fw.load_robot(_arm(tmp_path, f'<link name="probe"><origin xyz="{payload}"/></link>'))
    assert not marker.exists()


def test_trusted_files_may_read_the_environment(tmp_path, monkeypatch):
    monkeypatch.setenv("METAIK_TEST_LENGTH", "0.8")
    path = _arm(tmp_path).read_text().replace('default="0.3"', 'default="$(env METAIK_TEST_LENGTH)"')
    (tmp_path / "env.urdf.xacro").write_text(path)
    with pytest.raises(RobotFileError, match="trusted=True"):
        fw.load_robot(tmp_path / "env.urdf.xacro")
    robot = fw.load_robot(tmp_path / "env.urdf.xacro", trusted=True)
    assert robot.frame_placement(robot.middle, "tip").translation[2] == pytest.approx(0.8)


def test_undeclared_arguments_are_an_error(tmp_path):
    with pytest.raises(RobotFileError, match=r"\['lenght'\] are not declared"):
        fw.load_robot(_arm(tmp_path), xacro_args={"lenght": 0.5})


def test_find_and_include_through_package_dirs(tmp_path):
    """A xacro that includes a file of another package by $(find pkg), as ROS robot descriptions do."""
    packages = tmp_path / "src"
    share = packages / "arm_description"
    (share / "urdf").mkdir(parents=True)
    (share / "package.xml").write_text("<package><name>arm_description</name></package>")
    (share / "urdf" / "link.xacro").write_text(
        '<robot xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:macro name="tip_link">'
        '<link name="tip"/></xacro:macro></robot>')
    top = tmp_path / "robot.urdf.xacro"
    top.write_text(ARM.replace('<link name="tip"/>', '<xacro:tip_link/>').replace(
        "EXTRA", "").replace('<link name="base"/>', '<xacro:include filename="$(find arm_description)/urdf/'
                                                  'link.xacro"/><link name="base"/>'))
    with pytest.raises(RobotFileError, match="ROS package 'arm_description' not found"):
        fw.load_robot(top)
    robot = fw.load_robot(top, package_dirs=[packages])
    assert "tip" in robot.frame_names
    np.testing.assert_allclose(robot.frame_placement(robot.middle, "tip").translation, [0, 0, 0.3])
