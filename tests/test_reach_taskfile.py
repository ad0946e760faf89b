"""Paper 003's task files through the one task-file reader: the shipped paths are the stated formulas, M-FABRIK keeps
the base's reference point out of the obstacles' dilated shadows with Algorithm 2 steps <= ρ, the exact check
reports the platform where paper 003's point model lets it touch, and bad files exit 2 with one clear line."""

from __future__ import annotations

import numpy as np
import pytest
import shapely.geometry as sg

import framework as fw
from framework.cli import EXIT_INPUT, EXIT_OK, main
from framework.io.taskfile import TaskFile, load_task
from framework.resources import data_dir
from framework.tracking import track

TASKS = data_dir("tasks")
SCENARIOS = ("square", "corridor", "l_shape")


def test_paper003_task_files_state_the_papers_setup():
    random = load_task(TASKS / "paper003_random_targets.toml")
    assert random.solver["tolerance"] == 1e-3 and random.raw["bench"]["random_reachable"] == 1000
    path = load_task(TASKS / "paper003_sinusoid.toml").cases[0]
    x = np.linspace(-1.0, 1.0, 21)
    expected = np.column_stack([x, 0.5 + 0.15 * np.sin(np.pi * x), np.full(21, 0.35)])
    np.testing.assert_allclose(path.trajectory.positions, expected, atol=1e-12)
    np.testing.assert_allclose(path.initial[3:], np.radians([0, 30, -60, 30, 0]))
    square = load_task(TASKS / "paper003_obstacles_square.toml")
    x = np.linspace(-1.2, 1.2, 21)
    np.testing.assert_allclose(square.cases[0].trajectory.positions[:, 1], 0.15 * np.sin(np.pi * x / 1.2), atol=1e-12)
    assert square.solver["options"] == {"orientation": "follow_joint1", "base_margin": 0.2, "step": 0.1}
    l_shape = load_task(TASKS / "paper003_obstacles_l_shape.toml")
    x = np.linspace(-1.2, 1.2, 25)
    np.testing.assert_allclose(l_shape.cases[0].trajectory.positions[:, 1], 0.25 * np.cos(np.pi * x / 1.2) - 0.1,
                               atol=1e-12)
    assert l_shape.solver["options"]["orientation"] == "face_target"
    assert load_task(TASKS / "paper003_obstacles_corridor.toml").solver["options"]["orientation"] == "fixed"


def _shadows(task: TaskFile) -> list:
    """Each obstacle's exact floor shadow (shapely), from its own description: independent of M-FABRIK's."""
    out = []
    for o in task.scene:
        if isinstance(o, fw.Capsule):
            out.append(sg.Point(o.center[:2]).buffer(o.radius, quad_segs=256))
        elif isinstance(o, fw.Box):  # upright boxes in these files
            out.append(sg.box(*(o.center[:2] - o.size[:2] / 2), *(o.center[:2] + o.size[:2] / 2)))
        else:
            out.append(sg.Polygon(o.points))
    return out


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_obstacle_scenarios_keep_the_base_out_and_steps_within_rho(scenario):
    """Every set-point reached (Pinocchio FK), every base position — solutions and Algorithm 2's intermediate ones —
    at least the margin from every obstacle's exact shadow, every step <= ρ; the exact check decides success (paper
    003 models the base as a point: the platform, wider than the margin, and the arm reaching over an obstacle may
    touch it, and those set-points are failures — never silently reached)."""
    task = load_task(TASKS / f"paper003_obstacles_{scenario}.toml")
    case, options = task.cases[0], task.solver["options"]
    results: list[fw.IKResult] = []
    run = track(task.robot, case.trajectory, case.builder, solver="mfabrik", initial=case.initial, tolerance=1e-3,
                options=options, progress=False, callback=lambda k, r: results.append(r))
    reached = task.robot.frame_poses(run.configurations, "arm_ee").positions[:, 0]
    assert np.linalg.norm(reached - case.trajectory.positions, axis=1).max() <= 1e-3
    steps = [r.state["steps"] for r in results]
    assert len(steps) == case.trajectory.K and all(s.success for s in steps)
    bases = np.vstack([run.configurations[:, :2], *[s.bases for s in steps]])
    shadows = _shadows(task)
    least = min(shadow.distance(sg.Point(*p)) for p in bases for shadow in shadows)
    assert least >= options["base_margin"] - 1e-6
    for s in steps:
        assert np.linalg.norm(np.diff(s.bases, axis=0), axis=1).max() <= options["step"] + 1e-9
    assert all(r.success == (not r.collisions.contacts) for r in results)  # every set-point reached: contacts decide
    assert not run.all_success or not any(r.collisions.contacts for r in results)


def test_random_targets_and_baselines_through_the_command_line(capsys):
    assert main(["run", "paper003_random_targets", "--no-progress"]) == EXIT_OK
    assert "mfabrik" in capsys.readouterr().out
    assert main(["run", "paper003_sinusoid", "--solver", "dls", "--no-progress"]) == EXIT_OK
    out = capsys.readouterr().out
    assert "21/21" in out and "dls runs with its own defaults" in out


def test_reach_run_records_the_path(tmp_path, capsys):
    from framework.io.recording import read_recording

    path = tmp_path / "reach.rrd"
    assert main(["run", "paper003_sinusoid", "--record", str(path), "--no-progress"]) == EXIT_OK
    _, errors = read_recording(path).scalars("/tracking/paper003_sinusoid/position_error", "waypoint")
    task = load_task(TASKS / "paper003_sinusoid.toml")
    case = task.cases[0]
    run = track(task.robot, case.trajectory, case.builder, solver="mfabrik", initial=case.initial, tolerance=1e-3,
                options=task.solver["options"], progress=False)
    reached = task.robot.frame_poses(run.configurations, "arm_ee").positions[:, 0]
    np.testing.assert_allclose(errors, np.linalg.norm(reached - case.trajectory.positions, axis=1), atol=1e-12)


BASE = """
[task]
robot = "youbot_mobile"
[solver]
name = "mfabrik"
[solver.options]
orientation = "fixed"
[previous]
base = [0, 0, 0]
arm = [0, 0.5, -1, 0.5, 0]
[trajectory]
type = "line"
start = [0.5, 0, 0.3]
stop = [0.6, 0, 0.3]
points = 3
[[terms]]
type = "position"
frame = "arm_ee"
target = "t"
"""


@pytest.mark.parametrize(
    "change, message",
    [
        (('orientation = "fixed"', 'orientation = "sideways"'), "orientation must be one of"),
        (('orientation = "fixed"', 'orientation = "fixed"\nspeed = 1'), "speed"),
        (('orientation = "fixed"', 'orientation = "fixed"\nstep = -0.1'), "step must be a distance > 0"),
        (("arm = [0, 0.5, -1, 0.5, 0]", "arm = [0, 0.5]"), "arm needs 5 values"),
        (('frame = "arm_ee"', 'frame = "hand"'), "hand"),
        (("[previous]", "[reach]\nrandom = 3\n[previous]"), "[reach] tables are no more"),
        (('target = "t"', 'target = "t"\n[[terms]]\ntype = "obstacles"\n[[obstacles]]\ntype = "prism"\n'
                          'points = [[0, 0], [1, 0], [0.2, 0.2], [0, 1]]\nheight = 0.3'), "convex polygon"),
        (('target = "t"', 'target = "t"\n[[terms]]\ntype = "obstacles"\n[[obstacles]]\ntype = "prism"\n'
                          'points = [[0, 0], [1, 0]]\nheight = 0.3'), ">= 3 floor points"),
    ],
)
def test_bad_reach_files_exit_2(tmp_path, capsys, change, message):
    path = tmp_path / "reach.toml"
    text = BASE.replace(*change)
    assert text != BASE
    path.write_text(text)
    assert main(["run", str(path), "--no-progress"]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_the_base_file_itself_runs(tmp_path, capsys):
    path = tmp_path / "reach.toml"
    path.write_text(BASE)
    assert main(["run", str(path), "--no-progress"]) == EXIT_OK


def test_every_shipped_task_file_loads():
    from framework.io.placement import PlacementTask

    paths = sorted(TASKS.glob("*.toml"))
    assert len(paths) >= 23
    for path in paths:
        task = load_task(path, points=5)
        assert isinstance(task, (TaskFile, PlacementTask)), path
        assert task.robot.n > 0 and task.name


@pytest.mark.parametrize("solver", ["pinv", "dls"])
def test_a_reach_path_is_each_set_point_solved_from_the_previous_solution(solver):
    """tracking.track drives a reach path exactly as a plain loop of solves warm-started from the previous solution
    would (no predictor, no spread: the baselines are deterministic, so the configurations are equal bit for bit)."""
    task = load_task(TASKS / "paper003_sinusoid.toml")
    case = task.cases[0]
    run = track(task.robot, case.trajectory, case.builder, solver=solver, initial=case.initial, tolerance=1e-3,
                max_iterations=1000, predict=False, progress=False)
    term = fw.Position("arm_ee", np.zeros(3))
    problem, x = fw.Problem(task.robot, term), case.initial
    for k, target in enumerate(case.trajectory.positions):
        term.set_target(target)
        result = fw.solve(problem, solver, initial=x, tolerance=1e-3, max_iterations=1000)
        np.testing.assert_array_equal(run.configurations[k], result.configuration)
        assert run.iterations[k] == result.iterations
        x = result.configuration
    assert run.all_success
