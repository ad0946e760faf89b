"""A frame's origin on a plane and on a line (``PointOnPlane``, ``PointOnLine``): residuals against Pinocchio's frame
positions, Jacobians and curvature against finite differences, solves that meet them strictly, task files."""

from __future__ import annotations

import numpy as np
import pytest

import framework as fw
from framework.costs import Program
from framework.engine import residuals
from framework.errors import TaskError
from framework.io.taskfile import task_from_dict

from tests.test_costs import _curvature


@pytest.fixture(scope="module")
def robot() -> fw.Robot:
    return fw.load_robot("youbot_dual_mobile")  # planar base (x, y, θ) + two 5R arms


def _line_distance(p, point, direction):
    d = np.asarray(direction) / np.linalg.norm(direction)
    v = p - point
    return float(np.linalg.norm(v - (v @ d) * d))


@pytest.mark.parametrize("make", [
    lambda: fw.PointOnPlane("arm1_ee", [0.4, -0.1, 0.3], [0.2, -0.3, 1.0]),
    lambda: fw.PointOnLine("arm2_ee", [0.4, 0.2, 0.3], [1.0, 0.5, -0.2]),
])
def test_residual_against_pinocchio_and_jacobian_and_curvature_against_differences(robot, rng, make):
    """The residual's norm is the distance to the plane (signed: the residual itself) or to the line by Pinocchio's
    frame position; the Jacobian matches central differences (a zero Jacobian misses by the frame's, order 0.1-1),
    and so does the curvature Σ μ ∇²r (of the Jacobian's transpose times μ); the value is the distance."""
    term = make()
    program = Program(robot, 1.0 * term)
    h = 1e-6
    for x in robot.random_configurations(rng, 5):
        p = robot.frame_placement(x, term.frame).translation
        r, J = residuals(program, x)
        if isinstance(term, fw.PointOnPlane):
            assert r.shape == (1,) and r[0] == pytest.approx(term.normal @ (p - term.point), abs=1e-12)
        else:
            assert r.shape == (2,)
            assert np.linalg.norm(r) == pytest.approx(_line_distance(p, term.point, term.direction), abs=1e-12)
        fd = np.column_stack([(residuals(program, x + e)[0] - residuals(program, x - e)[0]) / (2 * h)
                              for e in np.eye(robot.n) * h])
        np.testing.assert_allclose(J, fd, atol=1e-7)
        assert np.abs(J).max() > 0.05
        mu = rng.standard_normal(r.size)
        fd = np.column_stack([(residuals(program, x + e)[1].T @ mu - residuals(program, x - e)[1].T @ mu)
                              / (2 * h) for e in np.eye(robot.n) * h])
        np.testing.assert_allclose(_curvature(program, x, mu), fd, atol=1e-6)
        assert fw.Problem(robot, term).values(x[None])[0, 0] == pytest.approx(np.linalg.norm(r), abs=1e-14)


def test_solves_meet_the_plane_and_the_line_and_leave_the_rest_free(robot):
    """From the middle of the box with paper 000's motion terms, the hybrid puts one hand on a plane and the other
    on a line (by Pinocchio's FK, within 1e-9 m), and the motion terms then keep them near where they started: an
    answer at the plane point itself (what a Position term would give) is farther from the start."""
    x0 = robot.middle
    p1, p2 = robot.frame_placement(x0, "arm1_ee").translation, robot.frame_placement(x0, "arm2_ee").translation
    plane = fw.PointOnPlane("arm1_ee", p1 + [0.0, 0.0, -0.08], [0.0, 0.0, 1.0])  # 8 cm below the hand
    line = fw.PointOnLine("arm2_ee", p2 + [0.0, 0.05, 0.0], [1.0, 0.0, 0.0])  # a rail 5 cm to the side
    problem = fw.Problem(robot, plane + line + 0.1 * fw.Motion("all", x0))
    result = fw.solve(problem, seed=0, tolerance=1e-9)
    assert result.success, result.errors
    x = result.configuration
    q1, q2 = robot.frame_placement(x, "arm1_ee").translation, robot.frame_placement(x, "arm2_ee").translation
    assert abs(q1[2] - plane.point[2]) <= 1e-9
    assert _line_distance(q2, line.point, line.direction) <= 1e-9
    pinned = fw.solve(fw.Problem(robot, fw.Position("arm1_ee", plane.point) + line + 0.1 * fw.Motion("all", x0)),
                      seed=0, tolerance=1e-9)
    assert pinned.success and result.terms["motion[all]"] < pinned.terms["motion[all]"]


def test_moved_targets_and_bad_input(robot):
    term = fw.PointOnPlane("arm1_ee", [0, 0, 0.3], [0, 0, 2])
    np.testing.assert_allclose(term.normal, [0, 0, 1])
    problem = fw.Problem(robot, term)
    x = robot.middle
    z = robot.frame_placement(x, "arm1_ee").translation[2]
    assert problem.program.task_errors(x)[0] == pytest.approx(abs(z - 0.3), abs=1e-12)
    term.set_target(([0, 0, 0.5], [0, 0, 1]))  # moved in place: the problem re-reads it
    assert problem.program.task_errors(x)[0] == pytest.approx(abs(z - 0.5), abs=1e-12)
    with pytest.raises(TaskError, match="normal"):
        fw.PointOnPlane("arm1_ee", [0, 0, 0], [0, 0, 0])
    with pytest.raises(TaskError, match="direction"):
        fw.PointOnLine("arm1_ee", [0, 0, 0], [np.nan, 0, 1])
    with pytest.raises(TaskError, match="point"):
        fw.PointOnLine("arm1_ee", [0, 0], [0, 0, 1])


def test_plane_and_line_in_a_task_file():
    """``point_on_plane`` and ``point_on_line`` entries with expressions, as the registry reads them; an unknown key
    names the keys the type takes."""
    raw = {"task": {"name": "plane", "robot": "youbot_dual_mobile"},
           "terms": [{"type": "point_on_plane", "frame": "arm1_ee", "point": "table", "normal": [0, 0, 1]},
                     {"type": "point_on_line", "frame": "arm2_ee", "point": [0.5, 0.0, 0.4], "direction": "rail"},
                     {"type": "motion", "group": "all", "weight": 0.1}],
           "cases": [{"name": "one", "table": [0.5, 0.0, 0.35], "rail": [0, 1, 0]}]}
    task = task_from_dict(raw, "plane.toml")
    problem = task.cases[0].problem
    plane, line = problem.objective.terms[0][1], problem.objective.terms[1][1]
    assert isinstance(plane, fw.PointOnPlane) and plane.point.tolist() == [0.5, 0.0, 0.35]
    assert isinstance(line, fw.PointOnLine) and line.direction.tolist() == [0.0, 1.0, 0.0]
    assert fw.solve(problem, seed=0).success
    raw["terms"][0]["normals"] = [0, 0, 1]
    with pytest.raises(TaskError, match=r"unknown keys \['normals'\].*takes .*'normal'"):
        task_from_dict(raw, "plane.toml")
