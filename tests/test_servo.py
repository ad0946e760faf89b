"""The servo loop (framework.tracking.servo): velocity and acceleration limits hold at every tick (checked from the
commanded configurations alone), a far target is reached, a moving one tracked exactly, one beyond reach
approached as far as the arm goes, and the limits are the URDF's."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest

import framework as fw
from framework.errors import TaskError
from framework.tracking.servo import Servo
from framework.tracking.timing import velocity_limits
from tests.conftest import example_robot_data_dir

FRAME = "panda_hand_tcp"
DT = 1e-3


@pytest.fixture(scope="module")
def panda() -> fw.Robot:
    return fw.load_robot(example_robot_data_dir() / "panda_description" / "urdf" / "panda.urdf",
                         locked={"panda_finger_joint1": 0.0})


def test_the_velocity_limits_are_the_urdf_s(panda):
    """Read from the URDF text itself (not through Pinocchio): each arm joint's <limit velocity>."""
    root = ET.fromstring(panda.urdf)
    given = {j.get("name"): float(j.find("limit").get("velocity")) for j in root.iter("joint")
             if j.find("limit") is not None}
    np.testing.assert_allclose(velocity_limits(panda), [given[name] for name in panda.coordinate_names])


def test_limits_hold_at_every_tick_under_jumping_targets(panda):
    """Targets jumping every 50 ms to poses of random configurations (a teleoperation device's worst): from the
    commanded configurations alone, |Δq|/dt <= v_max and |Δ²q|/dt² <= a_max at every tick, and q within the bounds
    (a servo without limits would jump by up to ~3 rad in a tick: 3000 rad/s)."""
    rng = np.random.default_rng(0)
    servo = Servo.pose(panda, FRAME, velocity_scale=0.5, acceleration=15.0)
    Q = [servo.q]
    targets = [panda.frame_placement(x, FRAME) for x in panda.random_configurations(rng, 8)]
    for k in range(400):
        Q.append(servo.step(DT, targets[k // 50]).q)
    Q = np.array(Q)
    V = np.diff(Q, axis=0) / DT
    assert np.all(np.abs(V) <= 0.5 * velocity_limits(panda) * (1 + 1e-9))
    assert np.all(np.abs(np.diff(V, axis=0)) / DT <= 15.0 * (1 + 1e-6))
    assert np.all(Q >= panda.lower - 1e-12) and np.all(Q <= panda.upper + 1e-12)
    assert np.abs(V).max() >= 0.4 * velocity_limits(panda).min()  # it moved at speed (not stuck)


def test_a_far_target_is_reached_and_held(panda):
    """A pose 2 rad away in joint space: held back by the limits on the way (said so), then reached exactly (FK
    within 1e-9) and held, in about the time the limits allow (a few seconds, not ticks)."""
    rng = np.random.default_rng(3)
    x = panda.random_configurations(rng, 1)[0]
    target = panda.frame_placement(x, FRAME)
    servo = Servo.pose(panda, FRAME, acceleration=20.0)
    first = servo.step(DT, target)
    assert not first.reached and first.limited and "held back by the limits" in first.reason
    steps = [servo.step(DT, target) for _ in range(4000)]
    k = next(i for i, s in enumerate(steps) if s.reached)
    assert 100 < k < 3000
    assert all(s.reached for s in steps[-500:])  # held (the goal may still be polished by microns once or twice)
    reached = panda.frame_placement(steps[-1].q, FRAME)
    assert np.linalg.norm(reached.translation - target.translation) <= 1e-9
    assert np.linalg.norm(pin.log3(reached.rotation.T @ target.rotation)) <= 1e-9


def test_a_moving_target_is_tracked_exactly_after_the_start(panda):
    """A 10 cm circle at 0.5 Hz streamed at 1 kHz: after the first half second (the start from rest), every tick's
    configuration meets its target within 1e-9 m by Pinocchio's FK."""
    servo = Servo.pose(panda, FRAME, acceleration=20.0)
    centre = panda.frame_placement(panda.middle, FRAME)
    errors = []
    for k in range(2000):
        t = k * DT
        target = pin.SE3(centre.rotation, centre.translation + 0.1 * np.array([0, np.cos(np.pi * t) - 1,
                                                                               np.sin(np.pi * t)]))
        q = servo.step(DT, target).q
        errors.append(np.linalg.norm(panda.frame_placement(q, FRAME).translation - target.translation))
    assert max(errors[500:]) <= 1e-9
    assert max(errors[:500]) > 1e-6  # the start lagged (from rest): the limits did act


def test_a_target_beyond_reach_is_approached_and_said(panda):
    """A position 3 m away: never reached, the step says why, the hand ends nearer to it than it started and the
    limits hold."""
    servo = Servo.pose(panda, FRAME, acceleration=20.0)
    start = panda.frame_placement(servo.q, FRAME).translation
    target = pin.SE3(np.eye(3), start + np.array([3.0, 0.0, 0.0]))
    steps = [servo.step(DT, target) for _ in range(1500)]
    assert not any(s.reached for s in steps) and "goal misses the task" in steps[-1].reason
    end = panda.frame_placement(steps[-1].q, FRAME).translation
    assert np.linalg.norm(end - target.translation) < np.linalg.norm(start - target.translation) - 0.1
    V = np.diff(np.array([s.q for s in steps]), axis=0) / DT
    assert np.all(np.abs(V) <= velocity_limits(panda) * (1 + 1e-9))


def test_bad_settings_are_named(panda):
    with pytest.raises(TaskError, match="velocity_scale"):
        Servo.pose(panda, FRAME, velocity_scale=0)
    with pytest.raises(TaskError, match="acceleration limits"):
        Servo.pose(panda, FRAME, acceleration=-1.0)
    servo = Servo.pose(panda, FRAME)
    with pytest.raises(TaskError, match="dt must be"):
        servo.step(0.0)
    with pytest.raises(TaskError, match="Servo.pose"):
        Servo(panda, fw.Position(FRAME, [0.4, 0.0, 0.4])).step(DT, pin.SE3.Identity())
