"""A failed answer says why in one line: the task term missed and by how much, a target beyond the robot's reach
(checked against a brute-force farthest point), a joint target outside the bounds, the waypoints a path missed."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import framework as fw
from framework.tracking import TrackingTask, track
from framework.tracking import trajectory as tr


@pytest.fixture(scope="module")
def puma() -> fw.Robot:
    return fw.load_robot("puma560")


def _farthest(robot: fw.Robot, frame: str, center: np.ndarray) -> float:
    """Brute force: the farthest ``frame`` gets from ``center`` over 200,000 random configurations."""
    X = robot.random_configurations(np.random.default_rng(11), 200_000)
    return float(np.linalg.norm(robot.frame_poses(X, frame).positions[:, 0] - center, axis=1).max())


def test_a_target_beyond_reach_says_how_far(puma):
    target = np.array([1.5, 0.4, 0.6])
    result = fw.solve(fw.Problem(puma, fw.Position("ee", target)))
    assert not result.success
    # the first joint of the chain: its origin is fixed in the world (Pinocchio's placement of joint 1)
    data = puma.model.createData()
    pin.forwardKinematics(puma.model, data, puma.to_pinocchio(puma.middle))
    center = np.array(data.oMi[1].translation)
    beyond = np.linalg.norm(target - center) - _farthest(puma, "ee", center)
    assert beyond > 0.5  # (a trivial check: the target is far outside)
    reported = float(result.reason.split(": ")[-1].split(" m beyond")[0])
    assert reported == pytest.approx(beyond, abs=0.01)
    assert result.reason.startswith("position[ee] missed by ")
    error = float(result.reason.split("missed by ")[1].split(" m")[0])
    assert error == pytest.approx(result.errors["position[ee]"], rel=1e-2)


def test_a_reachable_target_missed_by_a_short_budget_is_not_called_unreachable(puma):
    x = puma.random_configurations(np.random.default_rng(3), 1)[0]
    target = puma.frame_placement(x, "ee").translation
    result = fw.solve(fw.Problem(puma, fw.Position("ee", target)), "de", max_iterations=2)
    assert not result.success and "missed by" in result.reason and "beyond" not in result.reason
    assert fw.solve(fw.Problem(puma, fw.Position("ee", target))).reason == ""


def test_a_joint_target_outside_the_bounds_is_named(puma):
    result = fw.solve(fw.Problem(puma, fw.JointTarget("arm", [90, 0, 0, 0, 0, 0])))
    assert not result.success
    assert "joint1's target 90 lies outside its bounds [-2.793, 2.793] rad (degrees given for radians?)" in result.reason


def test_a_path_that_misses_waypoints_says_which(puma):
    positions = tr.Trajectory(np.array([[0.4, 0.1, 0.4], [0.45, 0.1, 0.4], [2.0, 0.0, 0.4], [2.1, 0.0, 0.4],
                                        [0.5, 0.1, 0.4]]))
    result = track(puma, positions, TrackingTask(frame="ee", motion={}), progress=False)
    assert result.stop_reason == "completed" and result.success.tolist() == [True, True, False, False, True]
    assert result.reason.startswith("2 of 5 waypoints missed (k = 2-3); waypoint 2: position missed by ")
    assert "the target is 2.04 m from ee's first joint" in result.reason  # waypoint 2's own target (2.0, 0, 0.4)
    whole = track(puma, positions[:2], TrackingTask(frame="ee", motion={}), progress=False)
    assert whole.reason == ""


def test_a_path_of_pose_terms_reports_their_distance_and_angle(puma):
    """A path tracked with a pose term (position and orientation in one term): the waypoints' position and
    orientation errors are the pose's distance and sin(angle / 2), not zeros."""
    R = pin.rpy.rpyToMatrix(0.0, np.pi / 2, 0.0)

    def builder(k, position, rotation, previous):
        return fw.Objective.of(fw.Pose("ee", pin.SE3(R, position)))

    path = tr.Trajectory(np.array([[0.4, 0.1, 0.3], [1.8, 0.0, 0.3]]))
    result = track(puma, path, builder, progress=False)
    assert result.success.tolist() == [True, False]
    missed = fw.solve(fw.Problem(puma, fw.Pose("ee", pin.SE3(R, path.positions[1]))),
                      initial=result.configurations[0])
    assert result.position_error[1] == pytest.approx(missed.errors["pose[ee].distance"], rel=1e-6)
    assert result.position_error[1] > 0.5 and result.position_error[0] < 1e-6
    assert result.orientation_error[1] == pytest.approx(np.sin(missed.errors["pose[ee].angle"] / 2), abs=1e-6)
