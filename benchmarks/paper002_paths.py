"""Paper 002 (MetaPAT), Tables 5-10 and Figs. 4-11: circle and lemniscate with orientation for four single arms.

Run (about 4 min on 2 cores; runs cached in --cache and resumable; --report-only rewrites the document from them):

    python benchmarks/paper002_paths.py -j 2
    python benchmarks/paper002_paths.py --report-only

Setup (paper 002 section 5): robots youbot_arm, puma560, baxter_arm, fanuc_am120ib; the task files
tasks/paper002_{youbot,puma,baxter,fanuc}_{circle,lemniscate}.toml (f = 0.7143 d_err + 0.1786 q_err + 0.1071 r_err,
R_d = Ry(π/2), circles and Bernoulli lemniscates in the plane x = C_x, 32 circle and 73 lemniscate poses: the
numbers of poses the paper's sign tests count); solvers DE, PSO, DEMPSO, ICA, HBBO, WOA, SCA with population 30 and
500 iterations per pose, plus our hybrid. One run per pose and solver (the paper: 30 runs per pose, median), each
warm-started from the previous pose's solution; the first pose from the centre of the joint box.

Writes docs/results/paper002_paths.md and docs/results/figures/paper002_*.png.
"""

from __future__ import annotations

import argparse
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import report  # noqa: E402

ROOT = report.ROOT
TITLE = "Paper 002: circle and lemniscate with orientation (youBot, Puma 560, Baxter, Fanuc)"
RESULTS = ROOT / "docs" / "results"
FIGURES = RESULTS / "figures"
REPORT = RESULTS / "paper002_paths.md"

ROBOTS = {"youbot": "youbot_arm", "puma": "puma560", "baxter": "baxter_arm", "fanuc": "fanuc_am120ib"}
PATHS = ("circle", "lemniscate")
SOLVERS = ("de", "pso", "dempso", "ica", "hbbo", "woa", "sca", "hybrid")
#: Paper 002's settings where they differ from the registry defaults (DEMPSO schedules of paper 002).
OPTIONS = {
    "dempso": {"w_start": 0.9, "w_end": 0.1, "c1_start": 2.0, "c1_end": 0.1, "c2_start": 0.1, "c2_end": 2.0}
}
ITERATIONS, POPULATION, SEED = 500, 30, 0
#: Further seeds of the hybrid (its restarts are random): the spread of its f mean beside the one-run table.
HYBRID_SEEDS = (1, 2, 3, 4, 5)
#: A waypoint's success threshold [m, rad] (what these documents have always used; the solvers' own default is
#: 1e-6).
TOLERANCE = 1e-4

#: Paper 002, mean position error [m] (Table 5 circle, Table 8 lemniscate) and mean objective (Tables 7, 10).
PAPER_POSITION = {
    "circle": {
        "youbot": (4.34e-18, 5.74e-3, 1.09e-3, 1.44e-5, 7.14e-5, 8.55e-3, 1.00e-2),
        "puma": (3.44e-5, 1.80e-3, 6.68e-5, 2.59e-3, 1.21e-3, 1.65e-2, 3.97e-2),
        "baxter": (6.11e-5, 2.72e-3, 1.04e-7, 2.33e-9, 2.25e-16, 1.50e-3, 3.95e-2),
        "fanuc": (1.30e-5, 7.62e-3, 2.14e-2, 1.60e-4, 4.74e-4, 3.27e-3, 6.64e-2),
    },
    "lemniscate": {
        "youbot": (2.78e-12, 6.65e-3, 1.48e-3, 4.62e-5, 7.94e-4, 8.42e-3, 1.04e-2),
        "puma": (3.41e-5, 1.01e-3, 5.95e-5, 7.43e-4, 1.05e-3, 1.43e-2, 4.43e-2),
        "baxter": (1.85e-4, 1.23e-3, 2.32e-7, 4.05e-8, 1.55e-7, 1.33e-3, 3.97e-2),
        "fanuc": (1.01e-5, 7.44e-3, 4.28e-2, 1.36e-4, 1.04e-3, 7.48e-3, 7.66e-2),
    },
}
PAPER_OBJECTIVE = {
    "circle": {
        "youbot": (2.54e-2, 3.59e-2, 1.08e-1, 2.74e-2, 2.67e-2, 5.12e-2, 3.69e-2),
        "puma": (5.19e-5, 1.32e-2, 1.66e-3, 2.01e-3, 3.21e-3, 7.74e-2, 6.35e-2),
        "baxter": (7.39e-4, 4.24e-2, 1.40e-2, 3.23e-2, 2.03e-2, 8.35e-2, 7.62e-2),
        "fanuc": (9.90e-3, 4.68e-2, 4.69e-2, 1.20e-2, 2.59e-2, 1.48e-1, 1.21e-1),
    },
    "lemniscate": {
        "youbot": (2.58e-2, 3.45e-2, 1.24e-1, 2.68e-2, 2.69e-2, 4.60e-2, 3.64e-2),
        "puma": (5.06e-5, 5.40e-3, 2.96e-4, 5.84e-4, 2.51e-3, 6.48e-2, 6.26e-2),
        "baxter": (1.63e-4, 2.87e-2, 1.04e-2, 2.72e-2, 1.59e-2, 7.82e-2, 7.66e-2),
        "fanuc": (8.44e-3, 3.49e-2, 7.73e-2, 1.18e-2, 2.26e-2, 1.43e-1, 1.19e-1),
    },
}
PAPER_SOLVERS = SOLVERS[:7]


def run_one(robot: str, path: str, solver: str, cache: Path) -> str:
    """One tracking run; ``solver`` may be ``"hybrid@s"``: the hybrid with seed ``s`` instead of :data:`SEED`."""
    from framework.io.taskfile import load_task
    from framework.tracking import track

    name, _, seed = solver.partition("@")
    seed = int(seed) if seed else SEED

    task = load_task(ROOT / "tasks" / f"paper002_{robot}_{path}.toml")
    case = task.cases[0]

    def run(trajectory):
        return track(task.robot, trajectory, case.builder, solver=name, seed=seed, max_iterations=ITERATIONS,
                     tolerance=TOLERANCE, population=POPULATION, initial=case.initial, options=OPTIONS.get(name),
                     priorities=task.priorities, progress=False)

    run(case.trajectory[:2])  # untimed: a process's first run loads (on a new machine, compiles) the kernels
    result = run(case.trajectory)
    np.savez(
        cache / f"{robot}_{path}_{solver}.npz",
        Q=result.configurations,
        position=result.terms["d_err"],
        orientation=result.terms["q_err"],
        motion=result.terms["r_err"],
        cost=result.cost,
        times=result.times,
        wall_time=result.wall_time,
        cpu_time=result.cpu_time,
    )
    return (
        f"{robot:7s} {path:10s} {solver:7s} pos {result.terms['d_err'].mean():.2e}  {result.wall_time:6.1f} s"
    )


def reach_floor(robot: str, path: str, cache: Path) -> str:
    """Per pose, the smallest position error of 4 position-only hybrid solves (seeds 0-3): the reach floor [m]."""
    from framework.costs import Position
    from framework.costs.problem import Problem
    from framework.solvers.solve import solve
    from framework.io.taskfile import load_task

    task = load_task(ROOT / "tasks" / f"paper002_{robot}_{path}.toml")
    floor = np.array(
        [
            min(solve(Problem(task.robot, Position("ee", t)), "hybrid", seed=s).task_error for s in range(4))
            for t in task.cases[0].trajectory.positions
        ]
    )
    np.savez(cache / f"{robot}_{path}_reach.npz", position=floor)
    return f"{robot:7s} {path:10s} reach   floor {floor.mean():.2e}"


def run_grid(solvers: list[str], jobs: int, cache: Path) -> None:
    cache.mkdir(parents=True, exist_ok=True)
    todo = [
        (r, p, s) for s in solvers for r in ROBOTS for p in PATHS if not (cache / f"{r}_{p}_{s}.npz").exists()
    ]
    todo += [(r, p, "reach") for r in ROBOTS for p in PATHS if not (cache / f"{r}_{p}_reach.npz").exists()]
    if "hybrid" in solvers:
        todo += [(r, p, f"hybrid@{k}") for k in HYBRID_SEEDS for r in ROBOTS for p in PATHS
                 if not (cache / f"{r}_{p}_hybrid@{k}.npz").exists()]
    print(f"{len(todo)} runs to do with {jobs} processes", flush=True)
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        futures = [
            pool.submit(
                reach_floor if job[2] == "reach" else run_one, *(job[:2] if job[2] == "reach" else job), cache
            )
            for job in todo
        ]
        for future in as_completed(futures):
            print(future.result(), flush=True)


def load(cache: Path, solvers: list[str]) -> dict:
    runs = {}
    for r in ROBOTS:
        for p in PATHS:
            for s in [*solvers, "reach", *(f"hybrid@{k}" for k in HYBRID_SEEDS if "hybrid" in solvers)]:
                f = cache / f"{r}_{p}_{s}.npz"
                if f.exists():
                    with np.load(f) as data:
                        runs[r, p, s] = {k: data[k] for k in data.files}
    return runs


def write_report(runs: dict, solvers: list[str], loads: tuple[float, float] | None = None) -> None:
    """The document from the cached ``runs``; ``loads``: the load average before and after the runs (none
    with ``--report-only``)."""
    lines = [
        "Setup (paper 002): f = 0.7143 d_err + 0.1786 q_err + 0.1071 r_err (d_err [m], q_err = |sin(φ/2)| of the "
        "orientation error, r_err = ‖r_i − r_{i−1}‖₁ / (n π)), R_d = Ry(π/2) at every pose, population 30, "
        f"{ITERATIONS} iterations per pose, solver settings of paper 002 (DEMPSO: w 0.9→0.1, c1 2→0.1, c2 0.1→2).",
        "",
        "Our choices and differences:",
        "",
        "- **Poses**: 32 per circle and 73 per lemniscate, the numbers of poses the paper's sign tests count "
        "(Tables 6 and 9); the paper does not state them otherwise.",
        "- **One run per pose** and solver (the paper: 30 runs per pose, median), warm-started from the previous "
        "pose's solution (`track(..., warm_spread=0.02)`); the first pose from the centre of the joint box (the "
        "paper gives no initial configuration).",
        "- **Paths** in the plane x = C_x (the paper's Test 3 targets lie on the circles in that plane); the "
        'lemniscate is Bernoulli\'s, r² = a² cos 2φ (the paper writes only "r = a cos θ").',
        "- **Robots**: the DH tables of SPEC, bases at the origin. With these models part of the paths is out of "
        "reach: the top of the youBot circle (z > 0.53 m is beyond 0.5075 m from joint 2), Baxter's poses with "
        "y > 0.66 m (arm base at the origin), and R_d is reachable by the 5-DOF youBot nowhere on the paths and "
        "by the Fanuc only on part of them. The paper reports near-zero position errors everywhere, so its base "
        "frames or tool frames differ from these DH tables; the *reach* column gives, per pose, the smallest "
        "position error our hybrid finds with position alone (multi-start), a floor for every solver.",
        "- **hybrid** (ours) is listed for reference.",
        "",
        "Position error d_err [m], orientation error q_err, joint error r_err and objective f per pose: mean (and "
        "worst) over the poses. Paper: mean position error (Tables 5, 8) and mean objective (Tables 7, 10).",
        "",
    ]
    for path in PATHS:
        table = "Tables 5 and 7" if path == "circle" else "Tables 8 and 10"
        lines += [f"## {path.capitalize()} ({table})", ""]
        for robot in ROBOTS:
            present = [s for s in solvers if (robot, path, s) in runs]
            if not present:
                continue
            lines += [
                f"### {ROBOTS[robot]}",
                "",
                "| | " + " | ".join(s.upper() if s != "hybrid" else "hybrid" for s in present) + " |",
                "|---|" + "---:|" * len(present),
            ]

            def row(label, fn):
                lines.append(f"| {label} | " + " | ".join(fn(runs[robot, path, s]) for s in present) + " |")

            row("d_err mean [m]", lambda r: f"{r['position'].mean():.2e}")
            if (robot, path, "reach") in runs:
                floor = runs[robot, path, "reach"]["position"]
                row(
                    "d_err mean above the reach floor [m]",
                    lambda r: f"{np.maximum(r['position'] - floor, 0).mean():.2e}",
                )
                lines.append(
                    f"| reach floor: d_err mean / poses out of reach (> 1e-6 m) | "
                    f"{floor.mean():.2e} / {int((floor > 1e-6).sum())} of {len(floor)} |"
                    + " |"
                    * (len(present) - 1)
                )
            row("d_err worst [m]", lambda r: f"{r['position'].max():.2e}")
            row("q_err mean", lambda r: f"{r['orientation'].mean():.2e}")
            row("r_err mean", lambda r: f"{r['motion'].mean():.2e}")
            row("f mean", lambda r: f"{r['cost'].mean():.2e}")
            row("time per pose [s]", lambda r: f"{float(r['wall_time']) / len(r['position']):.2f}")
            paper_pos = dict(zip(PAPER_SOLVERS, PAPER_POSITION[path][robot]))
            paper_f = dict(zip(PAPER_SOLVERS, PAPER_OBJECTIVE[path][robot]))
            lines.append(
                "| paper: d_err mean | "
                + " | ".join(f"{paper_pos[s]:.2e}" if s in paper_pos else "–" for s in present)
                + " |"
            )
            lines.append(
                "| paper: f mean | "
                + " | ".join(f"{paper_f[s]:.2e}" if s in paper_f else "–" for s in present)
                + " |"
            )
            lines += ["", f"![{robot} {path}](figures/paper002_{robot}_{path}.png)", ""]
    lines += hybrid_seed_lines(runs)
    lines += sign_test_lines(runs, solvers)
    report.write(REPORT, TITLE, "\n".join(lines), loads=loads)
    print(f"wrote {REPORT}")


def hybrid_seed_lines(runs: dict) -> list[str]:
    """The hybrid's f mean per path for seed :data:`SEED` (the tables) and :data:`HYBRID_SEEDS`: its restarts are
    random, and where a pose is out of reach or has several optima the answer depends on them."""
    seeds = (SEED, *HYBRID_SEEDS)
    keys = ["hybrid" if k == SEED else f"hybrid@{k}" for k in seeds]
    if not all((r, p, key) in runs for r in ROBOTS for p in PATHS for key in keys):
        return []
    lines = [
        "## The hybrid over seeds",
        "",
        f"The hybrid's f mean per path with seeds {', '.join(map(str, seeds))} (the tables above: seed {SEED}). "
        "Its random restarts (drawn when the warm start's basin misses the task, which is every pose out of reach) "
        "decide which of several optima a pose ends in, and a tracked path stays on the branch it is on: one run's "
        "f mean is one sample of this spread.",
        "",
        "| path | robot | " + " | ".join(f"seed {k}" for k in seeds) + " | min / median / max |",
        "|---|---|" + "---:|" * (len(seeds) + 1),
    ]
    for path in PATHS:
        for robot in ROBOTS:
            f = np.array([runs[robot, path, key]["cost"].mean() for key in keys])
            lines.append(f"| {path} | {ROBOTS[robot]} | " + " | ".join(f"{v:.2e}" for v in f)
                         + f" | {f.min():.2e} / {np.median(f):.2e} / {f.max():.2e} |")
    return lines + [""]


def sign_test_lines(runs: dict, solvers: list[str], reference: str = "de") -> list[str]:
    """Paper 002 Tables 6 and 9: the sign test of DE against each solver on the objective f, paired by pose."""
    from framework.bench.stats import sign_test

    lines = [
        "## Sign tests (Tables 6 and 9)",
        "",
        f"{reference.upper()} against each solver on the objective f of every pose (paired by pose; a pair within "
        "1e-12 is a tie); wins = poses where DE's f is lower; p = exact two-sided binomial p-value. The paper: DE "
        "wins against every other algorithm at p < 0.05.",
        "",
    ]
    for path in PATHS:
        others = [s for s in solvers if s != reference]
        lines += [f"### {path}", "", "| robot | " + " | ".join(o.upper() if o != "hybrid" else "hybrid"
                                                            for o in others) + " |",
                  "|---|" + "---:|" * len(others)]
        for robot in ROBOTS:
            if (robot, path, reference) not in runs:
                continue
            cells = []
            for other in others:
                if (robot, path, other) not in runs:
                    cells.append("–")
                    continue
                t = sign_test(runs[robot, path, reference]["cost"], runs[robot, path, other]["cost"], atol=1e-12)
                cells.append(f"{t.wins}/{t.losses} (p={t.p_value:.2g})")
            lines.append(f"| {ROBOTS[robot]} | " + " | ".join(cells) + " |")
        lines.append("")
    lines += [
        "## Reading the results",
        "",
        "- Where the path is within reach of these models (Puma 560, Fanuc), DE tracks the position to 1e-12 m or better, "
        "below the paper's DE (3.4e-5 m and 1.3e-5 m on the circle), and WOA and SCA are the worst, as in the paper.",
        "- On the youBot and the Baxter the position error is dominated by the reach floor (poses our models cannot "
        "reach, see above); above that floor DE and HBBO are the best on the youBot, PSO and ICA on the Baxter.",
        "- Sign tests: as in the paper, DE beats WOA and SCA on every robot and path (p < 0.01); against PSO, ICA, "
        "HBBO and DEMPSO the result depends on the robot (the paper: DE beats all six at p < 0.05). One run per pose "
        "here, against the paper's median of 30.",
        "- The hybrid (ours) minimizes the same f from the previous pose's solution with the compiled local engine "
        "(the weighted sum as the paper states it, by active sets of the task terms): "
        "it has the lowest or near-lowest f on the Puma and Fanuc circles, but as a local method it follows the "
        "branch it starts on, where DE's population can switch branch" + _branch_note(runs, reference) + ".",
        "",
    ]
    return lines


def _branch_note(runs: dict, reference: str) -> str:
    """`` (the youBot lemniscate: DE lower on w of N poses)`` from the runs (empty without them)."""
    from framework.bench.stats import sign_test

    key = ("youbot", "lemniscate")
    if (*key, reference) not in runs or (*key, "hybrid") not in runs:
        return ""
    theirs, ours = runs[(*key, reference)]["cost"], runs[(*key, "hybrid")]["cost"]
    t = sign_test(theirs, ours, atol=1e-12)
    return f" (the youBot lemniscate: {reference.upper()} lower on {t.wins} of {len(ours)} poses)"


def write_figures(runs: dict, solvers: list[str]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    FIGURES.mkdir(parents=True, exist_ok=True)
    for robot in ROBOTS:
        for path in PATHS:
            present = [s for s in solvers if (robot, path, s) in runs]
            if not present:
                continue
            fig, axes = plt.subplots(1, 4, figsize=(18, 4))
            for ax, (key, title) in zip(
                axes,
                (
                    ("position", "position error d_err [m]"),
                    ("orientation", "orientation error q_err"),
                    ("motion", "joint error r_err"),
                    ("times", "time per pose [s]"),
                ),
            ):
                data = [np.maximum(runs[robot, path, s][key], 1e-17) for s in present]
                ax.boxplot(data)
                ax.set_xticks(
                    range(1, len(present) + 1),
                    [s.upper() if s != "hybrid" else "hyb" for s in present],
                    rotation=30,
                )
                ax.set_yscale("log")
                ax.set_title(f"{ROBOTS[robot]} {path}: {title}", fontsize=9)
            fig.tight_layout()
            fig.savefig(FIGURES / f"paper002_{robot}_{path}.png", dpi=100)
            plt.close(fig)
    print(f"wrote figures to {FIGURES}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-j", "--jobs", type=int, default=2)
    parser.add_argument("--solvers", default=",".join(SOLVERS))
    parser.add_argument("--cache", type=Path, default=Path("/tmp/metaik_paper002_paths"))
    parser.add_argument("--report-only", action="store_true")
    args = parser.parse_args(argv)
    solvers = [s for s in args.solvers.split(",") if s]
    start, before = time.perf_counter(), report.load()
    if not args.report_only:
        run_grid(solvers, args.jobs, args.cache)
    runs = load(args.cache, solvers)
    write_report(runs, solvers, None if args.report_only else (before, report.load()))
    write_figures(runs, solvers)
    print(f"done in {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
