"""The Jacobian baselines (pseudo-inverse, damped least squares) on the mobile youBot."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import framework as fw
from framework.fabrik.jacobian import (
    JacobianSettings,
    damped_least_squares_ik,
    damped_least_squares_step,
    pseudo_inverse_ik,
    pseudo_inverse_step,
)


@pytest.fixture(scope="module")
def robot() -> fw.Robot:
    return fw.load_robot("youbot_mobile")


def easy_task(robot: fw.Robot, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A start inside the limits and a target a few centimetres from where it puts the end-effector."""
    x0 = robot.middle + 0.5 * (robot.random_configurations(rng, 1)[0] - robot.middle)
    x_target = np.clip(x0 + rng.normal(0, 0.1, robot.n), robot.lower, robot.upper)
    return robot.frame_placement(x_target, "arm_ee").translation, x0


@pytest.mark.parametrize("make", [pseudo_inverse_ik, damped_least_squares_ik])
def test_baselines_converge_on_easy_targets(robot, make, rng):
    solver = make(robot)
    for _ in range(10):
        target, x0 = easy_task(robot, rng)
        result = solver.solve(target, x0, tolerance=1e-6, max_iterations=500)
        assert result.success and result.reason == "converged"
        reached = robot.frame_placement(result.configuration, "arm_ee").translation
        assert np.linalg.norm(reached - target) <= 1e-6
        assert result.iterations < 200
        assert np.all(result.configuration >= robot.lower) and np.all(result.configuration <= robot.upper)
        assert result.base_path.shape == (result.iterations + 1, 3)


def test_jacobian_is_pinocchios_and_matches_finite_differences(robot, rng):
    """The position Jacobian the baselines use, against central differences of the forward kinematics."""
    data, fid = robot.model.createData(), robot.frame_id("arm_ee")
    x = robot.random_configurations(rng, 1)[0]
    J = pin.computeFrameJacobian(robot.model, data, x, fid, pin.LOCAL_WORLD_ALIGNED)[:3]
    J = J @ robot.coordinate_jacobian(x)
    h, fd = 1e-6, np.empty((3, robot.n))
    for i in range(robot.n):
        dx = np.zeros(robot.n)
        dx[i] = h
        fd[:, i] = (
            robot.frame_placement(x + dx, "arm_ee").translation
            - robot.frame_placement(x - dx, "arm_ee").translation
        ) / (2 * h)
    np.testing.assert_allclose(J, fd, atol=1e-8)


def test_update_rules(rng):
    J = rng.normal(size=(3, 8))
    e = rng.normal(size=3)
    s = JacobianSettings(damping=0.1)
    np.testing.assert_allclose(J @ pseudo_inverse_step(J, e, s), e, atol=1e-12)  # full row rank: exact
    dls = damped_least_squares_step(J, e, s)
    # the normal equations of damped least squares
    np.testing.assert_allclose((J.T @ J + 0.01 * np.eye(8)) @ dls, J.T @ e, atol=1e-12)


def test_steps_are_capped_and_the_heading_wraps(robot):
    """From far away every step moves no coordinate more than max_step; base_theta wraps instead of clipping."""
    solver = pseudo_inverse_ik(robot)
    x0 = np.zeros(robot.n)
    x0[2] = math.pi - 0.01
    result = solver.solve([1.3, -1.2, 0.3], x0, tolerance=1e-6, max_iterations=30)
    steps = np.abs(np.diff(result.base_path, axis=0))
    steps[:, 2] = np.abs(np.remainder(steps[:, 2] + math.pi, 2 * math.pi) - math.pi)
    assert steps.max() <= math.radians(5) + 1e-12
    assert np.all(np.abs(result.base_path[:, 2]) <= math.pi)
    # it turned through ±π (wrapped, not clipped)
    assert np.any(np.diff(np.sign(result.base_path[:, 2])) != 0)
    assert result.iterations == 30 and result.reason == "max_iterations"
