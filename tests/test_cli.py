"""The task-file format and the metaik command line: results, and every bad-input path with its exit code."""

from __future__ import annotations

import numpy as np
import pytest

import framework as fw
from framework.cli import EXIT_INPUT, EXIT_MISSED, EXIT_OK, main
from framework.resources import data_dir
from framework.io.taskfile import evaluate, load_task

TASK = data_dir("tasks") / "youbot_dual_coordinated_ik.toml"

MINIMAL = """
[task]
name = "reach"
robot = "youbot_arm"
[solver]
name = "hybrid"
[[terms]]
type = "position"
frame = "ee"
target = "p"
[[cases]]
name = "near"
p = [0.3, 0.0, 0.3]
"""


def test_paper000_task_file_matches_the_paper():
    task = load_task(TASK)
    assert [c.name for c in task.cases] == ["target 1", "target 2", "target 3", "target 4"]
    problem = task.cases[0].problem
    assert problem.names == ("e_t1", "e_t2", "e_q0", "e_q1", "e_q2")
    np.testing.assert_allclose(problem.weights, [1.2, 1.2, 0.1, 0.4, 0.4])
    e_t2 = problem.objective.terms[1][1]
    np.testing.assert_allclose(e_t2.target, [0.5 + 0.2, -0.2 - 0.3, 0.45 - 0.2])  # t*_e2 = t*_e1 + t_r
    q_prev = problem.objective.terms[2][1].previous
    np.testing.assert_allclose(q_prev[:3], [0, 0, np.pi / 2])
    np.testing.assert_allclose(q_prev[3:8], [-np.pi / 2, np.pi / 2, -np.pi / 4, np.pi / 4, 0])
    assert task.solver["population"] == 30 and task.solver["max_iterations"] == 1000


def test_expressions():
    assert evaluate("pi/2", {}, "x") == pytest.approx(np.pi / 2)
    np.testing.assert_allclose(evaluate("a + 2*b", {"a": [1, 2, 3], "b": [1, 0, -1]}, "x"), [3, 2, 1])
    np.testing.assert_allclose(evaluate("Ry(pi/2)", {}, "x") @ [1, 0, 0], [0, 0, -1], atol=1e-15)
    with pytest.raises(fw.TaskError, match="not a number/vector expression"):
        evaluate("__import__('os')", {}, "x")
    with pytest.raises(fw.TaskError, match="unknown name 'os'"):
        evaluate("os", {}, "x")
    with pytest.raises(fw.TaskError):
        evaluate("a.b", {"a": 1}, "x")


def test_run_hybrid_prints_the_table(capsys):
    assert main(["run", str(TASK), "--solver", "hybrid", "--case", "target 2"]) == EXIT_OK
    out = capsys.readouterr().out
    assert "target 2" in out and "e_t1" in out and "yes" in out


def test_a_command_that_compiled_says_how_long_and_one_that_loaded_does_not(monkeypatch, capsys):
    """A command during which compiling took time (a fresh install's first solves) says how much of its times it
    was, on stderr; one that only loaded cached code says nothing of it (each compile also says so as it begins:
    tests/test_compile_cache.py)."""
    from framework import cli
    from framework.compiled import cache as compile_cache

    def compiling_run(args, console):
        compile_cache.NOTICE.seconds += 12.0
        return EXIT_OK

    monkeypatch.setattr(cli, "run_command", compiling_run)
    assert main(["run", str(TASK)]) == EXIT_OK
    assert "include 12 s of compiling" in capsys.readouterr().err
    monkeypatch.undo()
    assert main(["run", str(TASK), "--solver", "hybrid", "--case", "target 2"]) == EXIT_OK
    assert "compiling" not in capsys.readouterr().err


def test_run_by_shipped_name_and_missed_tolerance_exit_code(tmp_path, capsys):
    path = tmp_path / "far.toml"
    path.write_text(MINIMAL.replace("[0.3, 0.0, 0.3]", "[2.0, 0.0, 0.3]"))
    assert main(["run", str(path)]) == EXIT_MISSED
    assert "no" in capsys.readouterr().out


def test_robots_and_show(capsys):
    assert main(["robots"]) == EXIT_OK
    out = capsys.readouterr().out
    assert "youbot_dual_mobile" in out and "13" in out
    assert main(["show", "youbot_dual_mobile"]) == EXIT_OK
    assert "base_theta" in capsys.readouterr().out


@pytest.mark.parametrize(
    "content, message",
    [
        (None, "does not exist"),
        ("[task\nname=", "not valid TOML"),
        (MINIMAL.replace('"youbot_arm"', '"youbot_arn"'), "unknown robot 'youbot_arn'"),
        (MINIMAL.replace('"hybrid"', '"annealing"'), "unknown solver 'annealing'"),
        (MINIMAL.replace('frame = "ee"', 'frame = "gripper"'), "no frame 'gripper'"),
        (MINIMAL.replace('target = "p"', 'target = "p"\nweight = -2'), "weight"),
        (MINIMAL.replace('target = "p"', 'target = "q"'), "unknown name 'q'"),
        (MINIMAL.replace("[0.3, 0.0, 0.3]", '[0.3, "nan", 0.3]'), "unknown name 'nan'"),
        (MINIMAL.replace('type = "position"', 'type = "posture"'), "unknown type 'posture'"),
        (MINIMAL.replace('name = "hybrid"', 'name = "hybrid"\npopsize = 3'), "unknown keys"),
    ],
)
def test_bad_input_is_one_line_with_exit_code_2(tmp_path, capsys, content, message):
    path = tmp_path / "task.toml"
    if content is not None:
        path.write_text(content)
    assert main(["run", str(path)]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert message in err.replace("\n", " ")
    assert "Traceback" not in err


def test_unknown_robot_in_show(capsys):
    assert main(["show", "nobot"]) == EXIT_INPUT
    assert "unknown robot" in capsys.readouterr().err


def test_help_everywhere(capsys):
    for argv in (["--help"], ["run", "--help"], ["show", "--help"], ["robots", "--help"], ["tasks", "--help"],
                 ["bench", "--help"], ["replay", "--help"]):
        with pytest.raises(SystemExit) as stop:
            main(argv)
        assert stop.value.code == 0
    assert "task" in capsys.readouterr().out


def test_run_record_writes_what_the_table_shows(tmp_path, capsys):
    from framework.io.recording import read_recording

    path = tmp_path / "run.rrd"
    argv = ["run", str(TASK), "--solver", "hybrid", "--case", "target 1", "--case", "target 3", "--record", str(path)]
    assert main(argv) == EXIT_OK
    out = capsys.readouterr().out
    recording = read_recording(path)
    assert recording.complete and {"solution", "iteration"} <= recording.timelines
    _, errors = recording.scalars("/summary/task_error", "solution")
    _, names = recording.values("/summary/name", "TextDocument:text", "solution")
    assert [n[0] for n in names] == ["target 1", "target 3"]
    row = next(line for line in out.splitlines() if "task error" in line)
    printed = [float(cell) for cell in row.split("│")[2:4]]
    np.testing.assert_allclose(errors, printed, rtol=0.01, atol=1e-15)  # the table prints 3 digits
    # the term logger is wired to solve's callback: the hybrid reports each phase (here one engine run, compiled),
    # its last trace is the solution's value
    iterations, traced = recording.scalars("/solutions/target_1/terms/e_t1", "iteration")
    assert len(iterations) >= 1 and traced[-1] == pytest.approx(errors[0] / 2, rel=0.5, abs=1e-15)
    assert main(["replay", str(path), "--summary"]) == EXIT_OK
    assert "target 3: task error" in capsys.readouterr().out
    # a metaheuristic traces every generation
    path = tmp_path / "cma.rrd"
    argv = ["run", str(TASK), "--solver", "cmaes_fast", "--case", "target 1", "--record", str(path)]
    assert main(argv) in (EXIT_OK, EXIT_MISSED)
    iterations, _ = read_recording(path).scalars("/solutions/target_1/terms/e_t1", "iteration")
    assert len(iterations) > 5


def test_replay_and_bench_bad_input_exit_2(tmp_path, capsys):
    assert main(["replay", str(tmp_path / "missing.rrd"), "--summary"]) == EXIT_INPUT
    assert "missing.rrd" in capsys.readouterr().err
    assert main(["bench", str(tmp_path / "missing.toml")]) == EXIT_INPUT
    err = capsys.readouterr().err
    assert "missing.toml" in err and "Traceback" not in err
    assert main(["run", str(TASK), "--case", "no such case"]) == EXIT_INPUT
    assert "no case named" in capsys.readouterr().err


def test_bench_through_the_command_line(tmp_path, capsys):
    path = tmp_path / "reach.toml"
    path.write_text(MINIMAL + "\n[bench]\nsolvers = [\"de\", \"hybrid\"]\nruns = 2\n")
    out = tmp_path / "out"
    argv = ["bench", str(path), "--iterations", "40", "--jobs", "1", "--out", str(out), "--no-figures"]
    assert main(argv) == EXIT_OK
    assert len((out / "results.jsonl").read_text().splitlines()) == 4
    table = capsys.readouterr().out
    assert "hybrid" in table and "de" in table


def test_solvers_lists_every_solver_with_its_defaults(capsys):
    from framework.solvers import solver_names

    assert main(["solvers"]) == EXIT_OK
    out = capsys.readouterr().out
    for name in solver_names():
        assert name in out
    assert "stall=6" in out and "sigma0=None" in out
    from framework.solvers import ik_solver

    assert all(ik_solver(name).kind for name in solver_names())  # every solver says what kind it is
    assert ik_solver("mfabrik").kind != ik_solver("de").kind != ik_solver("pinv").kind


def test_error_messages_keep_their_brackets(tmp_path, capsys):
    path = tmp_path / "no_task_table.toml"
    path.write_text('[solver]\nname = "hybrid"\n')
    assert main(["run", str(path)]) == EXIT_INPUT
    assert "missing [task] table" in capsys.readouterr().err
