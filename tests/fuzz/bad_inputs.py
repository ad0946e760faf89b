"""Every bad input we know of, as data: what a careless or hostile user types, and the field the error must name.

Read by ``tests/fuzz/test_bad_inputs.py`` (each case: our exception / exit 2, one line, the field named) and by
``benchmarks/reliability.py`` (counts per category in ``docs/reliability.md``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

IK = """
[task]
name = "t"
robot = "youbot_arm"
TASK
[solver]
name = "hybrid"
SOLVER
[[terms]]
type = "position"
frame = "ee"
target = TARGET
"""

TRACK = """
[task]
name = "w"
robot = "youbot_arm"
[solver]
name = "hybrid"
[previous]
arm = [0, 0.3, -0.6, 0.4, 0]
[trajectory]
type = "circle"
centre = [0.3, 0.0, 0.3]
radius = 0.02
points = POINTS
[[terms]]
type = "position"
frame = "ee"
target = "t"
"""

BENCH = """
[task]
name = "b"
robot = "youbot_arm"
[solver]
name = "de"
population = 10
max_iterations = 5
[bench]
solvers = ["de"]
RUNS
[[terms]]
type = "position"
frame = "ee"
target = [0.3, 0.0, 0.3]
"""


def ik_file(task: str = "", solver: str = "", target: str = "[0.3, 0.0, 0.3]") -> str:
    """The small IK task file with lines added to ``[task]`` / ``[solver]`` or another target."""
    return IK.replace("TASK", task).replace("SOLVER", solver).replace("TARGET", target)


@dataclass(frozen=True)
class CliCase:
    """``metaik ARGV`` (``{file}`` in ARGV is ``file_text`` written to a task file) must exit 2 with one line
    naming ``names`` (each a substring of the message)."""

    category: str
    id: str
    argv: tuple[str, ...]
    names: tuple[str, ...]
    file_text: str | None = None


@dataclass(frozen=True)
class ApiCase:
    """``call()`` must raise :class:`framework.errors.MetaikError` naming ``names`` (each a substring)."""

    category: str
    id: str
    call: Callable[[], object] = field(repr=False)
    names: tuple[str, ...]


def _cli(category, id, argv, names, file_text=None) -> CliCase:
    return CliCase(category, id, tuple(argv.split()), tuple(names), file_text)


RUN = "run youbot_dual_coordinated_ik"
CLI_CASES: list[CliCase] = [
    # command-line options
    _cli("option", "seed -1", f"{RUN} --seed -1", ["seed"]),
    _cli("option", "population 1e9", f"{RUN} --population 1000000000", ["population"]),
    _cli("option", "population 0", f"{RUN} --population 0", ["population"]),
    _cli("option", "iterations -1 hybrid", f"{RUN} --solver hybrid --iterations -1", ["iterations"]),
    _cli("option", "iterations 0", f"{RUN} --iterations 0", ["iterations"]),
    _cli("option", "unknown solver", f"{RUN} --solver nope", ["nope"]),
    _cli("option", "points 0", "run paper000_circular --points 0", ["points"]),
    _cli("option", "output is a folder", "run {file} --output .", ["--output"], TRACK.replace("POINTS", "4")),
    _cli("option", "output under a file", "run {file} --output t.toml/x.csv", ["--output"],
         TRACK.replace("POINTS", "4")),
    _cli("option", "record is a folder", f"{RUN} --record .", ["recording"]),
    _cli("option", "unknown case", f"{RUN} --case nope", ["nope"]),
    _cli("option", "bench runs 1e9", "bench {file} --runs 1000000000", ["runs", "--max-runs"],
         BENCH.replace("RUNS", "")),
    _cli("option", "bench runs 0", "bench {file} --runs 0", ["runs"], BENCH.replace("RUNS", "")),
    _cli("option", "bench population 0", "bench {file} --population 0", ["population"], BENCH.replace("RUNS", "")),
    _cli("option", "bench iterations 0", "bench {file} --iterations 0", ["iterations"], BENCH.replace("RUNS", "")),
    _cli("option", "bench tolerance 0", "bench {file} --tolerance 0", ["tolerance"], BENCH.replace("RUNS", "")),
    _cli("option", "bench tolerance nan", "bench {file} --tolerance nan", ["tolerance"], BENCH.replace("RUNS", "")),
    _cli("option", "bench reference", "bench {file} --reference nope", ["reference", "nope"],
         BENCH.replace("RUNS", "")),
    _cli("option", "bench jobs 0", "bench {file} --jobs 0", ["jobs"], BENCH.replace("RUNS", "")),
    _cli("option", "bench tracking task", "bench paper000_circular", ["paper000_circular"]),
    _cli("option", "bench reach task", "bench paper003_sinusoid", ["paper003_sinusoid"]),
    _cli("option", "reach orientations -1", "reach youbot_arm --orientations -1", ["orientations"]),
    _cli("option", "reach voxel 0", "reach youbot_arm --voxel 0", ["voxel"]),
    _cli("option", "missing task", "run no_such_task", ["no_such_task"]),
    _cli("option", "missing robot", "show no_such_robot", ["no_such_robot"]),
    _cli("option", "missing recording", "replay none.rrd --summary", ["none.rrd"]),
    # task-file values
    _cli("task file", "robot = 5", "run {file}", ["robot"], ik_file().replace('robot = "youbot_arm"', "robot = 5")),
    _cli("task file", "terms = 5", "run {file}", ["terms"],
         ik_file().split("[[terms]]")[0] + "terms = 5\n"),
    _cli("task file", "terms table", "run {file}", ["terms"],
         ik_file().split("[[terms]]")[0] + "[terms]\ntype = 'position'\n"),
    _cli("task file", 'seed = "x"', "run {file}", ["seed"], ik_file(solver='seed = "x"')),
    _cli("task file", "seed = -1", "run {file}", ["seed"], ik_file(solver="seed = -1")),
    _cli("task file", "options = 5", "run {file}", ["options"], ik_file(solver="options = 5")),
    _cli("task file", "population = 0", "run {file}", ["population"], ik_file(solver="population = 0")),
    _cli("task file", "max_iterations = nan", "run {file}", ["max_iterations"],
         ik_file(solver="max_iterations = nan")),
    _cli("task file", "tolerance = -1", "run {file}", ["tolerance"], ik_file(solver="tolerance = -1")),
    _cli("task file", 'locked = ["joint1"]', "run {file}", ["locked"], ik_file(task='locked = ["joint1"]')),
    _cli("task file", "joints = 5", "run {file}", ["joints"], ik_file(task="joints = 5")),
    _cli("task file", 'floating_base = "yes"', "run {file}", ["floating_base"], ik_file(task='floating_base = "yes"')),
    _cli("task file", "bounds = 5", "run {file}", ["bounds"], ik_file(solver="bounds = 5")),
    _cli("task file", "target 1/0", "run {file}", ["target", "1/0"], ik_file(target='"[1/0, 0, 0]"')),
    _cli("task file", "target nan", "run {file}", ["target"], ik_file(target="[nan, 0, 0.3]")),
    _cli("task file", "target of 2", "run {file}", ["target"], ik_file(target="[0.3, 0.0]")),
    _cli("task file", "target text", "run {file}", ["target"], ik_file(target='"hello"')),
    _cli("task file", "target import", "run {file}", ["target"], ik_file(target='"__import__(\'os\')"')),
    _cli("task file", "weight None-like", "run {file}", ["weight"], ik_file() + 'weight = "x"\n'),
    _cli("task file", "weight negative", "run {file}", ["weight"], ik_file() + "weight = -1\n"),
    _cli("task file", "unknown term type", "run {file}", ["type", "positon"],
         ik_file().replace('type = "position"', 'type = "positon"')),
    _cli("task file", "unknown frame", "run {file}", ["frame", "nope"],
         ik_file().replace('frame = "ee"', 'frame = "nope"')),
    _cli("task file", "points = nan", "run {file}", ["points"], TRACK.replace("POINTS", "nan")),
    _cli("task file", "points = 1e12", "run {file}", ["points"], TRACK.replace("POINTS", "1e12")),
    _cli("task file", "points = 1", "run {file}", ["points"], TRACK.replace("POINTS", "1")),
    _cli("task file", '[bench] runs = "x"', "bench {file}", ["runs"], BENCH.replace("RUNS", 'runs = "x"')),
    _cli("task file", "[bench] runs = 1e9", "bench {file}", ["runs"], BENCH.replace("RUNS", "runs = 1000000000")),
    _cli("task file", "not TOML", "run {file}", ["TOML"], "[task\nname = 1"),
    _cli("task file", "missing [task]", "run {file}", ["[task]"], "[solver]\nname = 'de'\n"),
]


def _urdf(axis: str, *, kind: str = "revolute", child: str = "b") -> str:
    """A two-link URDF with one joint (``axis``: its ``<axis>`` element)."""
    limit = '<limit lower="-1" upper="1" effort="1" velocity="1"/>' if kind == "revolute" else ""
    return (f'<robot name="r"><link name="a"/><link name="b"/><joint name="j" type="{kind}"><parent link="a"/>'
            f'<child link="{child}"/>{axis}{limit}</joint></robot>')


def _api_cases() -> list[ApiCase]:
    import numpy as np

    import framework as fw
    from framework.solvers import minimize

    def problem():
        robot = fw.load_robot("youbot_arm")
        return fw.Problem(robot, [(1.0, fw.Position("ee", [0.3, 0.0, 0.3]))])

    def position(weight):
        return lambda: fw.Problem(fw.load_robot("youbot_arm"), [(weight, fw.Position("ee", [0.3, 0.0, 0.3]))])

    return [
        ApiCase("api", "seed -1", lambda: fw.solve(problem(), "de", seed=-1), ["seed"]),
        ApiCase("api", "max_iterations nan", lambda: fw.solve(problem(), "de", max_iterations=float("nan")),
                ["max_iterations"]),
        ApiCase("api", "max_iterations -1 hybrid", lambda: fw.solve(problem(), "hybrid", max_iterations=-1),
                ["max_iterations"]),
        ApiCase("api", "population 0 multistart_lm", lambda: fw.solve(problem(), "multistart_lm", population=0),
                ["population"]),
        ApiCase("api", "population 1e9", lambda: fw.solve(problem(), "de", population=10**9), ["population"]),
        ApiCase("api", "tolerance nan", lambda: fw.solve(problem(), "hybrid", tolerance=float("nan")),
                ["tolerance"]),
        ApiCase("api", "time_budget -1", lambda: fw.solve(problem(), "hybrid", time_budget=-1.0), ["time_budget"]),
        ApiCase("api", "unknown option", lambda: fw.solve(problem(), "de", options={"populaton": 5}),
                ["populaton"]),
        ApiCase("api", "unknown solver", lambda: fw.solve(problem(), "nope"), ["nope"]),
        ApiCase("api", "None weight", position(None), ["weight"]),
        ApiCase("api", "nan weight", position(float("nan")), ["weight"]),
        ApiCase("api", "box not a pair", lambda: minimize(lambda X: X.sum(1), 5, rng=np.random.default_rng()),
                ["box"]),
        ApiCase("api", "minimize max_iterations nan", lambda: minimize(
            lambda X: X.sum(1), ([0.0], [1.0]), rng=np.random.default_rng(), max_iterations=float("nan")),
                ["max_iterations"]),
        ApiCase("api", "problem bounds", lambda: fw.Problem(fw.load_robot("youbot_arm"),
                                                           fw.Position("ee", [0.3, 0, 0.3]), bounds=5), ["bounds"]),
        ApiCase("api", "initial of the wrong size", lambda: fw.solve(problem(), "hybrid", initial=np.zeros(3)),
                ["initial"]),
        ApiCase("api", "initial nan", lambda: fw.solve(problem(), "hybrid", initial=np.full(5, np.nan)),
                ["initial"]),
        ApiCase("api", "position target of 2", lambda: fw.Position("ee", [0.3, 0.0]), ["target"]),
        ApiCase("api", "position target nan", lambda: fw.Position("ee", [np.nan, 0.0, 0.3]), ["target"]),
        ApiCase("api", "orientation not unit", lambda: fw.Orientation("ee", [0, 0, 0, 0]), ["quaternion"]),
        ApiCase("api", "unknown frame", lambda: fw.Problem(fw.load_robot("youbot_arm"),
                                                          [(1.0, fw.Position("nope", [0.3, 0, 0.3]))]),
                ["nope"]),
        ApiCase("api", "no terms", lambda: fw.Problem(fw.load_robot("youbot_arm"), []), ["term"]),
        ApiCase("api", "unknown robot", lambda: fw.load_robot("no_such_robot"), ["no_such_robot"]),
        ApiCase("api", "unknown joint", lambda: fw.load_robot("youbot_arm", joints=["nope"]), ["nope"]),
        ApiCase("api", "zero joint axis", lambda: fw.robot_from_urdf(_urdf('<axis xyz="0 0 0"/>')), ["axis"]),
        ApiCase("api", "no movable joint", lambda: fw.robot_from_urdf(_urdf("", kind="fixed")), ["joint"]),
        ApiCase("api", "joint to a missing link", lambda: fw.robot_from_urdf(_urdf("", child="nowhere")),
                ["nowhere"]),
        ApiCase("api", "joints as one string", lambda: fw.load_robot("youbot_arm", joints="joint1"), ["joints"]),
        ApiCase("api", "locked as a list", lambda: fw.load_robot("youbot_arm", locked=["joint1"]), ["locked"]),
        ApiCase("api", "batch targets wrong shape", lambda: fw.solve_batch(problem(), np.zeros((4, 2))),
                ["targets"]),
    ]


API_CASES = _api_cases()
