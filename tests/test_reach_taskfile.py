"""Reach task files (paper 003): the shipped paths are the stated formulas, runs keep the base out of the rejection
area with Algorithm 2 steps <= ρ, and bad files exit 2 with one clear line."""

from __future__ import annotations

import numpy as np
import pytest

from framework.cli import EXIT_INPUT, EXIT_OK, main
from framework.solvers.fabrik import BaseOrientation
from framework.io.fabrik_tasks import ReachTask, run_reach_task
from framework.resources import data_dir
from framework.io.taskfile import load_task

TASKS = data_dir("tasks")
SCENARIOS = ("square", "corridor", "l_shape")


def test_paper003_task_files_state_the_papers_setup():
    random = load_task(TASKS / "paper003_random_targets.toml")
    assert isinstance(random, ReachTask) and random.random == 1000 and random.solver["tolerance"] == 1e-3
    path = load_task(TASKS / "paper003_sinusoid.toml")
    x = np.linspace(-1.0, 1.0, 21)
    expected = np.column_stack([x, 0.5 + 0.15 * np.sin(np.pi * x), np.full(21, 0.35)])
    np.testing.assert_allclose(path.targets, expected, atol=1e-12)
    np.testing.assert_allclose(path.start[3:], np.radians([0, 30, -60, 30, 0]))
    square = load_task(TASKS / "paper003_obstacles_square.toml")
    x = np.linspace(-1.2, 1.2, 21)
    np.testing.assert_allclose(square.targets[:, 1], 0.15 * np.sin(np.pi * x / 1.2), atol=1e-12)
    assert square.environment.margin == 0.2 and square.step == 0.1
    l_shape = load_task(TASKS / "paper003_obstacles_l_shape.toml")
    x = np.linspace(-1.2, 1.2, 25)
    np.testing.assert_allclose(l_shape.targets[:, 1], 0.25 * np.cos(np.pi * x / 1.2) - 0.1, atol=1e-12)
    assert l_shape.orientation is BaseOrientation.FACE_TARGET
    assert load_task(TASKS / "paper003_obstacles_corridor.toml").orientation is BaseOrientation.FIXED


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_obstacle_scenarios_keep_the_base_out_and_steps_within_rho(scenario):
    task = load_task(TASKS / f"paper003_obstacles_{scenario}.toml")
    run = run_reach_task(task)
    assert all(r.success for r in run.results) and run.success and len(run.steps) == len(task.targets)
    reached = np.array([task.robot.frame_placement(r.configuration, task.frame).translation for r in run.results])
    assert np.linalg.norm(reached - task.targets, axis=1).max() <= 1e-3  # Pinocchio FK, not the solver's word
    assert not any(task.environment.in_rejection(*p) for p in run.base_positions)
    for steps in run.steps:
        assert np.linalg.norm(np.diff(steps.bases, axis=0), axis=1).max() <= task.step + 1e-9


def test_random_targets_and_baselines_through_the_command_line(capsys):
    assert main(["run", "paper003_random_targets", "--points", "30", "--no-progress"]) == EXIT_OK
    out = capsys.readouterr().out
    assert "30/30" in out and "mfabrik" in out
    main(["run", "paper003_sinusoid", "--solver", "dls"])
    assert "21" in capsys.readouterr().out


def test_reach_run_records_the_path(tmp_path, capsys):
    from framework.io.recording import read_recording

    path = tmp_path / "reach.rrd"
    assert main(["run", "paper003_sinusoid", "--record", str(path)]) == EXIT_OK
    _, errors = read_recording(path).scalars("/tracking/paper003_sinusoid/position_error", "waypoint")
    task = load_task(TASKS / "paper003_sinusoid.toml")
    expected = run_reach_task(task).position_errors
    np.testing.assert_allclose(errors, expected)


BASE = """
[task]
robot = "youbot_mobile"
[reach]
orientation = "fixed"
start = { base = [0, 0, 0], arm = [0, 0.5, -1, 0.5, 0] }
[reach.trajectory]
type = "line"
start = [0.5, 0, 0.3]
stop = [0.6, 0, 0.3]
points = 3
"""


@pytest.mark.parametrize(
    "change, message",
    [
        (('orientation = "fixed"', 'orientation = "sideways"'), "orientation must be one of"),
        (('orientation = "fixed"', 'orientation = "fixed"\nrandom = 10'), "either random"),
        (('orientation = "fixed"', 'orientation = "fixed"\nspeed = 1'), "unknown keys ['speed']"),
        (("start = { base = [0, 0, 0], arm = [0, 0.5, -1, 0.5, 0] }", ""), "needs a start"),
        (("arm = [0, 0.5, -1, 0.5, 0]", "arm = [0, 0.5]"), "start.arm needs 5 values"),
        (('robot = "youbot_mobile"', 'robot = "youbot_mobile"\nframe = "hand"'), "no frame 'hand'"),
        (('robot = "youbot_mobile"', 'robot = "youbot_arm"'), "no joint group 'base'"),
        (("[reach]", '[solver]\nname = "cmaes"\n[reach]'), "reach tasks are solved by"),
        (("[reach]", "[reach]\nstep = -0.1"), "step must be > 0"),
        (("[reach.trajectory]", '[reach.environment]\nobstacles = [{ type = "cone" }]\n[reach.trajectory]'),
         "type must be one of"),
        (("[reach.trajectory]", "[reach.environment]\nbounds = [[1, -1], [0, 1]]\n[reach.trajectory]"),
         "min < max"),
    ],
)
def test_bad_reach_files_exit_2(tmp_path, capsys, change, message):
    path = tmp_path / "reach.toml"
    path.write_text(BASE.replace(*change))
    assert main(["run", str(path)]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert message in err and str(path) in err and "Traceback" not in err


def test_the_base_file_itself_runs(tmp_path, capsys):
    path = tmp_path / "reach.toml"
    path.write_text(BASE)
    assert main(["run", str(path)]) == EXIT_OK


def test_every_shipped_task_file_loads():
    from framework.io.placement import PlacementTask
    from framework.io.taskfile import TaskFile

    paths = sorted(TASKS.glob("*.toml"))
    assert len(paths) >= 23
    for path in paths:
        task = load_task(path, points=5)
        assert isinstance(task, (TaskFile, ReachTask, PlacementTask)), path
        assert task.robot.n > 0 and task.name


def test_a_baseline_task_run_with_mfabrik_keeps_its_algorithm_2_step(tmp_path):
    path = tmp_path / "reach.toml"
    path.write_text(BASE.replace("[reach]", '[solver]\nname = "dls"\n[reach]\nstep = 0.02'))
    task = load_task(path)
    assert task.step == 0.02
    assert run_reach_task(task).steps is None  # the baselines do not plan base steps
    steps = run_reach_task(task, solver="mfabrik").steps
    assert all(s is not None and s.longest_step <= 0.02 + 1e-9 for s in steps)


@pytest.mark.parametrize("solver", ["pinv", "dls"])
def test_a_reach_path_is_each_set_point_solved_from_the_previous_solution(solver):
    """tracking.track drives a reach path exactly as a plain loop of solves warm-started from the previous solution
    would (no predictor, no spread: the baselines are deterministic, so the configurations are equal bit for bit)."""
    task = load_task(TASKS / "paper003_sinusoid.toml")
    run = run_reach_task(task, solver=solver)
    solve_one, x = task.solve_function(solver), task.start
    for k, target in enumerate(task.targets):
        result = solve_one(target, x, tolerance=1e-3, max_iterations=1000)
        np.testing.assert_array_equal(run.configurations[k], result.configuration)
        assert run.iterations[k] == result.iterations
        x = result.configuration
    assert run.position_errors.max() <= 1e-3 and run.success
