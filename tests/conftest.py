"""Shared fixtures: URDFs shipped by PyPI packages (example-robot-data), if installed."""

from __future__ import annotations

import os
import sysconfig
from pathlib import Path

import numpy as np
import pytest


def example_robot_data_dir() -> Path | None:
    """``share/example-robot-data/robots`` of the installed ``example-robot-data`` wheel, or None."""
    for key in ("purelib", "platlib"):
        path = Path(sysconfig.get_paths()[key]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
        if path.is_dir():
            return path
    return None


@pytest.fixture(scope="session")
def erd() -> Path:
    path = example_robot_data_dir()
    if path is None:
        pytest.fail("example-robot-data is a test dependency (pip install -e .[test]); it is not installed")
    return path


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261123)


def without_compile_notices(err: str) -> str:
    """``err`` without the lines saying the package's code compiles (a cold cache's first use; see
    :class:`framework.compiled.cache.CompileNotice`)."""
    return "".join(line for line in err.splitlines(keepends=True) if not line.startswith("metaik: compiling "))


def same_framework_env(**extra: str) -> dict[str, str]:
    """The environment of a child process (a CLI run, a notebook kernel) that imports the framework this test
    process imports: its numba cache is warm, so the child does not compile the engine again."""
    import framework

    root = str(Path(framework.__file__).resolve().parents[1])
    return {**os.environ, **extra, "PYTHONPATH": os.pathsep.join(p for p in (root, os.environ.get("PYTHONPATH")) if p)}



@pytest.fixture(scope="module")
def pr2_table(erd):
    """``(robot, shape, scene)``: PR2's torso and both 7-DOF arms, its shape with its SRDF's disabled pairs, and a
    table in front of it (a 0.6 x 1.2 x 0.05 m box, top at 0.625 m; benchmarks/collisions.py's)."""
    import framework as fw

    arm = ("shoulder_pan", "shoulder_lift", "upper_arm_roll", "elbow_flex", "forearm_roll", "wrist_flex",
           "wrist_roll")
    robot = fw.load_robot(erd / "pr2_description" / "urdf" / "pr2.urdf",
                          joints=["torso_lift_joint"] + [f"{s}_{j}_joint" for s in "lr" for j in arm])
    shape = fw.RobotShape(robot, srdf=erd / "pr2_description" / "srdf" / "pr2.srdf")
    return robot, shape, fw.Scene((fw.Box([0.7, 0.0, 0.6], [0.6, 1.2, 0.05], name="table"),))


@pytest.fixture(scope="module")
def sphere_arm():
    """``(robot, shape, exact cover)`` of the two-joint arm of ``tests/test_collision.py`` whose base and forearm
    are spheres: the cover is the geometry itself, so sphere terms and coal agree (the collision tests use it)."""
    import framework as fw
    from framework.geometry.spheres import SphereCover
    from tests.test_collision import SPHERES, L, R

    robot = fw.robot_from_urdf(SPHERES)
    exact = SphereCover(np.array([0, 2]), np.array([[L, 0, 0], [L, 0, 0]]), np.array([R, R]), ("base_0", "fore_0"))
    return robot, fw.RobotShape(robot), exact


def pinocchio_placements(robot, x: np.ndarray, frames) -> dict:
    """frame -> placement (``pin.SE3``) at ``x`` by Pinocchio's own model of the robot's whole URDF text: solved
    joints from ``x``, locked ones at their values, mimic joints from their leaders, each set by name (an
    independent check of the package's reduced model and kinematics)."""
    import pinocchio as pin

    full = pin.buildModelFromXML(robot.urdf)
    data = full.createData()
    values = dict(robot.locked)
    values.update({j.name: x[j.index] for j in robot.joints})
    values.update({m.name: m.multiplier * values[m.leader] + m.offset for m in robot.mimics})
    q = pin.neutral(full)
    for joint, value in values.items():
        jm = full.joints[full.getJointId(joint)]
        q[jm.idx_q:jm.idx_q + jm.nq] = [np.cos(value), np.sin(value)] if jm.nq == 2 else [value]
    pin.framesForwardKinematics(full, data, q)
    return {frame: data.oMf[full.getFrameId(frame)].copy() for frame in frames}
