"""Mistakes that used to pass silently are our errors, naming the problem (API and task files)."""

from __future__ import annotations

import pytest

import framework as fw
from framework.cli import EXIT_INPUT, main
from framework.errors import LimitsError, TaskError, UnknownJointError
from tests.conftest import same_framework_env, without_compile_notices


@pytest.mark.parametrize("kwargs, error, message", [
    (dict(joints=["joint1", "joint2"], locked={"joint2": 0.1}), UnknownJointError, "both solved"),
    (dict(joints=["joint1", "joint2"], groups={"g": ["joint3"]}), UnknownJointError, "names \\['joint3'\\]"),
    (dict(joints=["joint1"], locked={"joint2": 10.0}), LimitsError, "outside its limits"),
    (dict(joints=["joint1"], locked={"joint2": float("nan")}), LimitsError, "must be finite"),
    (dict(joints=["joint1"], locked={"joint2": "x"}), LimitsError, "must be a number"),
    (dict(joints=["joint1", "dh1"]), UnknownJointError, "'dh1' is a fixed joint"),
    (dict(joints=[]), UnknownJointError, "nothing to solve"),
], ids=["solved and locked", "group of an unsolved joint", "locked out of limits", "locked NaN", "locked text",
        "fixed joint", "no joint"])
def test_robot_loading_mistakes(kwargs, error, message):
    with pytest.raises(error, match=message):
        fw.load_robot("youbot_arm", **kwargs)


def test_index_groups_keep_the_solved_joints():
    robot = fw.load_robot("youbot_dual_mobile", joints=["arm1_joint1", "arm1_joint2"])
    assert list(robot.groups) == ["arm1"] and robot.group("arm1").tolist() == [0, 1]


TASK = """
[task]
name = "t"
robot = "youbot_arm"
EXTRA
[[terms]]
type = "position"
frame = "ee"
target = [0.3, 0.0, 0.3]
"""


@pytest.mark.parametrize("extra, message", [
    ('joint = ["joint1"]', "\\[task\\] has unknown keys \\['joint'\\]"),
    ('[solvr]\nname = "de"', "unknown tables \\['solvr'\\]"),
    ('[solver]\npopulaton = 5', "\\[solver\\] has unknown keys \\['populaton'\\]"),
    ('[previous]\narm = [0, 0, 0, 0, 0]\n[cases]', "cases"),
    ('bounds = {joint1 = 1.0}', "\\[task\\] bounds.joint1 must be a pair \\[lower, upper\\]"),
    ('bounds = {joint1 = [1, 2, 3]}', "\\[task\\] bounds.joint1 must be a pair"),
    ('[solver]\nname = "de"\noptions = {F = "abc"}', "\\[solver\\] option 'F' of solver 'de' must be a finite number"),
    ('[solver]\nname = "hybrid"\noptions = {global_solver = "nope"}', "\\[solver\\] Unknown solver 'nope'"),
    ('[solver]\ntolerance = -1.0', "\\[solver\\] tolerance must be a positive number"),
], ids=["task key typo", "table typo", "solver key typo", "a table where cases go", "bounds a scalar",
        "bounds a triple", "an option of the wrong kind", "an unknown global solver", "a negative tolerance"])
def test_task_file_mistakes_name_the_table_and_key(tmp_path, capsys, extra, message):
    path = tmp_path / "t.toml"
    text = TASK.replace("EXTRA", extra) if extra.startswith(("joint", "bounds")) else TASK.replace("EXTRA", "") + extra
    path.write_text(text)
    from framework.io.taskfile import load_task

    with pytest.raises(TaskError, match=message):
        load_task(path)
    assert main(["run", str(path)]) == EXIT_INPUT
    err = without_compile_notices(capsys.readouterr().err)
    assert err.count("\n") == 1 and str(path) in err  # one line, naming the file


def test_task_files_take_groups(tmp_path):
    from framework.io.taskfile import load_task

    path = tmp_path / "t.toml"
    path.write_text(TASK.replace("EXTRA", 'groups = { wrist = ["joint4", "joint5"] }'))
    assert load_task(path).robot.group("wrist").tolist() == [3, 4]


def test_ctrl_c_in_a_multi_case_run_stops_it_and_is_never_success(tmp_path):
    """SIGINT during the first of four cases: exit 130, that case shown and not a success, the others not run."""
    import signal
    import subprocess
    import sys
    import time

    from framework.io.taskfile import load_task, resolve_task

    case = load_task(resolve_task("youbot_dual_coordinated_ik")).cases[0]
    fw.solve(case.problem, "cmaes", max_iterations=2)  # compiles what the run needs (numba's cache is shared)
    env = same_framework_env(PYTHONUNBUFFERED="1")  # this process's framework: the same cache
    process = subprocess.Popen([sys.executable, "-m", "framework.cli", "run", "youbot_dual_coordinated_ik",
                                "--solver", "cmaes", "--iterations", "200000"], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, cwd=tmp_path, env=env)
    header = process.stdout.readline()  # printed just before the first case starts
    assert "youbot_dual_coordinated_ik" in header, header
    import psutil  # (with dask's distributed, a test dependency)

    child, start = psutil.Process(process.pid), time.monotonic()
    begun = sum(child.cpu_times()[:2])
    # 4 s of the child's CPU past its header: its first solve loads the compiled code from numba's cache (1-2 s of
    # CPU on a loaded CI machine, where a signal lands before the case begins), then runs the first case's
    # 200,000 generations (~3 minutes in all), however loaded the machine is
    while sum(child.cpu_times()[:2]) < begun + 4.0 and time.monotonic() - start < 90:
        time.sleep(0.1)
    process.send_signal(signal.SIGINT)
    try:
        out, err = process.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        process.kill()
        out, err = process.communicate()
        raise AssertionError(f"SIGINT did not stop the run within 120 s; its output: {header + out}\n{err}")
    out = header + out
    assert process.returncode == 130, (out, err)
    assert "interrupted during 'target 1'" in err and "1 of 4 cases" in err
    success_row = next(line for line in out.splitlines() if line.startswith("│ success"))
    assert "no" in success_row and "yes" not in success_row
    assert "target 2" not in out


def test_previous_must_be_a_table(tmp_path, capsys):
    path = tmp_path / "t.toml"
    path.write_text("previous = 3\n" + TASK.replace("EXTRA", ""))
    assert main(["run", str(path)]) == EXIT_INPUT
    assert "previous must be a [previous] table; got 3" in without_compile_notices(capsys.readouterr().err)


def test_output_and_bench_folders_are_checked_before_anything_runs(tmp_path, capsys):
    """metaik bench --out on a file and --doc under a file are one-line errors (exit 2); metaik run --output of an
    IK task writes its cases (its folder made)."""
    path = tmp_path / "t.toml"
    path.write_text(TASK.replace("EXTRA", "") + '[solver]\nname = "hybrid"\n')
    a_file = tmp_path / "a_file"
    a_file.write_text("")
    assert main(["bench", str(path), "--out", str(a_file)]) == EXIT_INPUT
    assert "is a file, not a folder" in capsys.readouterr().err
    assert main(["bench", str(path), "--doc", str(a_file / "x.md")]) == EXIT_INPUT
    assert "is a file, not a folder" in capsys.readouterr().err
    out = tmp_path / "no" / "such" / "x.csv"
    assert main(["run", str(path), "--output", str(out)]) == 0
    rows = out.read_text().splitlines()
    assert rows[0].startswith("case,success,task_error,cost,") and rows[1].startswith("t,True,")


@pytest.mark.parametrize("make, error, message", [
    (lambda r: r.frame_poses(["a", "b"]), fw.ConfigurationError, "must be numbers"),
    (lambda r: __import__("numpy").array([1.0, 2.0]) * fw.Position("ee", [0.3, 0, 0.3]), TaskError,
     "a cost weight must be a finite number"),
    (lambda r: r.with_bounds({"joint1": 1.0}), LimitsError, "must be a pair"),
    (lambda r: fw.solve(fw.Problem(r, fw.Position("ee", [0.3, 0, 0.3])), "de", options={"F": "abc"}),
     fw.SolverError, "option 'F' of solver 'de' must be a finite number"),
    (lambda r: fw.solve(fw.Problem(r, fw.Position("ee", [0.3, 0, 0.3])), options={"global_solver": "nope"}),
     fw.SolverError, "Unknown solver 'nope'"),
], ids=["poses of strings", "an array as a weight", "bounds a scalar", "an option of the wrong kind",
        "an unknown global solver"])
def test_python_mistakes_are_library_errors(make, error, message):
    with pytest.raises(error, match=message):
        make(fw.load_robot("youbot_arm"))


def test_a_batch_leaves_the_users_terms_as_they_were():
    """solve_batch solves its items on its own copies of the targeted terms: the problem's term keeps its target."""
    import numpy as np

    robot = fw.load_robot("youbot_arm")
    term = fw.Position("ee", [0.3, 0.0, 0.3])
    problem = fw.Problem(robot, term)
    before = (term.target.copy(), term.version)
    fw.solve_batch(problem, np.array([[0.25, 0.05, 0.3], [5.0, 0.0, 0.0]]), "de", max_iterations=3)
    assert np.array_equal(term.target, before[0]) and term.version == before[1]
