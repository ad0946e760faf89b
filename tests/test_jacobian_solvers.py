"""The Jacobian baselines ``pinv`` and ``dls`` behind ``solve()`` (paper 003's settings, on the mobile youBot)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import framework as fw
from framework.solvers.baselines.jacobian import dls_inverse, svd_pinv
from framework.solvers.baselines.solver import BUSS
from framework.engine import residuals


@pytest.fixture(scope="module")
def robot() -> fw.Robot:
    return fw.load_robot("youbot_mobile")


def easy_task(robot: fw.Robot, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A start inside the limits and a target a few centimetres from where it puts the end-effector."""
    x0 = robot.middle + 0.5 * (robot.random_configurations(rng, 1)[0] - robot.middle)
    x_target = np.clip(x0 + rng.normal(0, 0.1, robot.n), robot.lower, robot.upper)
    return robot.frame_placement(x_target, "arm_ee").translation, x0


@pytest.mark.parametrize("method", ["pinv", "dls"])
def test_baselines_converge_on_easy_targets(robot, method, rng):
    for _ in range(10):
        target, x0 = easy_task(robot, rng)
        steps = []
        result = fw.solve(fw.Problem(robot, 1.0 * fw.Position("arm_ee", target)), method, initial=x0,
                          tolerance=1e-6, max_iterations=500, options=BUSS,
                          callback=lambda k, e, x: steps.append(x))
        assert result.success and result.stop_reason == "tolerance"
        reached = robot.frame_placement(result.configuration, "arm_ee").translation  # Pinocchio FK
        assert np.linalg.norm(reached - target) <= 1e-6
        assert 0 < result.iterations < 200 and len(steps) == result.iterations
        assert result.evaluations == result.iterations + 1 == result.history.size
        assert result.history[-1] <= 1e-6 < result.history[0]
        assert np.all(result.configuration >= robot.lower) and np.all(result.configuration <= robot.upper)


def test_the_task_residual_is_the_position_error_and_its_jacobian_matches_finite_differences(robot, rng):
    """What the loop steps on: ``r = p(x) − t`` and ``∂r/∂x`` against central differences of Pinocchio's FK
    (the planar base's heading included)."""
    x = robot.random_configurations(rng, 1)[0]
    target = np.array([0.3, -0.2, 0.4])
    program = fw.Problem(robot, 1.0 * fw.Position("arm_ee", target)).program
    r, J = residuals(program, x)
    np.testing.assert_allclose(r, robot.frame_placement(x, "arm_ee").translation - target, atol=1e-12)
    h, fd = 1e-6, np.empty((3, robot.n))
    for i in range(robot.n):
        dx = np.zeros(robot.n)
        dx[i] = h
        fd[:, i] = (robot.frame_placement(x + dx, "arm_ee").translation
                    - robot.frame_placement(x - dx, "arm_ee").translation) / (2 * h)
    np.testing.assert_allclose(J, fd, atol=1e-8)


def test_update_rules(rng):
    J = rng.normal(size=(3, 8))
    e = rng.normal(size=3)
    np.testing.assert_allclose(J @ (svd_pinv(J, 0.01) @ e), e, atol=1e-12)  # full row rank: exact
    dls = dls_inverse(J, 0.1) @ e
    # the normal equations of damped least squares
    np.testing.assert_allclose((J.T @ J + 0.01 * np.eye(8)) @ dls, J.T @ e, atol=1e-12)


def test_steps_are_capped_and_the_heading_wraps(robot):
    """From far away every step moves no coordinate more than max_step; base_theta wraps instead of clipping."""
    x0 = np.zeros(robot.n)
    x0[2] = math.pi - 0.01
    path = [x0]
    result = fw.solve(fw.Problem(robot, 1.0 * fw.Position("arm_ee", [1.3, -1.2, 0.3])), "pinv", initial=x0,
                      tolerance=1e-6, max_iterations=30, options=BUSS, callback=lambda k, e, x: path.append(x))
    path = np.array(path)
    steps = np.abs(np.diff(path, axis=0))
    steps[:, 2] = np.abs(np.remainder(steps[:, 2] + math.pi, 2 * math.pi) - math.pi)
    assert steps.max() <= math.radians(5) + 1e-12
    assert np.all(np.abs(path[:, 2]) <= math.pi)
    # it turned through ±π (wrapped, not clipped)
    assert np.any(np.diff(np.sign(path[:, 2])) != 0)
    assert result.iterations == 30 and result.stop_reason == "max_iterations" and not result.success


def test_without_clamps_one_full_step_solves_a_linear_task():
    """A prismatic-only problem is linear: the pseudo-inverse step lands on the target at once (gain 1), half
    way with gain 0.5 — a trivial method reaches neither in one step."""
    robot = fw.load_robot("youbot_mobile")
    base = fw.JointTarget("base", [0.4, -0.3, 0.2])
    for gain, expected in ((1.0, 1), (0.5, None)):
        result = fw.solve(fw.Problem(robot, 1.0 * base), "pinv", initial=robot.middle, tolerance=1e-9,
                          max_iterations=1, options={"gain": gain})
        x = result.configuration[list(robot.groups["base"])]
        if expected:
            np.testing.assert_allclose(x, [0.4, -0.3, 0.2], atol=1e-12)
            assert result.success
        else:
            middle = robot.middle[list(robot.groups["base"])]
            np.testing.assert_allclose(x, middle + 0.5 * (np.array([0.4, -0.3, 0.2]) - middle), atol=1e-12)


@pytest.mark.parametrize("options", [{"gain": 0}, {"damping": -1}, {"max_step": math.inf}, {"rcond": "x"},
                                     {"nope": 1}])
def test_bad_options_are_named(options):
    robot = fw.load_robot("youbot_arm")
    with pytest.raises(fw.SolverError, match=next(iter(options))):
        fw.solve(fw.Problem(robot, 1.0 * fw.Position("ee", [0.2, 0.0, 0.3])), "pinv", options=options)
