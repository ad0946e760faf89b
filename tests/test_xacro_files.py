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


def test_expansion_leaves_this_process_xacro_as_it_is(tmp_path, monkeypatch):
    """xacro's globals are replaced in a process of its own, never in this one: with this process's xacro made
    unusable, a file still expands, and xacro's evaluator and substitution commands are the library's own."""
    import xacro
    from xacro import substitution_args

    before = (xacro.safe_eval, substitution_args._eval_find, substitution_args._eval_env)

    def unusable(*args, **kwargs):
        raise AssertionError("xacro was called in the user's process")

    monkeypatch.setattr(xacro, "process_file", unusable)
    robot = fw.load_robot(_arm(tmp_path), xacro_args={"length": 0.25})
    assert robot.frame_placement(robot.middle, "tip").translation == pytest.approx([0, 0, 0.25])
    assert (xacro.safe_eval, substitution_args._eval_find, substitution_args._eval_env) == before


def test_relative_package_dirs_resolve_against_the_working_folder(tmp_path, monkeypatch):
    """A relative ``package_dirs`` entry is the caller's folder, also for a ``$(find pkg)`` in an included file."""
    package = tmp_path / "pkgs" / "my_arm"
    (package / "urdf").mkdir(parents=True)
    (package / "urdf" / "arm.urdf.xacro").write_text(ARM.replace("EXTRA", ""))
    top = tmp_path / "robots" / "top.urdf.xacro"
    top.parent.mkdir()
    top.write_text('<robot name="top" xmlns:xacro="http://www.ros.org/wiki/xacro">'
                   '<xacro:include filename="$(find my_arm)/urdf/arm.urdf.xacro"/></robot>')
    monkeypatch.chdir(tmp_path)
    robot = fw.load_robot(Path("robots") / "top.urdf.xacro", package_dirs=["pkgs"])
    assert "tip" in robot.frame_names
