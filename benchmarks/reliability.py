"""Reliability: every known bad input, xacro escape attempts, kills at random moments, random robots.

1. Bad inputs: each case of ``tests/fuzz/bad_inputs.py`` through the CLI (exit 2, one line on stderr naming the
   field, no traceback) or the API (our ``MetaikError`` naming the field).
2. Xacro escapes: each attempt of ``tests/fuzz/escapes.py`` put into a robot file: ``load_robot`` must raise
   ``RobotFileError`` and leave no file behind.
3. Kills: ``metaik run paper000_sinusoidal --solver cmaes --output --record`` killed (SIGKILL) or interrupted
   (SIGINT) at a random moment; the CSV's rows must equal the first rows of an uninterrupted run of the same seed,
   and the recording must read back with every CSV waypoint posed (a SIGKILL between the CSV row and the
   recording may leave the last one out). ``metaik bench -j 2`` killed at a random moment, then resumed: no worker
   left running, no duplicate row, and the resumed results equal an uninterrupted bench's, run by run. Two benches
   started together on the same results file: each run stored once.
4. Random robots (``tests/fuzz/trees.py``): population FK against Pinocchio's, frame Jacobians against central
   differences, and the hybrid on the FK pose (position + orientation) of a random configuration of the deepest
   leaf, checked with Pinocchio's FK at 1e-9 m / 1e-9 rad.

Usage: ``python benchmarks/reliability.py [--trees 400] [--kills 6]``.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402
import report  # noqa: E402

import framework as fw  # noqa: E402
from framework.cli import EXIT_INPUT, EXIT_INTERRUPTED, main as cli  # noqa: E402
from framework.errors import MetaikError, RobotFileError  # noqa: E402
from framework.io.recording import read_recording  # noqa: E402
from tests.fuzz.bad_inputs import API_CASES, CLI_CASES  # noqa: E402
from tests.fuzz.escapes import ARM, ESCAPES  # noqa: E402
from tests.fuzz.references import fk_difference, jacobian_difference, reach_reachable_pose  # noqa: E402
from tests.fuzz.trees import random_tree  # noqa: E402
from tests.processes import alive, children  # noqa: E402

OUT = report.ROOT / "docs" / "reliability.md"
RUN = ["run", "paper000_sinusoidal", "--solver", "cmaes", "--points", "40", "--no-progress"]
BENCH_TASK = """
[task]
name = "kill"
robot = "youbot_arm"
[solver]
name = "de"
population = 20
max_iterations = 400
[bench]
solvers = ["de", "pso"]
runs = 8
[[terms]]
type = "position"
frame = "ee"
target = [0.3, 0.0, 0.3]
"""


def bad_inputs() -> tuple[Counter, Counter, list[str]]:
    """Cases tried and cases handled (our error, field named; CLI: exit 2, one line) per category."""
    tried, handled, failures = Counter(), Counter(), []
    with tempfile.TemporaryDirectory() as folder:
        cwd = os.getcwd()
        os.chdir(folder)
        try:
            for case in CLI_CASES:
                argv = list(case.argv)
                if case.file_text is not None:
                    Path("t.toml").write_text(case.file_text)
                    argv = [a.replace("{file}", "t.toml") for a in argv]
                err = io.StringIO()
                try:
                    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
                        code = cli(argv)
                except BaseException as exc:  # noqa: BLE001 - a crash is what this counts
                    code = f"{type(exc).__name__}"
                text = err.getvalue()
                ok = code == EXIT_INPUT and text.count("\n") == 1 and all(n in text for n in case.names)
                tried[f"CLI, {case.category}"] += 1
                handled[f"CLI, {case.category}"] += ok
                if not ok:
                    failures.append(f"CLI {case.id}: {code} {text.strip()[:200]}")
        finally:
            os.chdir(cwd)
    for case in API_CASES:
        tried["API"] += 1
        try:
            case.call()
            failures.append(f"API {case.id}: no error")
        except MetaikError as err:
            ok = all(n in str(err) for n in case.names)
            handled["API"] += ok
            if not ok:
                failures.append(f"API {case.id}: {err}")
        except Exception as err:  # noqa: BLE001
            failures.append(f"API {case.id}: {type(err).__name__}: {err}")
    return tried, handled, failures


def escapes() -> tuple[int, int]:
    """(attempts, blocked): blocked = RobotFileError and no marker file written."""
    blocked = 0
    for expression in ESCAPES.values():
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / "arm.urdf.xacro"
            extra = f'<link name="probe"><visual><origin xyz="{expression} 0 0"/></visual></link>'
            path.write_text(ARM.replace("EXTRA", extra))
            try:
                fw.load_robot(path)
            except RobotFileError:
                blocked += not any(p.name != path.name for p in Path(folder).iterdir())
    return len(ESCAPES), blocked


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(report.ROOT), "PYTHONUNBUFFERED": "1"}


def _rows(path: Path) -> list[str]:
    return path.read_text().splitlines() if path.exists() else []


def kill_runs(kills: int, rng: np.random.Generator) -> dict[str, list]:
    """Kill ``metaik run`` at random moments (SIGKILL and SIGINT, alternately); what each one kept."""
    out: dict[str, list] = {"SIGKILL": [], "SIGINT": []}
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        command = [sys.executable, "-m", "framework.cli", *RUN]
        for _ in range(2):  # the second run's time: without compiling (kills land within a warm run)
            start = time.perf_counter()
            subprocess.run([*command, "--output", str(folder / "full.csv"), "--record", str(folder / "full.rrd")],
                           env=_env(), cwd=folder, check=True, capture_output=True)
            duration = time.perf_counter() - start
        reference = _rows(folder / "full.csv")
        for k in range(kills):
            how = ("SIGKILL", "SIGINT")[k % 2]
            csv, rrd = folder / f"k{k}.csv", folder / f"k{k}.rrd"
            process = subprocess.Popen([*command, "--output", str(csv), "--record", str(rrd)], env=_env(), cwd=folder,
                                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            time.sleep(float(rng.uniform(0.1, 0.8)) * duration)
            process.send_signal(getattr(signal, how))
            _, err = process.communicate(timeout=300)
            rows = _rows(csv)
            matching = sum(a == b for a, b in zip(rows, reference))
            try:
                posed = len(read_recording(rrd).configurations("waypoint")[1])
            except MetaikError:
                posed = 0
            waypoints = max(len(rows) - 1, 0)
            lost = (len(rows) - matching) + max(0, waypoints - posed - (how == "SIGKILL"))
            finished = waypoints == len(reference) - 1 and process.returncode == 0  # done before the signal came
            exit_ok = finished or process.returncode == (-signal.SIGKILL if how == "SIGKILL" else EXIT_INTERRUPTED)
            out[how].append(dict(waypoints=waypoints, of=len(reference) - 1, posed=posed, lost=lost, exit_ok=exit_ok))
            print(how, out[how][-1], flush=True)
    return out


def _results(path: Path) -> dict[tuple, float]:
    runs: dict[tuple, float] = {}
    duplicates = 0
    for line in path.read_text().splitlines():
        record = json.loads(line)
        key = (record["case"], record["solver"], record["seed"])
        duplicates += key in runs
        runs[key] = record["task_error"]
    return runs, duplicates


def kill_benches(kills: int, rng: np.random.Generator) -> dict[str, object]:
    """SIGKILL ``metaik bench -j 2`` at random moments and resume it; then two benches at once on one file."""
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        task = folder / "kill.toml"
        task.write_text(BENCH_TASK)
        base = [sys.executable, "-m", "framework.cli", "bench", str(task), "-j", "2", "--no-figures"]
        start = time.perf_counter()
        subprocess.run([*base, "--out", str(folder / "full")], env=_env(), check=True, capture_output=True)
        duration = time.perf_counter() - start
        reference, _ = _results(folder / "full" / "results.jsonl")
        orphans = unequal = duplicates = 0
        for k in range(kills):
            out = folder / f"k{k}"
            process = subprocess.Popen([*base, "--out", str(out)], env=_env(), stdout=subprocess.DEVNULL,
                                       stderr=subprocess.DEVNULL)
            time.sleep(float(rng.uniform(0.2, 0.8)) * duration)
            workers = children(process.pid)
            process.kill()
            process.wait()
            deadline = time.monotonic() + 20
            while time.monotonic() < deadline and alive(workers):
                time.sleep(0.1)
            orphans += len(alive(workers))
            subprocess.run([*base, "--out", str(out)], env=_env(), check=True, capture_output=True)
            runs, dup = _results(out / "results.jsonl")
            duplicates += dup
            unequal += sum(runs.get(key) != value for key, value in reference.items()) + len(set(runs) - set(reference))
            print("bench kill", k, "orphans", orphans, "duplicates", duplicates, "unequal", unequal, flush=True)
        together = [subprocess.Popen([*base, "-j", "1", "--out", str(folder / "shared")], env=_env(),
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL) for _ in range(2)]
        for process in together:
            process.wait()
        runs, shared_duplicates = _results(folder / "shared" / "results.jsonl")
    return dict(kills=kills, orphans=orphans, duplicates=duplicates, unequal=unequal, runs=len(reference),
                shared_runs=len(runs), shared_duplicates=shared_duplicates)


def random_robots(count: int) -> dict[str, object]:
    """FK and Jacobian errors and hybrid successes over ``count`` random trees (seeds 0 .. count - 1)."""
    fk_error = jac_error = 0.0
    kinds: Counter = Counter()
    successes, misses = 0, []
    for seed in range(count):
        tree = random_tree(seed)
        robot = fw.robot_from_urdf(tree.urdf)
        kinds.update(j.kind.value for j in robot.joints)
        kinds.update("mimic" for _ in robot.mimics)
        X = robot.random_configurations(np.random.default_rng(seed), 3)
        fk_error = max(fk_error, fk_difference(tree, robot, X, tree.leaves))
        jac_error = max(jac_error, jacobian_difference(robot, X, tree.leaves))
        ok, position, angle = reach_reachable_pose(seed)
        if ok and position <= 1e-9 and angle <= 1e-9:
            successes += 1
        else:
            misses.append((seed, position, angle))
    return dict(count=count, kinds=kinds, fk_error=fk_error, jac_error=jac_error, successes=successes, misses=misses)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trees", type=int, default=400)
    parser.add_argument("--kills", type=int, default=6)
    args = parser.parse_args()
    rng = np.random.default_rng(2026)
    before = report.load()
    tried, handled, failures = bad_inputs()
    print("bad inputs", dict(tried), dict(handled), failures, flush=True)
    attempts, blocked = escapes()
    print("escapes", attempts, blocked, flush=True)
    trees = random_robots(args.trees)
    print("trees", trees, flush=True)
    runs = kill_runs(args.kills, rng)
    benches = kill_benches(max(2, args.kills // 2), rng)
    print("benches", benches, flush=True)
    after = report.load()

    lines = [__doc__.split("\n\n", 1)[1].rsplit("\n\nUsage", 1)[0].strip(), "", "## Bad inputs", "",
             "| category | tried | our error, field named (CLI: exit 2, one line) |", "|---|---:|---:|"]
    for category in sorted(tried):
        lines.append(f"| {category} | {tried[category]} | {handled[category]} |")
    lines.append(f"| **all** | **{sum(tried.values())}** | **{sum(handled.values())}** |")
    if failures:
        lines += ["", "Not handled:", "", *[f"- `{f}`" for f in failures]]
    lines += ["", "## Xacro escape attempts", "", f"{blocked} of {attempts} blocked (our error, no side effect).",
              "", "## Kills at random moments", "",
              "| signal | runs | waypoints kept / of (each run) | lost | exit code as expected (or 0 when it finished first) |",
              "|---|---:|---|---:|---:|"]
    for how, items in runs.items():
        kept = ", ".join(f"{i['waypoints']}/{i['of']}" for i in items)
        lines.append(f"| `metaik run` {how} | {len(items)} | {kept} | {sum(i['lost'] for i in items)} | "
                     f"{sum(i['exit_ok'] for i in items)}/{len(items)} |")
    lines += ["", f"`metaik bench -j 2` ({benches['runs']} runs) killed {benches['kills']} times at random moments "
              f"and resumed: {benches['orphans']} workers left running, {benches['duplicates']} duplicate rows, "
              f"{benches['unequal']} runs differing from an uninterrupted bench. Two benches at once on one file: "
              f"{benches['shared_runs']} runs stored, {benches['shared_duplicates']} duplicates.",
              "", "## Random robots", "",
              f"{trees['count']} random trees (joints: "
              + ", ".join(f"{n} {kind}" for kind, n in sorted(trees["kinds"].items()))
              + f"); largest FK difference to Pinocchio {trees['fk_error']:.1e}; largest Jacobian difference to "
              f"central differences (h = 1e-6) {trees['jac_error']:.1e}; hybrid reaching the FK pose of a random "
              f"configuration (position + orientation, 1e-9 m / 1e-9 rad by Pinocchio's FK): "
              f"**{trees['successes']}/{trees['count']}**"
              + (f"; missed seeds {[m[0] for m in trees['misses']]}" if trees["misses"] else "") + "."]
    report.write(OUT, "Reliability: bad inputs, escapes, kills, random robots", "\n".join(lines),
                 loads=(before, after))
    print(OUT.read_text())


if __name__ == "__main__":
    main()
