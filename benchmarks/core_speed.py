"""The compiled core against the framework before it, side by side: same machine, same run, same inputs.

Four measurements, each taken with this checkout and with a baseline commit (default ``ef3b923``, the last one
before the compiled core; checked out into a temporary git worktree), in separate processes, alternated twice
so that load drift hits both alike; the better of the two runs of each is kept:

1. **Paper 000's four coordinated-IK targets** (mobile dual youBot, tasks/youbot_dual_coordinated_ik.toml, the
   problem built once): median wall time of 10 passes of 20 hybrid solves (seeds 0-19, tolerance 1e-12; a seed
   gives the same answer in every pass), the largest task error, and the largest cost against the median cost of
   20 ``cmaes_fast`` runs with the paper's settings (λ 30, 1000 iterations) — the hybrid must find the same
   optimum.
2. **cmaes_fast, paper 000 settings** (λ 30, 1000 iterations), target 1: wall time per solve (median of 5).
3. **Paper 000's four 200-point paths** tracked by the hybrid (the tasks' weights, from the paper's q_prev, the
   task first): seconds per path and the largest position error along it.
4. **Problem.cost** of target 1 at pop 30 and 1000: µs per call, and the share of it spent in the population
   forward kinematics (the FK kernel alone on the same population).

    python benchmarks/core_speed.py [--baseline ef3b923]

Writes docs/results/core_speed.md.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import report  # noqa: E402

OUT = report.ROOT / "docs" / "results" / "core_speed.md"
PATHS = ("sinusoidal", "circular", "trapezoidal", "rose")
#: Passes over the 20 seeds of each target (the median is over all of them).
PASSES = 10
Q_PREV = [0, 0, np.pi / 2, -np.pi / 2, np.pi / 2, -np.pi / 4, np.pi / 4, 0, np.pi / 2, np.pi / 2, -np.pi / 4,
          np.pi / 4, 0]


def measure() -> dict:
    """Every measurement with whichever ``framework`` is importable (this checkout or the baseline)."""
    import framework
    from framework import solve
    from framework.tracking import TrackingTask, track

    try:  # the folders by layer
        from framework.io.taskfile import load_task
        from framework.tracking.paths import paper000
    except ImportError:  # a baseline from before them
        from framework.taskfile import load_task
        from framework.trajectory import paper000

    root = Path(framework.__file__).resolve().parents[1]
    task = load_task(root / "tasks" / "youbot_dual_coordinated_ik.toml")
    out: dict = {"targets": [], "paths": {}}
    for case in task.cases:
        p = case.problem
        solve(p, "hybrid", seed=0)
        solve(p, "cmaes_fast", seed=0, max_iterations=10)
        times, errors, costs = [], [], []
        for _ in range(PASSES):  # 200 solves of ~0.15 ms per target, not 20
            for s in range(20):
                t = time.perf_counter()
                r = solve(p, "hybrid", seed=s, tolerance=1e-12)
                times.append(time.perf_counter() - t)
                errors.append(r.task_error)
                costs.append(r.cost)
        cma = [solve(p, "cmaes_fast", seed=s, max_iterations=1000).cost for s in range(20)]
        out["targets"].append({"name": case.name, "median_ms": 1e3 * float(np.median(times)),
                               "max_error": float(max(errors)), "max_cost": float(max(costs)),
                               "cmaes_median_cost": float(np.median(cma))})
    p = task.cases[0].problem
    runs = []
    for s in range(5):
        t = time.perf_counter()
        solve(p, "cmaes_fast", seed=s, max_iterations=1000)
        runs.append(time.perf_counter() - t)
    out["cmaes_fast_ms"] = 1e3 * float(np.median(runs))
    robot = p.robot
    weights = {"frame": "arm1_ee", "follower": "arm2_ee", "offset": (0.2, -0.3, -0.2), "position_weight": 1.2,
               "motion": {"base": 0.1, "arm1": 0.4, "arm2": 0.4}}
    budget = report.track_budget(track, 300, 1e-4)  # the same in either checkout
    extra: dict = {}  # the task first (the default now; the baseline's hybrid reached every point as well)
    for name in PATHS:
        path = paper000(name)
        track(robot, path[:3], TrackingTask(**weights), solver="hybrid", initial=np.array(Q_PREV), progress=False,
              **budget, **extra)
        t = time.perf_counter()
        result = track(robot, path, TrackingTask(**weights), solver="hybrid", initial=np.array(Q_PREV),
                       progress=False, **budget, **extra)
        out["paths"][name] = {"seconds": time.perf_counter() - t, "points": len(result),
                              "max_error": float(result.position_error.max())}
    rng = np.random.default_rng(0)
    for pop in (30, 1000):
        X = robot.random_configurations(rng, pop)
        frames = ("arm1_ee", "arm2_ee")
        cost = _per_call(lambda: p.cost(X), 3000 // (1 + pop // 100))
        fk = _per_call(lambda: robot.frame_poses(X, frames), 3000 // (1 + pop // 100))
        out[f"cost_{pop}"] = {"cost_us": cost, "fk_us": fk}
    return out


def _per_call(f, repeat: int) -> float:
    f()
    t = time.perf_counter()
    for _ in range(repeat):
        f()
    return 1e6 * (time.perf_counter() - t) / repeat


def run(folder: Path) -> dict:
    env = {"PYTHONPATH": str(folder), "PATH": "/usr/bin:/bin", "HOME": str(Path.home()),
           "OPENBLAS_NUM_THREADS": "1"}
    code = f"import sys; sys.path.insert(0, {str(Path(__file__).resolve().parent)!r}); import core_speed, json; " \
           "print(json.dumps(core_speed.measure()))"
    done = subprocess.run([sys.executable, "-c", code], cwd=folder, env=env, capture_output=True, text=True)
    if done.returncode:
        raise SystemExit(done.stderr[-2000:])
    return json.loads(done.stdout.strip().splitlines()[-1])


def better(a: dict, b: dict) -> dict:
    """Of two runs, the faster figures (the slower one met more load)."""
    out = json.loads(json.dumps(a))
    for i, t in enumerate(b["targets"]):
        out["targets"][i]["median_ms"] = min(a["targets"][i]["median_ms"], t["median_ms"])
    out["cmaes_fast_ms"] = min(a["cmaes_fast_ms"], b["cmaes_fast_ms"])
    for name in PATHS:
        out["paths"][name]["seconds"] = min(a["paths"][name]["seconds"], b["paths"][name]["seconds"])
    for pop in (30, 1000):
        key = f"cost_{pop}"
        if b[key]["cost_us"] < a[key]["cost_us"]:
            out[key] = b[key]
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", default="ef3b923")
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    before = report.load()
    with tempfile.TemporaryDirectory() as tmp:
        worktree = Path(tmp) / "baseline"
        subprocess.run(["git", "worktree", "add", "--detach", str(worktree), args.baseline], cwd=report.ROOT,
                       check=True, capture_output=True)
        try:
            runs = {"baseline": [], "now": []}
            for _ in range(2):
                runs["baseline"].append(run(worktree))
                runs["now"].append(run(report.ROOT))
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(worktree)], cwd=report.ROOT,
                           capture_output=True)
    old, new = (better(*runs[k]) for k in ("baseline", "now"))
    body = table(old, new, args.baseline)
    print(body)
    report.write(args.out, "The compiled core against the framework before it", body, loads=(before, report.load()))


def table(old: dict, new: dict, baseline: str) -> str:
    lines = [__doc__.split("\n\n")[1].strip(), "", __doc__.split("\n\n")[2].strip(), "",
             f"Baseline: commit `{baseline}`. Each figure is the better of two runs.", "",
             "## Paper 000's four targets: the hybrid", "",
             "| target | median ms now | median ms baseline | speed-up | max task error now [m] | max cost now | "
             "cmaes_fast median cost | cost − median |", "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for t_new, t_old in zip(new["targets"], old["targets"]):
        lines.append(f"| {t_new['name']} | {t_new['median_ms']:.3f} | {t_old['median_ms']:.3f} | "
                     f"{t_old['median_ms'] / t_new['median_ms']:.1f}x | {t_new['max_error']:.1e} | "
                     f"{t_new['max_cost']:.12f} | {t_new['cmaes_median_cost']:.12f} | "
                     f"{t_new['max_cost'] - t_new['cmaes_median_cost']:+.1e} |")
    lines += ["", "## cmaes_fast, λ 30, 1000 iterations (target 1)", "",
              "| now ms | baseline ms | speed-up |", "|---:|---:|---:|",
              f"| {new['cmaes_fast_ms']:.1f} | {old['cmaes_fast_ms']:.1f} | "
              f"{old['cmaes_fast_ms'] / new['cmaes_fast_ms']:.1f}x |",
              "", "## Paper 000's paths, 200 points, hybrid", "",
              "| path | s per path now | baseline | speed-up | max position error now [m] | baseline [m] |",
              "|---|---:|---:|---:|---:|---:|"]
    for name in PATHS:
        a, b = new["paths"][name], old["paths"][name]
        lines.append(f"| {name} | {a['seconds']:.3f} | {b['seconds']:.3f} | {b['seconds'] / a['seconds']:.0f}x | "
                     f"{a['max_error']:.1e} | {b['max_error']:.1e} |")
    lines += ["", "## Problem.cost, target 1 (13 DOF, two frames)", "",
              "| population | µs now | FK share now | µs baseline | FK share baseline | speed-up |",
              "|---:|---:|---:|---:|---:|---:|"]
    for pop in (30, 1000):
        a, b = new[f"cost_{pop}"], old[f"cost_{pop}"]
        lines.append(f"| {pop} | {a['cost_us']:.1f} | {100 * min(1.0, a['fk_us'] / a['cost_us']):.0f} % | "
                     f"{b['cost_us']:.1f} | {100 * min(1.0, b['fk_us'] / b['cost_us']):.0f} % | "
                     f"{b['cost_us'] / a['cost_us']:.1f}x |")
    lines += ["", "FK share = time of `robot.frame_poses(X, frames)` (the compiled FK of the same population, called "
              "alone) over the time of `Problem.cost(X)`, which computes that FK and every term in one pass."]
    return "\n".join(lines)


if __name__ == "__main__":
    main()
