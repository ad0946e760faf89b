"""Algorithm 2 (intermediate configurations) and path tracking: steps of at most ρ, never in or across the
rejection area."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import shapely.geometry as sg
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import framework as fw
from framework.solvers.fabrik import Environment, MFabrik, MobileArm
from framework.solvers.fabrik.environment import Circle, Polygon
from framework.solvers.fabrik.steps import intermediate_configurations, shortest_free_path
from framework.solvers.fabrik.steps import algorithm2
from framework.tracking import track
from framework.tracking.trajectory import Trajectory

BOX = ((-1.5, 1.5), (-1.5, 1.5))


def Rectangle(centre, size, angle=0.0) -> Polygon:
    """A rectangular floor shadow: centre (x, y) [m], size (along x, along y) [m], turned by ``angle`` [rad]."""
    (cx, cy), (w, d) = centre, size
    c, s = math.cos(angle), math.sin(angle)
    corners = [(-w / 2, -d / 2), (w / 2, -d / 2), (w / 2, d / 2), (-w / 2, d / 2)]
    return Polygon(tuple((cx + c * u - s * v, cy + s * u + c * v) for u, v in corners))


@pytest.fixture(scope="module")
def robot() -> fw.Robot:
    return fw.load_robot("youbot_mobile")


@pytest.fixture(scope="module")
def arm(robot) -> MobileArm:
    return MobileArm.from_robot(robot)


def assert_free_steps(env: Environment, bases: np.ndarray, step: float) -> None:
    lengths = np.linalg.norm(np.diff(bases, axis=0), axis=1)
    assert np.all(lengths <= step + 1e-12)
    for a, b in itertools.pairwise(bases):
        assert not env.rejection.intersects(sg.LineString([tuple(a), tuple(b)]))
        assert env.clearance(*b) >= env.margin


def configuration_at(robot: fw.Robot, base: tuple[float, float]) -> np.ndarray:
    x = np.zeros(robot.n)
    x[:2] = base
    return x


def test_steps_go_around_an_l_shaped_obstacle(robot, arm):
    """Behind a concave obstacle, heading straight for the goal would stall; the steps go round it."""
    wall = Polygon(((-0.2, -0.8), (0.2, -0.8), (0.2, 0.8), (-0.6, 0.8), (-0.6, 0.5), (-0.2, 0.5)))
    env = Environment([wall], margin=0.2, bounds=BOX)
    solver = MFabrik(arm, env)
    previous, new = configuration_at(robot, (-0.5, 0.0)), configuration_at(robot, (1.0, 0.0))
    steps = intermediate_configurations(solver, previous, new, np.array([1.2, 0.0, 0.3]), step=0.1)
    assert steps.success and steps.reason == "steps"
    np.testing.assert_allclose(steps.bases[[0, -1]], [(-0.5, 0.0), (1.0, 0.0)])
    assert_free_steps(env, steps.bases, 0.1)
    assert len(steps.configurations) == len(steps.bases) - 2
    np.testing.assert_allclose(steps.configurations[:, :2], steps.bases[1:-1], atol=1e-12)
    path_length = np.linalg.norm(np.diff(steps.bases, axis=0), axis=1).sum()
    assert path_length > 1.5 + 0.4  # longer than the straight line: it went round


def test_near_positions_need_no_steps(robot, arm):
    solver = MFabrik(arm, Environment(bounds=BOX))
    steps = intermediate_configurations(
        solver,
        configuration_at(robot, (0, 0)),
        configuration_at(robot, (0.05, 0)),
        np.array([0.5, 0, 0.3]),
        0.1,
    )
    assert steps.success and steps.reason == "direct" and steps.configurations.shape == (0, robot.n)


def test_enclosed_goal_has_no_path(robot, arm):
    ring = [
        Circle((0.6 * math.cos(a), 0.6 * math.sin(a)), 0.25)
        for a in np.linspace(0, 2 * math.pi, 12, endpoint=False)
    ]
    env = Environment(ring, margin=0.2, bounds=BOX)
    assert shortest_free_path(env, np.zeros(2), np.array([1.3, 1.3])) is None
    steps = intermediate_configurations(
        MFabrik(arm, env),
        configuration_at(robot, (0, 0)),
        configuration_at(robot, (1.3, 1.3)),
        np.array([1.3, 1.3, 0.3]),
        0.1,
    )
    assert not steps.success and steps.configurations.shape == (0, robot.n)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    centres=st.lists(st.tuples(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0)), min_size=1, max_size=4),
    sizes=st.lists(st.tuples(st.floats(0.05, 0.6), st.floats(0.05, 0.6)), min_size=4, max_size=4),
    ends=st.tuples(*[st.floats(-1.45, 1.45)] * 4),
    step=st.floats(0.05, 0.5),
)
def test_steps_are_short_and_free(robot, arm, centres, sizes, ends, step):
    env = Environment([Rectangle(c, s) for c, s in zip(centres, sizes)], margin=0.2, bounds=BOX)
    a, b = np.array(ends[:2]), np.array(ends[2:])
    if env.in_rejection(*a) or env.in_rejection(*b):
        assert shortest_free_path(env, a, b) is None
        return
    path = shortest_free_path(env, a, b)
    if path is None:  # then a and b are in different pieces of the navigable area
        assert env.piece_of(*a) is not env.piece_of(*b) or env.piece_of(*a) is None
        return
    steps = intermediate_configurations(
        MFabrik(arm, env),
        configuration_at(robot, tuple(a)),
        configuration_at(robot, tuple(b)),
        np.array([0.0, 0.0, 0.3]),
        step,
    )
    assert steps.success
    assert_free_steps(env, steps.bases, step)


def test_tracking_a_path_past_an_obstacle(robot, arm):
    """Paper 003 experiment 2: a sinusoid over a square obstacle (a box of the scene an Obstacles term reads), 20 cm
    margin, steps of 10 cm: the solver's own steps (option ``step``) are Algorithm 2's along the path."""
    env = Environment([Rectangle((0.0, 0.0), (0.4, 0.4))], margin=0.2, bounds=BOX)
    solver = MFabrik(arm, env)
    shape = fw.RobotShape(robot)
    box = fw.Box([0.0, 0.0, 0.1], [0.4, 0.4, 0.2])

    def task(k, position, rotation, previous):
        return fw.Position("arm_ee", position) + fw.Obstacles(shape, [box])

    ys = np.linspace(-1.0, 1.0, 21)
    targets = np.column_stack([0.1 * np.sin(2 * np.pi * ys), ys, np.full_like(ys, 0.3)])
    x0 = configuration_at(robot, (-0.2, -1.3))
    states = []
    tracking = track(robot, Trajectory.from_array(targets), task, solver="mfabrik", initial=x0, tolerance=1e-3,
                     max_iterations=1000, options={"step": 0.1}, progress=False,
                     callback=lambda k, result: states.append(result.state))
    reached = robot.frame_poses(tracking.configurations, "arm_ee").positions[:, 0]  # Pinocchio FK
    assert np.linalg.norm(reached - targets, axis=1).max() <= 1e-3
    expected = algorithm2(solver, x0, tracking.configurations, targets, 0.1)
    for steps, state in zip(expected, states, strict=True):
        assert steps.success
        assert_free_steps(env, steps.bases, 0.1)
        np.testing.assert_allclose(state["steps"].bases, steps.bases, atol=1e-9)
    assert tracking.iterations.sum() < 21 * 10
