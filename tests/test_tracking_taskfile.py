"""Tracking task files (``[trajectory]``) and ``metaik run`` on them: the papers' paths, exit codes, bad input."""

from __future__ import annotations

import numpy as np
import pytest

import framework as fw
from framework.tracking import paths
from framework.tracking import trajectory as tr
from tests.conftest import same_framework_env
from framework.cli import EXIT_INPUT, EXIT_MISSED, EXIT_OK, main
from framework.resources import data_dir
from framework.io.taskfile import load_task

TASKS = data_dir("tasks")

TRACK = """
[task]
name = "wave"
robot = "youbot_arm"
[solver]
name = "hybrid"
[previous]
arm = [0, 0.3, -0.6, 0.4, 0]
[trajectory]
type = "circle"
centre = [0.3, 0.0, 0.3]
radius = "r"
points = 12
[[terms]]
type = "position"
frame = "ee"
target = "t"
[[terms]]
type = "motion"
group = "all"
weight = 0.01
[[cases]]
name = "small"
r = 0.02
[[cases]]
name = "file"
r = 0.02
[cases.trajectory]
type = "file"
path = "path.csv"
"""


@pytest.mark.parametrize("path", paths.PAPER000_PATHS)
def test_paper000_task_files_are_the_papers_paths(path):
    task = load_task(TASKS / f"paper000_{path}.toml")
    case = task.cases[0]
    assert (
        task.is_tracking and task.robot.name == "youbot_dual_mobile" and task.solver["max_iterations"] == 300
    )
    np.testing.assert_allclose(case.trajectory.positions, paths.paper000(path).positions, atol=1e-15)
    np.testing.assert_allclose(case.initial[:3], [0, 0, np.pi / 2])
    objective = case.builder(5, case.trajectory.positions[5], None, case.initial)
    assert [t.name for _, t in objective] == ["e_t1", "e_t2", "e_q0", "e_q1", "e_q2"]
    np.testing.assert_allclose([w for w, _ in objective], [1.2, 1.2, 0.1, 0.4, 0.4])
    t_r = np.array([0.0, -0.3, 0.0])
    np.testing.assert_allclose(objective.terms[1][1].target, case.trajectory.positions[5] + t_r)


@pytest.mark.parametrize("robot", ["youbot", "puma", "baxter", "fanuc"])
@pytest.mark.parametrize("path", ["circle", "lemniscate"])
def test_paper002_task_files(robot, path):
    task = load_task(TASKS / f"paper002_{robot}_{path}.toml")
    case = task.cases[0]
    expected = paths.paper002(task.robot.name, path, case.trajectory.K)
    assert (32 if path == "circle" else 73) == case.trajectory.K
    np.testing.assert_allclose(case.trajectory.positions, expected.positions, atol=1e-15)
    np.testing.assert_allclose(case.trajectory.rotations, expected.rotations, atol=1e-15)
    objective = case.builder(0, expected.positions[0], expected.rotations[0], case.initial)
    np.testing.assert_allclose([w for w, _ in objective], [0.7143, 0.1786, 0.1071])
    assert objective.terms[2][1].norm == "l1"


def test_paper001_task_files():
    for name, robot in (
        ("paper001_youbot_circle", "youbot_dual"),
        ("paper001_baxter_sinusoid", "baxter_dual"),
    ):
        task = load_task(TASKS / f"{name}.toml")
        assert task.is_tracking and task.robot.name == robot and task.solver["name"] == "de"


def test_run_tracks_and_prints_the_summary(capsys):
    code = main(
        [
            "run",
            str(TASKS / "paper000_circular.toml"),
            "--solver",
            "hybrid",
            "--points",
            "15",
            "--no-progress",
        ]
    )
    out = capsys.readouterr().out
    assert code == EXIT_OK
    assert "15/15" in out and "position error, mean" in out and "max joint step" in out


def test_user_task_file_with_cases_and_a_csv_path(tmp_path, capsys):
    paths.line((0.3, 0.0, 0.25), (0.3, 0.03, 0.25), 6).to_csv(tmp_path / "path.csv")
    file = tmp_path / "wave.toml"
    file.write_text(TRACK)
    task = load_task(file)
    assert [c.trajectory.K for c in task.cases] == [12, 6]
    assert task.cases[0].trajectory.positions[0] == pytest.approx(
        [0.3, 0.02, 0.3]
    )  # plane yz, radius from the case
    output = tmp_path / "joints.csv"
    assert main(["run", str(file), "--no-progress", "--output", str(output)]) == EXIT_OK
    rows = output.read_text().splitlines()
    assert len(rows) == 1 + 12 + 6 and rows[0].startswith("case,k,joint1")
    # a budget too small for a metaheuristic misses the tolerance: exit code 1
    assert (
        main(["run", str(file), "--solver", "de", "--iterations", "2", "--case", "file", "--no-progress"])
        == EXIT_MISSED
    )
    assert load_task(file, points=4).cases[1].trajectory.K == 4


@pytest.mark.parametrize(
    ("change", "match"),
    [
        (('type = "circle"', 'type = "spiral"'), "unknown type 'spiral'"),
        (('radius = "r"', 'radius = "r"\ncolour = 1'), "unknown keys"),
        (('radius = "r"', 'radius = "-r"'), "radius"),
        (('target = "t"', "target = [0.3, 0, 0.3]"), "use the waypoint"),
        (("points = 12", "points = 1"), "points"),
        (("r = 0.02\n[[cases]]", "r = 0.02\nt = 1\n[[cases]]"), "waypoint variables"),
        (('path = "path.csv"', 'path = "missing.csv"'), "does not exist"),
    ],
)
def test_bad_trajectory_tables_exit_2(tmp_path, capsys, change, match):
    paths.line((0.3, 0.0, 0.25), (0.3, 0.03, 0.25), 6).to_csv(tmp_path / "path.csv")
    file = tmp_path / "bad.toml"
    file.write_text(TRACK.replace(*change, 1))
    with pytest.raises(fw.TaskError, match=match):
        load_task(file)
    assert main(["run", str(file)]) == EXIT_INPUT
    assert match.split("'")[0].split(" ")[0] in capsys.readouterr().err


def test_nan_in_a_csv_path_exits_2(tmp_path, capsys):
    (tmp_path / "path.csv").write_text("x,y,z\n0.3,0,0.3\n0.3,nan,0.3\n")
    file = tmp_path / "t.toml"
    file.write_text(TRACK)
    assert main(["run", str(file)]) == EXIT_INPUT
    assert "NaN" in capsys.readouterr().err


def test_a_killed_tracking_run_keeps_every_finished_waypoint(tmp_path):
    """SIGKILL midway through a slow tracking run: the CSV holds complete rows for the waypoints solved so far,
    each equal to the same waypoint of an uninterrupted run (same seed), and the recording holds their poses."""
    import os
    import signal
    import subprocess
    import sys
    import time

    env = same_framework_env()  # this process's framework: its numba cache is warm
    killed, full = tmp_path / "killed.csv", tmp_path / "full.csv"
    command = [sys.executable, "-m", "framework.cli", "run", "paper000_sinusoidal", "--solver", "cmaes",
               "--points", "60", "--no-progress", "--output"]
    process = subprocess.Popen([*command, str(killed), "--record", str(tmp_path / "killed.rrd")], env=env,
                               cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and (not killed.exists() or len(killed.read_text().splitlines()) < 4):
        time.sleep(0.05)
    os.kill(process.pid, signal.SIGKILL)
    process.wait()
    rows = killed.read_text().splitlines()
    assert 4 <= len(rows) < 61, len(rows)  # header + some waypoints, killed before the end
    subprocess.run([*command, str(full), "--record", str(tmp_path / "full.rrd")], env=env, cwd=tmp_path,
                   check=True, capture_output=True)
    reference = full.read_text().splitlines()
    assert len(reference) == 61
    assert rows[-1].count(",") == reference[0].count(",")  # no torn last row
    assert rows == reference[: len(rows)]
    from framework.io.recording import read_recording

    _, X_full, _ = read_recording(tmp_path / "full.rrd").configurations("waypoint")
    assert len(X_full) == 60  # each waypoint posed once
    recording = read_recording(tmp_path / "killed.rrd")
    assert not recording.complete
    _, X, _ = recording.configurations("waypoint")
    solved = len(rows) - 1  # waypoints in the CSV (written first, then posed in the recording)
    assert solved - 1 <= len(X) <= solved  # a kill between the two writes leaves the last one in the CSV only
    np.testing.assert_array_equal(X, X_full[: len(X)])


@pytest.mark.parametrize("motion", ["", 'previous = [0, 0.3, -0.6, 0.4, 0]'])
def test_task_file_paths_run_chained_with_the_answers_of_one_solve_per_waypoint(tmp_path, monkeypatch, motion):
    # the task file's terms know their parameters along the path: its waypoints run in compiled stretches (a
    # motion term with a `previous` of its own keeps it: only the others measure from the previous solution)
    from framework.costs.problem import Problem
    from framework.solvers.solve import solve
    from framework.tracking import FIRST_GLOBAL_ITERATIONS, chain, track

    chained = []
    follow = chain.follow_items
    monkeypatch.setattr(chain, "follow_items", lambda *a: chained.append(follow(*a)) or chained[-1])
    paths.line((0.3, 0.0, 0.25), (0.3, 0.03, 0.25), 6).to_csv(tmp_path / "path.csv")
    file = tmp_path / "wave.toml"
    file.write_text(TRACK.replace('group = "all"', 'group = "all"\n' + motion, 1))
    case = load_task(file).cases[0]
    robot = case.problem.robot
    result = track(robot, case.trajectory, case.builder, initial=case.initial, tolerance=1e-6, progress=False)
    rng, previous, reference = np.random.default_rng(0), case.initial.copy(), []
    for k in range(case.trajectory.K):  # the loop's definition: the builder's problem at each waypoint
        problem = Problem(robot, case.builder(k, case.trajectory.positions[k], case.trajectory.rotation(k), previous))
        reference.append(solve(problem, "hybrid", seed=rng, max_iterations=300, tolerance=1e-6, initial=previous[None],
                               options={"global_iterations": FIRST_GLOBAL_ITERATIONS} if k == 0 else None))
        previous = reference[-1].configuration
    assert sum(chained) == case.trajectory.K - 1
    np.testing.assert_array_equal(result.configurations, [r.configuration for r in reference])
    np.testing.assert_array_equal(result.cost, [r.cost for r in reference])
    assert result.all_success
