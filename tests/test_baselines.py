"""Jacobian baselines: pseudo-inverses, convergence, paper 001's task priority, and the singular jump."""

from __future__ import annotations

import numpy as np
import pytest

import framework as fw
from framework.tracking import paths
from framework.tracking import trajectory as tr
from framework.solvers.baselines import dls_inverse, relative_jacobian_step, svd_pinv
from framework.tracking import jacobian_track, relative_jacobian_track
from framework.solvers.baselines.jacobian import position_and_jacobian
from framework.tracking import TrackingTask, track


@pytest.fixture(scope="module")
def arm() -> fw.Robot:
    return fw.load_robot("youbot_arm")


def test_pseudo_inverses(rng):
    J = rng.standard_normal((3, 7))
    np.testing.assert_allclose(svd_pinv(J), np.linalg.pinv(J), atol=1e-12)
    np.testing.assert_allclose(
        dls_inverse(J, 0.1), J.T @ np.linalg.inv(J @ J.T + 0.01 * np.eye(3)), atol=1e-12
    )
    singular = np.array([[1.0, 0.0], [0.0, 1e-9]])
    np.testing.assert_allclose(
        svd_pinv(singular, rcond=1e-6), [[1.0, 0.0], [0.0, 0.0]]
    )  # σ below the cut dropped


def test_jacobian_matches_finite_differences(arm, rng):
    x = arm.random_configurations(rng, 1)[0]
    p, J = position_and_jacobian(arm, x, "ee")
    h = 1e-7
    fd = np.column_stack([(arm.frame_placement(x + h * e, "ee").translation - p) / h for e in np.eye(arm.n)])
    np.testing.assert_allclose(J, fd, atol=1e-6)


@pytest.mark.parametrize("method", ["pinv", "dls"])
def test_closed_loop_ik_converges_for_an_arm_and_a_mobile_arm(method, rng):
    for name, frame in (("youbot_arm", "ee"), ("youbot_mobile", "arm_ee")):
        robot = fw.load_robot(name)
        x_goal = np.clip(robot.middle + 0.3 * rng.standard_normal(robot.n), robot.lower, robot.upper)
        target = robot.frame_placement(x_goal, frame).translation
        x0 = np.clip(x_goal + 0.05 * rng.standard_normal(robot.n), robot.lower, robot.upper)
        result = fw.solve(fw.Problem(robot, 1.0 * fw.Position(frame, target)), method, initial=x0,
                          max_iterations=200, tolerance=1e-9)
        error = np.linalg.norm(robot.frame_placement(result.configuration, frame).translation - target)
        assert result.success and error <= 1e-9


def stretched_arm_and_path(arm):
    """The youBot arm stretched (joints 3 = 0, 4 = π/2: links 2, 3 and 4-5 in line) and a 2 cm path along it."""
    x_singular = np.array([0.0, 0.5, 0.0, np.pi / 2, 0.0])
    p, J = position_and_jacobian(arm, x_singular, "ee")
    U, s, _ = np.linalg.svd(J)
    assert s[-1] < 1e-12  # constructed to be singular: no velocity along the arm
    along = U[:, -1] if U[:, -1] @ p > 0 else -U[:, -1]
    path = paths.line(p, p - 0.02 * along, 21)  # inward, 1 mm per waypoint
    return x_singular + np.array([0.0, 0.0, 1e-4, 0.0, 0.0]), path


def test_baseline_jumps_at_a_singularity_and_the_optimizer_does_not(arm):
    x0, path = stretched_arm_and_path(arm)
    pinv = jacobian_track(arm, path, method="pinv", initial=x0)  # resolved rate: one step per waypoint
    jump = pinv.smoothness(arm)
    assert jump.max_step["all"] > 1.0 and jump.worst_point["all"] == 1  # 1/σ_min blows the first step up
    assert pinv.position_error.max() > 0.1  # ... and the end-effector leaves the path by > 10 cm

    optimizer = track(arm, path, TrackingTask(motion=0.001), solver="hybrid", initial=x0, progress=False)
    smooth = optimizer.smoothness(arm)
    assert optimizer.position_error.max() < 1e-8
    assert smooth.max_step["all"] < 0.2  # the inherent bend of the elbow, not a jump
    assert smooth.max_step["all"] < 0.1 * jump.max_step["all"]

    dls = jacobian_track(arm, path, method="dls", initial=x0)  # damping: no jump, but it cannot follow
    assert dls.smoothness(arm).max_step["all"] < 0.2 and dls.position_error.max() > 0.01


def test_relative_jacobian_priority_and_tracking():
    robot = fw.load_robot("youbot_dual")
    x0 = robot.middle.copy()
    P = robot.frame_poses(x0, ("arm1_ee", "arm2_ee")).positions[0]
    offset = P[1] - P[0] + [0.0, 0.0, 0.01]
    target = P[0] + [0.0, 0.01, 0.0]
    dx, e_r, e_a = relative_jacobian_step(robot, x0, "arm1_ee", "arm2_ee", target, offset)
    assert e_r == pytest.approx(0.01) and e_a == pytest.approx(0.01)
    x1 = x0 + dx
    P1 = robot.frame_poses(x1, ("arm1_ee", "arm2_ee")).positions[0]
    # first-order: the relative error shrinks by K_r = 0.3, arm A's by K_A = 0.7
    assert np.linalg.norm(offset - (P1[1] - P1[0])) == pytest.approx(0.7 * 0.01, rel=0.05)
    assert np.linalg.norm(target - P1[0]) == pytest.approx(0.3 * 0.01, rel=0.05)

    path = paths.circle(P[0] + [0.0, 0.02, 0.0], 0.02, 12, start_angle=np.pi)
    result = relative_jacobian_track(
        robot, path, "arm1_ee", "arm2_ee", P[1] - P[0], initial=x0, iterations_per_point=60, tolerance=1e-10
    )
    assert result.position_error.max() < 1e-8
    assert (
        set(result.terms) == {"position", "follower", "motion[all]"} and result.solver == "relative_jacobian"
    )


def test_bad_input(arm):
    path = paths.line((0.3, 0.0, 0.3), (0.3, 0.01, 0.3), 3)
    with pytest.raises(fw.TaskError, match="method"):
        jacobian_track(arm, path, method="transpose")
    with pytest.raises(fw.ConfigurationError):
        jacobian_track(arm, path, initial=np.zeros(3))
    with pytest.raises(fw.UnknownFrameError):
        jacobian_track(arm, path, frame="hand")
    dual = fw.load_robot("youbot_dual")
    with pytest.raises(fw.TaskError, match="t_r"):
        relative_jacobian_track(dual, path, "arm1_ee", "arm2_ee", (0.0, np.inf, 0.0))
