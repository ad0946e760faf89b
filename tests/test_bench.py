"""framework.bench: the grid from task files, resumable runs, determinism, tables, figures and the command."""

from __future__ import annotations

import argparse
import dataclasses
import io
import json
from pathlib import Path

import numpy as np
import pytest
from rich.console import Console

from framework.bench import (
    RunRecord,
    downsample,
    drop_runs,
    expand_task,
    grid_records,
    plan,
    random_reachable_cases,
    read_results,
    run_grid,
    write_report,
)
from framework.cli.bench import add_bench_command
from framework.errors import TaskError
from framework.resources import data_dir
from framework.bench.stats import sign_rows, summary_rows
from tests.conftest import same_framework_env
from tests.processes import alive, children

SMALL = """
[task]
name = "small"
robot = "youbot_arm"

[solver]
name = "de"
population = 10
max_iterations = 15

[bench]
solvers = ["de", "pso"]
runs = 3
seed = 5
reference = "de"

[[terms]]
type = "position"
frame = "ee"
target = "p"
weight = 1.0

[[terms]]
type = "motion"
group = "arm"
weight = 0.1

[[cases]]
name = "near"
p = [0.3, 0.0, 0.3]

[[cases]]
name = "far"
p = [0.2, 0.2, 0.4]
"""


@pytest.fixture
def small(tmp_path) -> Path:
    path = tmp_path / "small.toml"
    path.write_text(SMALL)
    return path


def _lines(path: Path) -> list[str]:
    return path.read_text().splitlines()


def _without_time(record: RunRecord) -> dict:
    return {k: v for k, v in dataclasses.asdict(record).items() if k not in ("wall_time", "cpu_time")}


def test_plan_reads_the_bench_table_and_command_line_overrides(small):
    grid = plan([small])
    assert len(grid.specs) == 2 * 2 * 3
    assert {s.solver for s in grid.specs} == {"de", "pso"} and {s.seed for s in grid.specs} == {5, 6, 7}
    assert grid.reference == "de" and grid.group_by == "case"
    assert [s.seed for s in grid.specs[:4]] == [
        5
    ] * 4  # seed-major: a partial grid covers every solver and case
    budget = json.loads(grid.specs[0].budget)
    assert (budget["population"], budget["max_iterations"]) == (10, 15)
    grid = plan([small], solvers=["cs"], runs=2, seed=0, max_iterations=7, cases=["far"])
    assert [(s.case, s.solver, s.seed) for s in grid.specs] == [("far", "cs", 0), ("far", "cs", 1)]
    assert json.loads(grid.specs[0].budget)["max_iterations"] == 7


def test_bad_bench_tables_name_the_file_and_the_entry(tmp_path, small):
    bad = tmp_path / "bad.toml"
    bad.write_text(SMALL.replace("runs = 3", "runz = 3"))
    with pytest.raises(TaskError, match=r"bad\.toml.*unknown keys \['runz'\]"):
        plan([bad])
    with pytest.raises(TaskError, match="unknown solver"):
        plan([small], solvers=["simplex"])
    with pytest.raises(TaskError, match="no case"):
        plan([small], cases=["nowhere"])


def test_random_reachable_cases_are_reachable_deterministic_and_mapped_onto_each_system():
    path = data_dir("tasks") / "paper001_cooperative_ik.toml"
    task = expand_task(path)
    systems = {c.system: c.problem.robot.name for c in task.cases}
    assert systems == {
        "youBot arms": "youbot_dual",
        "Stanford arms": "stanford_dual",
        "Baxter arms": "baxter_dual",
        "Puma 560 + SCARA": "puma_scara",
    }
    assert len(task.cases) == 4 * 50
    for case in task.cases[::17]:
        evaluation = case.problem.evaluate(np.array(case.variables["q_ref"]))
        assert evaluation.task_error[0] < 1e-12  # the target is the FK of q_ref: reachable
        assert evaluation.term("joint_limits")[0] == 0.0  # q_ref is within the limits
    rng = np.random.default_rng([1, 0])  # case_seed = 1, first system: the same points again
    again = random_reachable_cases(task.cases[0].problem.robot, 50, rng)
    assert [{k: v for k, v in c.items() if k != "name"} for c in again] == [
        c.variables for c in task.cases[:50]
    ]
    points = [c.variables["t_ee1"] for c in task.cases if c.system in ("youBot arms", "Baxter arms")]
    assert len({tuple(p) for p in points}) == 100


def test_systems_with_their_own_cases():
    task = expand_task(data_dir("tasks") / "paper002_single_pose.toml")
    assert [(c.system, c.problem.robot.name, c.variables["t_d"]) for c in task.cases] == [
        ("youBot", "youbot_arm", [0.3, 0.2359, 0.5348]),
        ("Puma 560", "puma560", [0.5, 0.0, 0.7]),
        ("Baxter", "baxter_arm", [0.6, 0.6, 0.8]),
        ("Fanuc AM120iB", "fanuc_am120ib", [1.4, 0.0, 0.75]),
    ]
    assert task.cases[2].problem.names == ("d_err", "q_err", "r_err")


def test_an_interrupted_grid_resumes_without_repeating_finished_runs(small, tmp_path):
    grid = plan([small])
    results = tmp_path / "results.jsonl"
    first = run_grid(grid, results, jobs=1, max_runs=5, progress=False)
    assert (first.completed, first.skipped, first.interrupted) == (5, 0, False)
    assert len(_lines(results)) == 5
    # a crash tore the last line: that run is dropped and done again, nothing else is repeated
    results.write_text(results.read_text()[:-40])
    second = run_grid(grid, results, jobs=1, progress=False)
    assert (second.completed, second.skipped) == (len(grid.specs) - 4, 4)
    records = read_results(results)
    assert len(records) == len(_lines(results)) == len(grid.specs)
    assert {r.key for r in records} == grid.keys
    third = run_grid(grid, results, jobs=1, progress=False)
    assert (third.completed, third.skipped) == (0, len(grid.specs))
    # after a code change, some runs are dropped and done again; the others stay
    pso = {s.key for s in grid.specs if s.solver == "pso"}
    assert drop_runs(results, pso) == len(pso)
    fourth = run_grid(grid, results, jobs=1, progress=False)
    assert (fourth.completed, fourth.skipped) == (len(pso), len(grid.specs) - len(pso))
    assert len(_lines(results)) == len(grid.specs)


def test_a_stop_request_ends_the_run_between_solves(small, tmp_path):
    grid = plan([small])
    results = tmp_path / "results.jsonl"
    report = run_grid(
        grid, results, jobs=1, progress=False, stop=lambda: results.is_file() and len(_lines(results)) >= 3
    )
    assert report.interrupted and report.completed == 3 and len(_lines(results)) == 3


def test_the_same_grid_gives_the_same_results_in_one_or_two_processes_and_after_a_stop(small, tmp_path):
    grid = plan([small], runs=2, max_iterations=200)
    serial, again, parallel = (tmp_path / f"{name}.jsonl" for name in ("serial", "again", "parallel"))
    run_grid(grid, serial, jobs=1, progress=False)
    run_grid(grid, again, jobs=1, progress=False)
    # two workers, stopped after a few runs (as Ctrl-C does), then resumed
    stopped = run_grid(
        grid,
        parallel,
        jobs=2,
        chunk_size=1,
        progress=False,
        stop=lambda: parallel.is_file() and len(_lines(parallel)) >= 1,
    )
    assert stopped.interrupted and 1 <= stopped.completed < len(grid.specs)
    report = run_grid(grid, parallel, jobs=2, chunk_size=3, progress=False)
    assert report.skipped + report.completed == len(grid.specs) == 8
    assert len(_lines(parallel)) == 8 and len({r.key for r in read_results(parallel)}) == 8
    reference = [_without_time(r) for r in grid_records(grid, serial)]
    assert [_without_time(r) for r in grid_records(grid, again)] == reference
    assert [_without_time(r) for r in grid_records(grid, parallel)] == reference


def _record(case: str, solver: str, seed: int, error: float, motion: float, time: float) -> RunRecord:
    return RunRecord(
        task="t",
        system="robot",
        case=case,
        solver=solver,
        seed=seed,
        budget="{}",
        settings={},
        terms={"e": error, "m": motion},
        task_error=error,
        position_error=error,
        orientation_error=None,
        motion_error=motion,
        cost=error + 0.1 * motion,
        success=error <= 1e-4,
        stop_reason="max_iterations",
        iterations=3,
        evaluations=30,
        wall_time=time,
        configuration=[0.0],
        history_at=[1, 2, 3],
        history=[1.0, 0.5, error + 0.1 * motion],
    )


def test_summary_statistics_equal_numpy_on_a_known_results_file(tmp_path, rng):
    values = {
        (case, solver): rng.lognormal(-10, 3, size=(7, 3)) for case in ("a", "b") for solver in ("x", "y")
    }
    path = tmp_path / "known.jsonl"
    path.write_text(
        "".join(_record(c, s, k, *v[k]).to_json() + "\n" for (c, s), v in values.items() for k in range(7))
    )
    rows = summary_rows(read_results(path), tolerance=1e-4)
    assert [(r.group, r.solver) for r in rows] == list(values)
    for row in rows:
        v = values[(row.group, row.solver)]
        for column, metric in enumerate(("task_error", "motion_error", "wall_time")):
            s = row.stats[metric]
            assert (s.mean, s.std, s.best, s.worst, s.median) == (
                np.mean(v[:, column]),
                np.std(v[:, column], ddof=1),
                np.min(v[:, column]),
                np.max(v[:, column]),
                np.median(v[:, column]),
            )
        assert row.stats["e"] == row.stats["task_error"]
        assert row.successes == np.sum(v[:, 0] <= 1e-4)


def test_sign_tests_pair_runs_by_case_and_seed():
    records = [_record("a", "x", k, 1.0, 1.0, 1.0) for k in range(6)]
    records += [_record("a", "y", k, 2.0 if k < 4 else 0.5, 1.0, 1.0) for k in range(6)]
    (task_error,) = [r for r in sign_rows(records, "x") if r.metric == "task_error"]
    assert (task_error.test.wins, task_error.test.losses, task_error.test.ties) == (4, 2, 0)
    (motion,) = [r for r in sign_rows(records, "x") if r.metric == "motion_error"]
    assert (motion.test.ties, motion.test.p_value) == (6, 1.0)


def test_downsampled_history_keeps_the_start_the_end_and_exact_values():
    history = np.geomspace(1.0, 1e-15, 1000)
    at, values = downsample(history, 200)
    assert at[:50] == list(range(1, 51)) and at[-1] == 1000 and len(at) <= 250
    assert values == history[np.array(at) - 1].tolist()
    assert downsample(history, 0)[0] == list(range(1, 1001))


def test_report_writes_tables_sign_tests_and_figures(small, tmp_path):
    grid = plan([small], runs=2)
    results = tmp_path / "results.jsonl"
    run_grid(grid, results, jobs=1, progress=False)
    written = write_report(grid_records(grid, results), tmp_path / "report", reference="de")
    names = {p.relative_to(tmp_path / "report").as_posix() for p in written}
    assert {
        "summary.md",
        "summary.csv",
        "sign_test.md",
        "sign_test.csv",
        "figures/boxplots_near.png",
        "figures/convergence_far.png",
    } <= names
    assert all(p.stat().st_size > 0 for p in written)
    assert (tmp_path / "report/figures/boxplots_near.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert len((tmp_path / "report/summary.csv").read_text().splitlines()) == 1 + 2 * 2
    assert "| pso |" in (tmp_path / "report/sign_test.md").read_text()


def test_bench_command(small, tmp_path):
    parser = argparse.ArgumentParser()
    add_bench_command(parser.add_subparsers(dest="command"))
    out = tmp_path / "out"
    args = parser.parse_args(
        ["bench", str(small), "--runs", "1", "--jobs", "1", "--out", str(out), "--no-figures"]
    )
    console = Console(file=io.StringIO(), width=150)
    assert args.handler(args, console) == 0
    assert len(_lines(out / "results.jsonl")) == 4 and (out / "summary.md").is_file()
    args = parser.parse_args(["bench", str(small), "--runs", "1", "--out", str(out), "--report-only"])
    assert args.handler(args, console) == 0
    assert len(_lines(out / "results.jsonl")) == 4
    assert (out / "figures" / "convergence_near.png").stat().st_size > 0


def test_a_second_bench_on_the_same_file_is_refused_and_duplicates_count_once(small, tmp_path):
    import fcntl

    from framework.errors import MetaikError

    grid = plan([small])
    results = tmp_path / "r.jsonl"
    run_grid(grid, results, jobs=1, max_runs=3, progress=False)
    with open(tmp_path / "r.jsonl.lock", "a") as held:  # another bench holds the file
        fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
        with pytest.raises(MetaikError, match="another bench is writing"):
            run_grid(grid, results, jobs=1, progress=False)
        fcntl.flock(held, fcntl.LOCK_UN)
    lines = _lines(results)
    results.write_text("\n".join(lines + lines[:2]) + "\n")  # two runs written twice (older versions could)
    assert len(read_results(results)) == 3
    report = run_grid(grid, results, jobs=1, progress=False)
    assert report.skipped == 3 and len(read_results(results)) == len(grid.specs)


def test_killing_the_bench_ends_its_workers(small, tmp_path):
    """SIGKILL of a `metaik bench -j 2` process: its worker processes end too (none left holding its stdout)."""
    import subprocess
    import sys
    import time

    env = same_framework_env()
    slow = small.read_text().replace("max_iterations = 15", "max_iterations = 3000").replace("runs = 3", "runs = 30")
    small.write_text(slow)
    bench = subprocess.Popen([sys.executable, "-m", "framework.cli", "bench", str(small), "-j", "2", "--out",
                              str(tmp_path / "out"), "--no-figures"], env=env, stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL)

    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and len(children(bench.pid)) < 2:
        time.sleep(0.1)
    workers = children(bench.pid)
    assert len(workers) >= 2
    time.sleep(1.0)
    bench.kill()
    bench.wait()
    deadline = time.monotonic() + 20
    running = workers
    while time.monotonic() < deadline and running:
        running = alive(workers)
        time.sleep(0.1)
    assert not running, f"workers still running after their bench was killed: {running}"


def test_history_points_zero_keeps_every_iteration(small, tmp_path):
    """``history_points = 0`` is documented as "keep all": the plan accepts it and a run stores its whole history."""
    small.write_text(small.read_text().replace("[bench]", "[bench]\nhistory_points = 0"))
    grid = plan([small], solvers=["de"], runs=1, cases=[expand_task(small).cases[0].name])
    assert {spec.history_points for spec in grid.specs} == {0}
    results = tmp_path / "r.jsonl"
    run_grid(grid, results, jobs=1, progress=False)
    record = read_results(results)[0]
    assert record.history_at == list(range(1, record.iterations + 1))
