"""Start-up: what a new user waits for before a first answer, and the speed after it, side by side with a baseline.

Five parts, each in fresh processes (``METAIK_CACHE_DIR`` pointing at a folder of the run's own):

1. **Cold start** (an empty cache folder each run, three runs, the median): the README's Python example (the dual
   youBot, hybrid) — its first ``solve`` and the whole process —, a UR5 ``Pose`` first solve, and the README's first
   command (``metaik run paper000_sinusoidal --solver hybrid --record run.rrd``, its wall time after the install).
   With it, one more run of the README example with the helper process off (``METAIK_COMPILE_HELPER=0``: every
   compile in the process) records numba's compile events: seconds per function, the table that shows where
   each change pays.
2. **Warm start**: a new process with the cache filled — import, then the first solve (three runs, the median).
3. **The cache lasts**: another copy of the same sources (a reinstall, a second venv), a read-only copy, and the
   same copy after an edit of one term module and of one engine module: what each compiles on its first solve.
4. **Fast loop**: ``.ci/run`` on a fresh clone of ``HEAD`` (its venv, install and test suite) with an empty cache;
   the suite's own time from pytest's summary.
5. **Speed held**: the same workloads solved by this checkout and by a baseline commit (its own clone and venv,
   ``--baseline``), chunk by chunk alternately (which one goes first alternates too), each a long-lived worker
   process: pose IK (UR5, Panda, Baxter: median, p95 and strict success ≤ 1e-5 m and rad by Pinocchio FK),
   ``solve_batch`` IK/s on two threads, the README's youBot problem on random reachable targets, a 200-point path
   (the README's ``track``), and the youBot with its ``SelfCollision`` term on targets where the unconstrained
   solve collides (success: hands within 1e-5 m and no contact by coal).

    python benchmarks/startup.py [--baseline 5fd0fce] [--build-dir build/startup] [--parts cold,warm,cache,suite,speed]

Writes docs/results/startup.md (a run of some parts only prints its tables).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import report  # noqa: E402

OUT = report.ROOT / "docs" / "results" / "startup.md"
PARTS = ("cold", "warm", "cache", "suite", "speed")
RUNS = 3

#: The README's Python example, timed: its ``solve`` calls are wrapped to time the first.
_EXAMPLE = """
import json, sys, time
started = time.perf_counter()
sys.path.insert(0, sys.argv[1])
import framework
imported = time.perf_counter() - started
solves = []
_solve = framework.solve
def timed(*args, **kwargs):
    t = time.perf_counter()
    result = _solve(*args, **kwargs)
    solves.append(time.perf_counter() - t)
    return result
framework.solve = timed
exec(compile(sys.argv[2], "README.md", "exec"), {})
from framework.compiled.cache import NOTICE
print(json.dumps({"import": imported, "first_solve": solves[0], "compiling": NOTICE.seconds,
                  "process": time.perf_counter() - started}))
"""

_UR5 = """
import json, sys, time
started = time.perf_counter()
sys.path.insert(0, sys.argv[1])
import framework as fw
imported = time.perf_counter() - started
from tests.conftest import example_robot_data_dir
robot = fw.load_robot(example_robot_data_dir() / "ur_description" / "urdf" / "ur5_robot.urdf")
target = robot.frame_placement(robot.middle + 0.1, "tool0")
t = time.perf_counter()
result = fw.solve(fw.Problem(robot, fw.Pose("tool0", target)))
first = time.perf_counter() - t
assert result.success
from framework.compiled.cache import NOTICE
print(json.dumps({"import": imported, "first_solve": first, "compiling": NOTICE.seconds,
                  "process": time.perf_counter() - started}))
"""

#: numba's compile events of the README example, every compile in the process: exclusive and inclusive seconds.
_EVENTS = """
import json, sys, time
from collections import defaultdict
import numba.core.event as ev
events = []
class Listener(ev.Listener):
    def on_start(self, e): events.append((time.perf_counter(), 0, e))
    def on_end(self, e): events.append((time.perf_counter(), 1, e))
ev.register("numba:compile", Listener())
sys.path.insert(0, sys.argv[1])
exec(compile(sys.argv[2], "README.md", "exec"), {})
stack, own, total, count = [], defaultdict(float), defaultdict(float), defaultdict(int)
for t, end, e in events:
    if not end:
        d = e.data["dispatcher"]
        f = getattr(d, "py_func", None) or getattr(d, "_pyfunc", None)
        stack.append([f"{f.__module__}.{f.__qualname__}", t, 0.0])
    else:
        name, start, inner = stack.pop()
        own[name] += t - start - inner
        if not any(s[0] == name for s in stack):
            total[name] += t - start
        count[name] += 1
        if stack:
            stack[-1][2] += t - start
print(json.dumps({"own": own, "total": total, "count": count}))
"""


def _readme() -> tuple[str, list[str]]:
    """The README's Python example (its first ``python`` block) and its first command."""
    text = (report.ROOT / "README.md").read_text()
    block = text.split("```python\n", 1)[1].split("```", 1)[0]
    command = text.split("```bash\n", 1)[1].splitlines()[0].split(" && ")[-1].split()
    return block, command


def _python(script: str, *args: str, cache: Path, root: Path = report.ROOT, **environment: str) -> dict:
    env = {**os.environ, "METAIK_CACHE_DIR": str(cache), "METAIK_COMPILE_NOTICE": "0", **environment}
    done = subprocess.run([sys.executable, "-c", script, str(root), *args], capture_output=True, text=True, env=env,
                          cwd=root)
    if done.returncode:
        raise SystemExit(f"startup: a run failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.splitlines()[-1])


def _median(values: list[float]) -> float:
    return statistics.median(values)


def _seconds(values: list[float], digits: int = 1) -> str:
    return f"**{_median(values):.{digits}f}** ({', '.join(f'{v:.{digits}f}' for v in values)})"


def cold(scratch: Path) -> tuple[list[str], Path]:
    """Part 1; returns its lines and a cache folder it filled (for the warm part)."""
    example, command = _readme()
    rows = {"example": [], "example_process": [], "ur5": [], "command": []}
    filled = None
    for run in range(RUNS):
        cache = scratch / f"cold-{run}"
        got = _python(_EXAMPLE, example, cache=cache)
        rows["example"].append(got["first_solve"])
        rows["example_process"].append(got["process"])
        rows["ur5"].append(_python(_UR5, cache=scratch / f"cold-ur5-{run}")["first_solve"])
        work = scratch / f"command-{run}"
        work.mkdir()
        metaik = Path(sys.executable).parent / command[0]
        t = time.perf_counter()
        done = subprocess.run([str(metaik), *command[1:]], cwd=work, capture_output=True, text=True,
                              env={**os.environ, "METAIK_CACHE_DIR": str(scratch / f"cold-command-{run}")})
        rows["command"].append(time.perf_counter() - t)
        if done.returncode:
            raise SystemExit(f"startup: `{' '.join(command)}` failed:\n{done.stderr[-3000:]}")
        filled = cache
        print(f"cold run {run + 1}: example {rows['example'][-1]:.1f} s, UR5 {rows['ur5'][-1]:.1f} s, "
              f"command {rows['command'][-1]:.1f} s", flush=True)
    _python(_UR5, cache=filled)  # the UR5's kernels in the cache the warm part reads too
    events = _python(_EVENTS, example, cache=scratch / "events", METAIK_COMPILE_HELPER="0")
    lines = [
        "## Cold start: a fresh install's first answer",
        "",
        f"Each run in a new process with an empty cache folder; the median of {RUNS} runs in bold, the runs in "
        "brackets. The README example's process time includes importing the package and loading the robot.",
        "",
        "| what | seconds | target |",
        "|---|---:|---:|",
        f"| README's Python example (dual youBot, hybrid): first `solve` | {_seconds(rows['example'])} | ≤ 30 |",
        f"| README's Python example: the whole process | {_seconds(rows['example_process'])} | |",
        f"| UR5 `Pose`: first `solve` | {_seconds(rows['ur5'])} | ≤ 20 |",
        f"| README's first command (`{' '.join(command)}`), after the install | {_seconds(rows['command'])} | ≤ 90 |",
        "",
    ]
    lines += _compile_table(events)
    return lines, filled


def _compile_table(events: dict, top: int = 25) -> list[str]:
    own, total, count = events["own"], events["total"], events["count"]
    names = sorted(own, key=lambda k: -own[k])
    lines = [
        "### Compile time per function (README example, everything compiled in one process)",
        "",
        f"numba's compile events (`numba.core.event`), the helper process off: {len(own)} functions, "
        f"{sum(count.values())} signatures, {sum(own.values()):.1f} s in all. *Own*: the function's compile without "
        "its callees' (typing, lowering; an entry point's also includes LLVM's optimization and machine code of "
        "everything linked into it); *with callees*: the whole compile it started.",
        "",
        "| function | own s | with callees s | signatures |",
        "|---|---:|---:|---:|",
    ]
    for name in names[:top]:
        lines.append(f"| `{name.removeprefix('framework.')}` | {own[name]:.2f} | {total[name]:.2f} | {count[name]} |")
    return lines + [""]


def warm(scratch: Path, cache: Path) -> list[str]:
    example, _ = _readme()
    got = [_python(_EXAMPLE, example, cache=cache) for _ in range(RUNS)]
    ur5 = [_python(_UR5, cache=cache) for _ in range(RUNS)]

    def row(label, runs):
        return (f"| {label} | {_median([r['import'] for r in runs]):.2f} | "
                f"{_median([r['first_solve'] for r in runs]):.2f} | {_seconds([r['process'] for r in runs], 2)} |")

    return ["## Warm start: a new process, the cache filled", "",
            f"Median of {RUNS} new processes in bold, the runs in brackets (target: import and first answer ≤ 1.5 "
            "s). *Import*: `import framework`; *first solve*: the first `solve` call (the UR5's includes building "
            "its `Problem`, whose kernels load from the cache); *the script*: import, robot, problem and solve, "
            "from the script's first line to its answer.", "",
            "| problem | import s | first solve s | the script s |", "|---|---:|---:|---:|",
            row("README's Python example (dual youBot)", got), row("UR5 `Pose`", ur5), ""]


def cache_lasts(scratch: Path, cache: Path) -> list[str]:
    """Part 3: copies of the sources using the filled ``cache``."""
    example, _ = _readme()
    copy = scratch / "copy"
    shutil.copytree(report.ROOT / "framework", copy / "framework", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(report.ROOT / "robots", copy / "robots")
    rows = []

    def first(label: str, root: Path):
        got = _python(_EXAMPLE, example, cache=cache, root=root, METAIK_COMPILE_HELPER="0")
        rows.append(f"| {label} | {got['first_solve']:.2f} | {got['compiling']:.1f} |")

    first("another copy of the same sources (a reinstall, another venv)", copy)
    for path in (copy / "framework").rglob("*"):
        path.chmod(path.stat().st_mode & ~0o222)
    try:
        first("the same copy, read-only", copy)
    finally:
        for path in (copy / "framework").rglob("*"):
            path.chmod(path.stat().st_mode | 0o200)
    for module, what in (("costs/position.py", "a term module (its kernel recompiles)"),
                         ("engine/newton_search.py", "an engine module (the functions of the Newton phase that "
                                                     "import it retype, the rest loads as bitcode)")):
        path = copy / "framework" / module
        path.write_text(path.read_text() + "\n# edited\n")
        first(f"the copy after an edit of `{module}`: {what}", copy)
    return ["## The cache lasts", "",
            "The README example's first solve in a new process, the cache filled by the runs above (keyed by the "
            "sources' content: a copy elsewhere finds it), the helper process off; *compiling*: the seconds the "
            "process spent compiling.", "",
            "| sources | first solve s | compiling s |", "|---|---:|---:|", *rows, ""]


def suite(scratch: Path) -> list[str]:
    """Part 4: ``.ci/run`` on a fresh clone of HEAD, empty cache."""
    clone = scratch / "clone"
    subprocess.run(["git", "clone", "-q", str(report.ROOT), str(clone)], check=True)
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=clone, capture_output=True, text=True,
                          check=True).stdout.strip()
    t = time.perf_counter()
    done = subprocess.run([str(clone / ".ci" / "run")], cwd=clone, capture_output=True, text=True,
                          env={**os.environ, "METAIK_CACHE_DIR": str(scratch / "ci-cache")})
    wall = time.perf_counter() - t
    summary = [line for line in done.stdout.splitlines() if " passed" in line and " in " in line]
    if done.returncode or not summary:
        raise SystemExit(f"startup: .ci/run failed:\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}")
    tests = float(summary[-1].rsplit(" in ", 1)[1].split("s")[0])
    return ["## Fast loop: tests on a fresh clone", "",
            f"`.ci/run` on a fresh clone of `HEAD` ({head}) with an empty cache folder: a new venv, `pip install "
            "\".[test]\"`, then the README's test command.", "",
            "| what | minutes | target |", "|---|---:|---:|",
            f"| the test suite (pytest's own time: {summary[-1].strip('= ')}) | {tests / 60:.1f} | ≤ 4 |",
            f"| `.ci/run` (venv, install, test suite) | {wall / 60:.1f} | ≤ 6 |", ""]


# --- part 5: speed held, side by side ------------------------------------------------------------------------

#: Chains of the pose workloads: (name, URDF below example-robot-data, tip).
CHAINS = (("UR5", "ur_description/urdf/ur5_robot.urdf", "tool0"),
          ("Panda", "panda_description/urdf/panda.urdf", "panda_hand_tcp"),
          ("Baxter left arm", "baxter_description/urdf/baxter.urdf", "left_gripper"))
POSES, POSE_CHUNK = 1500, 100
BATCH, BATCH_CHUNK = 8000, 1000
YOUBOT, YOUBOT_CHUNK = 300, 25
COLLIDING, COLLIDING_CHUNK = 120, 10
PATHS, PATH_CHUNK = 40, 4
#: The README's previous configuration of the dual youBot.
Q_PREV = (0, 0, 1.5707963267948966, -1.5707963267948966, 1.5707963267948966, -0.7853981633974483,
          0.7853981633974483, 0, 1.5707963267948966, 1.5707963267948966, -0.7853981633974483, 0.7853981633974483, 0)


def _inputs(path: Path) -> None:
    """The workloads' inputs, drawn once (this checkout), read by both workers."""
    import numpy as np

    import framework as fw
    from tests.conftest import example_robot_data_dir

    rng = np.random.default_rng(2026)
    erd = example_robot_data_dir()
    data = {}
    for k, (_, urdf, tip) in enumerate(CHAINS):
        robot = fw.load_robot(erd / urdf)
        poses = lambda count: np.array([robot.frame_placement(q, tip).homogeneous
                                        for q in robot.random_configurations(rng, count)])
        data[f"pose{k}"] = poses(POSES)
        if k == 0:
            data["batch"] = poses(BATCH)
    youbot = fw.load_robot("youbot_dual_mobile")
    hands = lambda q: np.concatenate([youbot.frame_placement(q, f).translation for f in ("arm1_ee", "arm2_ee")])
    data["youbot"] = np.array([hands(q) for q in youbot.random_configurations(rng, YOUBOT)])
    shape = fw.RobotShape(youbot)
    colliding = []
    while len(colliding) < COLLIDING:  # targets (of a contact-free configuration) the unconstrained solve collides on
        q = youbot.random_configurations(rng, 1)[0]
        if shape.check(q, distances=False).colliding:
            continue
        t = hands(q)
        result = fw.solve(fw.Problem(youbot, _youbot_objective(fw, t, np.array(Q_PREV))), seed=len(colliding))
        if shape.check(result.configuration, distances=False).colliding:
            colliding.append(t)
    data["colliding"] = np.array(colliding)
    np.savez(path, **data)


def _youbot_objective(fw, targets, q_prev):
    return (1.2 * fw.Position("arm1_ee", targets[:3]) + 1.2 * fw.Position("arm2_ee", targets[3:])
            + 0.1 * fw.Motion("base", q_prev) + 0.4 * fw.Motion("arm1", q_prev) + 0.4 * fw.Motion("arm2", q_prev))


def worker(root: str, inputs: str) -> None:
    """A worker: solve the chunks asked on stdin (one JSON line each) with the package at ``root``."""
    sys.path.insert(0, root)
    import numpy as np
    import pinocchio as pin

    import framework as fw
    from framework.tracking import TrackingTask, track
    from tests.conftest import example_robot_data_dir

    try:
        from framework.tracking import paths
    except ImportError:  # a baseline from before the folders by layer
        from framework import trajectory as paths
    budget = report.track_budget(track, 300, 1e-4)  # the same in either checkout

    data = np.load(inputs)
    erd = example_robot_data_dir()
    robots = [fw.load_robot(erd / urdf) for _, urdf, _ in CHAINS]
    youbot = fw.load_robot("youbot_dual_mobile")
    shape = fw.RobotShape(youbot)
    q_prev = np.array(Q_PREV)
    task = TrackingTask(frame="arm1_ee", follower="arm2_ee", offset=(0, -0.3, 0), position_weight=1.2,
                        motion={"base": 0.1, "arm1": 0.4, "arm2": 0.4})
    path = paths.paper000("sinusoidal")

    def strict(robot, tip, q, target) -> bool:
        error = robot.frame_placement(q, tip).inverse() * pin.SE3(target)
        return bool(np.linalg.norm(error.translation) <= 1e-5 and np.linalg.norm(pin.log3(error.rotation)) <= 1e-5)

    def hands_within(q, targets) -> bool:
        return all(np.linalg.norm(youbot.frame_placement(q, f).translation - targets[3 * i:3 * i + 3]) <= 1e-5
                   for i, f in enumerate(("arm1_ee", "arm2_ee")))

    def pose(k, start, stop):
        robot, tip, poses = robots[k], CHAINS[k][2], data[f"pose{k}"]
        times, answers = [], []
        for i in range(start, stop):
            t = time.perf_counter()
            result = fw.solve(fw.Problem(robot, fw.Pose(tip, poses[i])), tolerance=1e-5, time_budget=0.005, seed=i)
            times.append(time.perf_counter() - t)
            answers.append((result.configuration, poses[i]))
        return times, [strict(robot, tip, q, target) for q, target in answers]

    def batch(start, stop):
        poses = data["batch"][start:stop]
        problem = fw.Problem(robots[0], fw.Pose("tool0", poses[0]))
        result = fw.solve_batch(problem, poses, tolerance=1e-5, time_budget=0.005, workers=2, progress=False)
        ok = [strict(robots[0], "tool0", q, target) for q, target in zip(result.configurations, poses)]
        return [result.wall_time / len(poses)], ok

    def youbot_solves(key, start, stop, collision):
        times, answers = [], []
        for i in range(start, stop):
            targets = data[key][i]
            objective = _youbot_objective(fw, targets, q_prev)
            if collision:
                objective = objective + fw.SelfCollision(shape, margin=0.005)
            problem = fw.Problem(youbot, objective)
            t = time.perf_counter()
            result = fw.solve(problem, seed=i)
            times.append(time.perf_counter() - t)
            answers.append(result.configuration)
        ok = [hands_within(q, data[key][i]) and not (collision and shape.check(q, distances=False).colliding)
              for i, q in zip(range(start, stop), answers)]
        return times, ok

    def tracked(start, stop):
        times, ok = [], []
        for _ in range(start, stop):
            t = time.perf_counter()
            result = track(youbot, path, task, **budget)
            times.append(time.perf_counter() - t)
            ok.append(bool(np.max(result.position_error) <= 1e-5))
        return times, ok

    run = {"pose0": lambda a, b: pose(0, a, b), "pose1": lambda a, b: pose(1, a, b),
           "pose2": lambda a, b: pose(2, a, b), "batch": batch,
           "youbot": lambda a, b: youbot_solves("youbot", a, b, False),
           "colliding": lambda a, b: youbot_solves("colliding", a, b, True), "path": tracked}
    sizes = {key: items for key, _, items, _, _ in WORKLOADS}
    for name in run:  # one untimed pass over every input: whatever compiles lazily does so before any timing
        run[name](0, sizes[name])
    print(json.dumps({"ready": True}), flush=True)
    for line in sys.stdin:
        ask = json.loads(line)
        times, ok = run[ask["workload"]](ask["start"], ask["stop"])
        print(json.dumps({"times": times, "ok": ok}), flush=True)


#: (key, label, items, chunk, unit): the speed workloads.
WORKLOADS = (("pose0", "UR5 pose IK, new Problem per pose", POSES, POSE_CHUNK, "ms"),
             ("pose1", "Panda pose IK", POSES, POSE_CHUNK, "ms"),
             ("pose2", "Baxter left arm pose IK", POSES, POSE_CHUNK, "ms"),
             ("batch", "UR5 `solve_batch`, 2 threads", BATCH, BATCH_CHUNK, "IK/s"),
             ("youbot", "README's youBot problem, random reachable targets", YOUBOT, YOUBOT_CHUNK, "ms"),
             ("path", "200-point path (README's `track`, paper 000 sinusoid)", PATHS, PATH_CHUNK, "ms"),
             ("colliding", "youBot + `SelfCollision`, targets the unconstrained solve collides on", COLLIDING,
              COLLIDING_CHUNK, "ms"))


class _Worker:
    def __init__(self, python: Path, root: Path, inputs: Path, cache: Path):
        env = {**os.environ, "METAIK_CACHE_DIR": str(cache), "METAIK_COMPILE_NOTICE": "0"}
        self.process = subprocess.Popen([str(python), __file__, "--worker", str(root), "--inputs", str(inputs)],
                                        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env,
                                        cwd=root)
        self._read()

    def _read(self) -> dict:
        line = self.process.stdout.readline()
        if not line:
            raise SystemExit("startup: a speed worker stopped")
        return json.loads(line)

    def ask(self, workload: str, start: int, stop: int) -> dict:
        self.process.stdin.write(json.dumps({"workload": workload, "start": start, "stop": stop}) + "\n")
        self.process.stdin.flush()
        return self._read()

    def close(self) -> None:
        self.process.stdin.close()
        self.process.wait()


def _baseline(ref: str, build: Path) -> Path:
    """A clone of the repository at ``ref`` with its own venv (made once in ``build``)."""
    root = build / f"baseline-{ref}"
    if not (root / ".venv" / "bin" / "python").exists():
        shutil.rmtree(root, ignore_errors=True)
        subprocess.run(["git", "clone", "-q", str(report.ROOT), str(root)], check=True)
        subprocess.run(["git", "checkout", "-q", ref], cwd=root, check=True)
        subprocess.run([sys.executable, "-m", "venv", str(root / ".venv")], check=True)
        subprocess.run([str(root / ".venv" / "bin" / "pip"), "install", "-q", "-e", ".[test]"], cwd=root, check=True)
    return root


def speed(scratch: Path, ref: str, build: Path) -> list[str]:
    import numpy as np

    base = _baseline(ref, build)
    inputs = scratch / "inputs.npz"
    _inputs(inputs)
    print("speed: inputs drawn; starting the workers (the baseline's first start may compile for minutes)", flush=True)
    workers = {"baseline": _Worker(base / ".venv" / "bin" / "python", base, inputs, build / "baseline-cache"),
               "this": _Worker(Path(sys.executable), report.ROOT, inputs, build / "this-cache")}
    results = {(w[0], who): {"times": [], "ok": [], "chunks": []} for w in WORKLOADS for who in workers}
    chunk = 0
    for key, _, items, size, _ in WORKLOADS:
        for start in range(0, items, size):
            order = ("baseline", "this") if chunk % 2 == 0 else ("this", "baseline")
            chunk += 1
            for who in order:
                got = workers[who].ask(key, start, min(start + size, items))
                entry = results[(key, who)]
                entry["times"] += got["times"]
                entry["ok"] += got["ok"]
                entry["chunks"].append(float(np.median(got["times"])))
        print(f"speed: {key} done", flush=True)
    for w in workers.values():
        w.close()
    lines = ["## Speed held: side by side with the commit before this work", "",
             f"Baseline: commit `{ref}` (its own clone and venv); this: the checkout. Each workload's items are cut in "
             "chunks; each chunk is solved by one worker, then the other (the first alternates), both warm. "
             "*Chunk ratios*: this / baseline of each chunk's median (time: > 1 is slower here; IK/s: the "
             "baseline's rate / this rate, so > 1 is slower here too); *ratio*: their median — the machine's speed "
             "drifts by tens of percent over seconds, and a pair of chunks run back to back sees the same drift, "
             "where the two medians over the whole run do not.", "",
             "| workload | baseline median | this median | ratio (median of chunks) | baseline p95 | this p95 "
             "| success baseline / this | chunk ratios (count: range) |", "|---|---:|---:|---:|---:|---:|---|---|"]
    for key, label, items, size, unit in WORKLOADS:
        b, t = results[(key, "baseline")], results[(key, "this")]
        ratios = np.array(t["chunks"]) / np.array(b["chunks"])
        chunks = f"{len(ratios)}: {ratios.min():.2f} to {ratios.max():.2f}"
        ratio = float(np.median(ratios))
        if unit == "IK/s":
            rate = lambda r: 1.0 / np.array(r["times"])
            med_b, med_t = np.median(rate(b)), np.median(rate(t))
            lines.append(f"| {label} | {med_b:,.0f} IK/s | {med_t:,.0f} IK/s | {ratio:.3f} | | | "
                         f"{np.mean(b['ok']):.2%} / {np.mean(t['ok']):.2%} | {chunks} |")
            continue
        ms = lambda r, q: 1e3 * float(np.percentile(r["times"], q))
        lines.append(f"| {label} | {ms(b, 50):.3f} ms | {ms(t, 50):.3f} ms | {ratio:.3f} | "
                     f"{ms(b, 95):.3f} ms | {ms(t, 95):.3f} ms | {np.mean(b['ok']):.2%} / {np.mean(t['ok']):.2%} | "
                     f"{chunks} |")
    return lines + ["", "Target: every ratio within 5 % (≤ 1.05).", ""]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--baseline", default="5fd0fce", help="the commit to compare speed with")
    parser.add_argument("--build-dir", type=Path, default=report.ROOT / "build" / "startup",
                        help="where the baseline's clone and venv are made (kept between runs)")
    parser.add_argument("--parts", default=",".join(PARTS), help=f"which parts to run, of {','.join(PARTS)}")
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    parser.add_argument("--inputs", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(args.worker, args.inputs)
        return
    parts = [p for p in args.parts.split(",") if p]
    unknown = set(parts) - set(PARTS)
    if unknown:
        parser.error(f"unknown parts {sorted(unknown)}; parts: {','.join(PARTS)}")
    args.build_dir.mkdir(parents=True, exist_ok=True)
    loads = [report.load()]
    lines: list[str] = []
    with tempfile.TemporaryDirectory(prefix="metaik-startup-") as folder:
        scratch = Path(folder)
        filled = scratch / "warm-cache"
        if "cold" in parts:
            part, filled = cold(scratch)
            lines += part
        elif {"warm", "cache"} & set(parts):  # the cache filled first
            _python(_EXAMPLE, _readme()[0], cache=filled)
            _python(_UR5, cache=filled)
        if "warm" in parts:
            lines += warm(scratch, filled)
        if "cache" in parts:
            lines += cache_lasts(scratch, filled)
        if "suite" in parts:
            lines += suite(scratch)
        if "speed" in parts:
            lines += speed(scratch, args.baseline, args.build_dir)
    loads.append(report.load())
    body = "\n".join(lines)
    print(body)
    if parts == list(PARTS):
        intro = ("What a new user waits for: the first answer after an install (the package's compiled code built "
                 "for this machine and cached by content in the user's cache folder), after that in a new "
                 "process, after a reinstall or an edit; how long the tests take; and the speed once loaded, side "
                 "by side with the commit before the start-up work.\n")
        report.write(OUT, "Start-up time, the cache, and the speed held", intro + "\n" + body, loads=tuple(loads))
        print(f"wrote {OUT.relative_to(report.ROOT)}")


if __name__ == "__main__":
    main()
