"""FABRIK on fixed-base chains: reaches reachable targets, and its joint angles reproduce its positions in Pinocchio."""

from __future__ import annotations

import numpy as np
import pytest

import framework as fw
from framework.errors import TaskError
from framework.solvers.fabrik import Fabrik, PlanarChain
from framework.solvers.fabrik.progress import Progress
from tests.test_fabrik_chain import PLANAR_3R


def load(name: str) -> fw.Robot:
    return fw.robot_from_urdf(PLANAR_3R) if name == "planar3r" else fw.load_robot(name)


@pytest.mark.parametrize(("name", "rate"), [("youbot_arm", 0.97), ("planar3r", 1.0), ("puma560", 0.9)])
def test_reaches_reachable_targets_to_a_micrometre(name, rate, rng):
    """Targets are forward kinematics of random configurations within limits, starts are random too."""
    robot = load(name)
    solver = Fabrik(PlanarChain.from_robot(robot))
    frame = robot.end_effectors[0]
    results = []
    for _ in range(60):
        x_target, x0 = robot.random_configurations(rng, 2)
        target = robot.frame_placement(x_target, frame).translation
        result = solver.solve(target, x0, tolerance=1e-6)
        reached = robot.frame_placement(result.configuration, frame).translation
        assert result.position_error == pytest.approx(np.linalg.norm(reached - target), abs=1e-12)
        assert np.all(result.configuration >= robot.lower) and np.all(result.configuration <= robot.upper)
        results.append(result)
    assert np.mean([r.success for r in results]) >= rate
    for r in results:
        assert r.success == (r.position_error <= 1e-6)
        assert (r.reason == "converged") == r.success


def test_internal_error_is_pinocchios_error(rng):
    """The error FABRIK tracks on its points equals Pinocchio's at the returned angles: conversion is exact."""
    robot = fw.load_robot("youbot_arm")
    solver = Fabrik(PlanarChain.from_robot(robot))
    for _ in range(20):
        x_target, x0 = robot.random_configurations(rng, 2)
        target = robot.frame_placement(x_target, "ee").translation
        result = solver.solve(target, x0, tolerance=1e-6, max_iterations=3)
        assert result.iterations <= 3
        assert result.error_history.min() == pytest.approx(result.position_error, abs=1e-12)


def test_passive_wrist_roll_keeps_its_value(rng):
    robot = fw.load_robot("youbot_arm")
    solver = Fabrik(PlanarChain.from_robot(robot))
    x_target, x0 = robot.random_configurations(rng, 2)
    result = solver.solve(robot.frame_placement(x_target, "ee").translation, x0)
    assert result.configuration[4] == x0[4]


def test_fixed_base_of_a_mobile_robot_stays(rng):
    """With joints='arm', the base joints hold their start values and the root placement follows them."""
    robot = fw.load_robot("youbot_mobile")
    solver = Fabrik(PlanarChain.from_robot(robot, joints="arm"))
    x_target, x0 = robot.random_configurations(rng, 2)
    x_target[:3] = x0[:3]  # a target the arm can reach from where the base stands
    result = solver.solve(robot.frame_placement(x_target, "arm_ee").translation, x0, tolerance=1e-6)
    np.testing.assert_array_equal(result.configuration[:3], x0[:3])
    assert result.success


def test_out_of_reach_target_is_reported_without_iterating():
    robot = fw.load_robot("youbot_arm")
    result = Fabrik(PlanarChain.from_robot(robot)).solve([2.0, 0.0, 0.3], np.zeros(robot.n))
    assert not result.success and result.reason.startswith("unreachable")
    assert result.iterations == 1  # the single stretch towards the target
    assert result.position_error > 1.0


def test_bad_target_is_refused():
    robot = fw.load_robot("youbot_arm")
    with pytest.raises(TaskError):
        Fabrik(PlanarChain.from_robot(robot)).solve([np.nan, 0.0, 0.3], np.zeros(robot.n))


def test_progress_restarts_then_finishes_the_best_attempt():
    progress = Progress(
        tolerance=1e-6, max_iterations=100, window=3, restarts=1, history=[1.0, 0.9, 0.9, 0.9]
    )
    assert progress.decide() == "restart"
    progress.history += [0.8, 0.8, 0.8]
    assert progress.decide() == "resume"
    progress.history += [0.7, 0.6, 0.5]
    assert progress.decide() == "continue"  # slow but steady while finishing
    progress.history += [0.5, 0.5, 0.5]
    assert progress.decide() == "stalled"
