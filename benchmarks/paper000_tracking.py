"""Paper 000, Tables 8-11 and Figs. 7-10: coordinated trajectory tracking with the mobile dual-arm youBot.

Run (2 cores; the full grid takes 15-30 min on a shared 2-core machine, runs are cached and resumable):

    python benchmarks/paper000_tracking.py -j 2
    python benchmarks/paper000_tracking.py --report-only      # tables + figures from the cache

Setup (paper 000 section 4): robot ``youbot_dual_mobile`` (13 DOF), f = 1.2 (e_t1 + e_t2) + 0.1 e_q0 + 0.4 (e_q1 + e_q2)
(L2 motion to the previous waypoint's solution), q_prev of the paper before the first waypoint, K = 200 points,
300 iterations per point, population 30, infeasible members re-sampled in the box. The paper does not give t_r
for tracking: we use t_r = (0, -0.3, 0) m, the offset of the two end-effectors at the paper's q_prev (holding a
30 cm object). Target 1's t_r = (0.2, -0.3, -0.2) is reachable along all four paths, but at the first point of
the sinusoidal and rose paths the cost's minimum does not reach e_2 (the motion of reaching costs more than
1.2 e_t2: the minimizer leaves e_t2 = 0.029 m and 0.040 m). Our tracker warm-starts every solve from the previous
solution (the paper only uses it as q_prev in the cost): ``cmaes_fast`` continues the previous point's search
distribution (Jacobian-predicted mean, adapted covariance mixed with the task's, sigma0 = 1e-4; the first point
from the prediction with the task covariance), pycma with sigma0 = 0.02, DE/SDE/CS with
half of the first population drawn around it (warm_spread = 0.02 rad / m). CMA-ES is ``cmaes_fast`` (numpy CMA-ES, same algorithm as pycma without its overhead);
``cmaes`` (pycma) runs too unless ``--solvers`` says otherwise.

Writes docs/results/paper000_tables8-11.md and docs/results/figures/paper000_*.png.
"""

from __future__ import annotations

import argparse
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np

from framework.io.taskfile import load_task, resolve_task

sys.path.insert(0, str(Path(__file__).resolve().parent))

import report  # noqa: E402

ROOT = report.ROOT
RESULTS = ROOT / "docs" / "results"
FIGURES = RESULTS / "figures"
REPORT = RESULTS / "paper000_tables8-11.md"

PATHS = ("sinusoidal", "circular", "trapezoidal", "rose")
SOLVERS = ("de", "sde", "cs", "cmaes_fast", "cmaes", "hybrid")
LABELS = {
    "de": "DE",
    "sde": "SDE",
    "cs": "CS",
    "cmaes_fast": "CMA-ES (cmaes_fast)",
    "cmaes": "CMA-ES (pycma)",
    "hybrid": "hybrid",
}
T_R = (0.0, -0.3, 0.0)
#: Solvers that take the task first (the framework's default, ``priorities=True``): ours. The paper's algorithms
#: minimize the paper's f (``priorities=False``: their candidates are ranked by the weighted sum).
TASK_FIRST = ("hybrid",)
#: A waypoint's success threshold [m, rad] (what these documents have always used; the solvers' own default is
#: 1e-6).
TOLERANCE = 1e-4
Q_PREV = load_task(resolve_task("paper000_circular")).cases[0].initial  # paper 000's q_prev (its task file)
ITERATIONS, POPULATION, SEED = 300, 30, 0

#: Paper 000 Tables 8-11: mean, STD, min, max of e_t1 + e_t2 [m] per path and algorithm.
PAPER = {
    "sinusoidal": {
        "de": (5.104e-5, 7.5244e-5, 6.0195e-6, 8.7922e-4),
        "sde": (5.5523e-5, 3.94e-5, 4.3216e-6, 2.6586e-4),
        "cs": (9.9478e-3, 5.5781e-3, 2.8493e-3, 3.6553e-2),
        "cmaes": (1.1142e-8, 2.9257e-8, 2.6832e-13, 3.7112e-7),
    },
    "circular": {
        "de": (4.0829e-5, 2.9189e-5, 3.7308e-6, 2.1541e-4),
        "sde": (5.2769e-5, 3.8536e-5, 6.9321e-6, 2.404e-4),
        "cs": (9.863e-3, 4.6131e-3, 2.5768e-3, 2.7738e-2),
        "cmaes": (3.4473e-9, 6.085e-9, 3.7374e-15, 4.8502e-8),
    },
    "trapezoidal": {
        "de": (4.1641e-5, 3.4045e-5, 4.1663e-6, 2.4229e-4),
        "sde": (4.6393e-5, 3.4973e-5, 5.7924e-6, 1.9833e-4),
        "cs": (1.0247e-2, 4.7796e-3, 1.5987e-3, 3.0391e-2),
        "cmaes": (7.3893e-9, 2.0364e-8, 3.4801e-16, 1.2199e-7),
    },
    "rose": {
        "de": (3.5829e-5, 2.8703e-5, 5.3653e-6, 1.964e-4),
        "sde": (4.2613e-5, 2.9939e-5, 4.1256e-6, 1.8327e-4),
        "cs": (9.2417e-3, 4.8608e-3, 1.4107e-3, 3.1768e-2),
        "cmaes": (2.3824e-9, 3.9706e-9, 3.6486e-12, 2.4175e-8),
    },
}


def task():
    from framework.tracking import TrackingTask

    return TrackingTask(
        frame="arm1_ee",
        follower="arm2_ee",
        offset=T_R,
        position_weight=1.2,
        motion={"base": 0.1, "arm1": 0.4, "arm2": 0.4},
    )


def run_one(path: str, solver: str, cache: Path) -> str:
    """Track one path with one solver; save the per-point data to ``cache/{path}_{solver}.npz``."""
    import framework as fw
    from framework.tracking import track
    from framework.tracking.paths import paper000

    robot = fw.load_robot("youbot_dual_mobile")

    def run(trajectory):
        return track(robot, trajectory, task(), solver=solver, seed=SEED, max_iterations=ITERATIONS,
                     tolerance=TOLERANCE, population=POPULATION, initial=Q_PREV, priorities=solver in TASK_FIRST,
                     progress=False)

    run(paper000(path)[:2])  # untimed: a process's first run loads (on a new machine, compiles) the kernels
    result = run(paper000(path))
    np.savez(
        cache / f"{path}_{solver}.npz",
        Q=result.configurations,
        position=result.position_error,
        motion=result.motion_error,
        e_t1=result.terms["position"],
        e_t2=result.terms["follower"],
        times=result.times,
        evaluations=result.evaluations,
        wall_time=result.wall_time,
        cpu_time=result.cpu_time,
        completed=result.completed,
    )
    return f"{path:12s} {solver:10s} mean {result.position_error.mean():.3e}  {result.wall_time:7.1f} s"


def run_grid(solvers: list[str], jobs: int, cache: Path, force: bool) -> None:
    cache.mkdir(parents=True, exist_ok=True)
    todo = [(p, s) for s in solvers for p in PATHS if force or not (cache / f"{p}_{s}.npz").exists()]
    todo.sort(key=lambda job: job[1] != "cmaes")  # the slowest (pycma) first
    print(f"{len(todo)} runs to do with {jobs} processes", flush=True)
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        futures = [pool.submit(run_one, p, s, cache) for p, s in todo]
        for future in as_completed(futures):
            print(future.result(), flush=True)


# ---------------------------------------------------------------------------------------------- report
def target_lines(runs: dict) -> list[str]:
    """The issue's targets, checked: CMA-ES mean <= the paper's; hybrid every point <= 1e-9 m in <= 2 s per path."""
    lines = ["## Targets", "", "| path | CMA-ES mean (cmaes_fast) | paper | met | first point | mean of points 2-200 | "
             "hybrid max [m] | hybrid wall / CPU [s] | met |", "|---|---:|---:|---|---:|---:|---:|---:|---|"]
    for path in PATHS:
        cells = [path]
        if (path, "cmaes_fast") in runs:
            e = runs[path, "cmaes_fast"]["position"]
            ours, paper = float(e.mean()), PAPER[path]["cmaes"][0]
            cells += [f"{ours:.2e}", f"{paper:.2e}", "yes" if ours <= paper else f"no ({ours / paper:.1f}x)",
                      f"{e[0]:.1e}", f"{e[1:].mean():.1e}"]
        else:
            cells += ["–"] * 5
        if (path, "hybrid") in runs:
            h = runs[path, "hybrid"]
            worst, wall, cpu = float(h["position"].max()), float(h["wall_time"]), float(h["cpu_time"])
            ok = worst <= 1e-9 and len(h["position"]) == 200
            cells += [f"{worst:.1e}", f"{wall:.1f} / {cpu:.1f}",
                      ("yes" if ok and wall <= 2 else "accuracy yes; time: CPU " + ("yes" if cpu <= 2 else "no")
                       + ", wall no (shared machine)") if ok else "no"]
        else:
            cells += ["–", "–", "–"]
        lines.append("| " + " | ".join(cells) + " |")
    lines += [
        "",
        "`cmaes_fast` starts each point from the Jacobian prediction with a covariance that knows the task: at the "
        "first point, wide along the null space of the task Jacobian and 1e-4 across it (sigma0 = 0.1); from the "
        "second point on, the previous point's adapted covariance mixed half and half with that task covariance "
        "(sigma0 = 1e-4). Same algorithm, same 300 iterations and λ = 30. With a fresh identity covariance at every "
        "point (sigma0 = 0.02) the means were 2.4e-8 to 5.2e-8 m, 5-13x above the paper's, and the first point alone "
        "(300 iterations from the paper's q_prev, off the path) ended at 1e-6 to 4e-6 m. pycma (`cmaes`) keeps that "
        "plain warm start. The paper's CMA-ES implementation and its settings beyond λ = 30 are not given.",
    ]
    return lines


def load(cache: Path, solvers: list[str]) -> dict[tuple[str, str], dict]:
    runs = {}
    for p in PATHS:
        for s in solvers:
            f = cache / f"{p}_{s}.npz"
            if f.exists():
                with np.load(f) as data:
                    runs[p, s] = {k: data[k] for k in data.files}
    return runs


def fmt(x: float) -> str:
    return f"{x:.3e}"


def write_report(runs: dict, solvers: list[str], loads: tuple[float, float] | None = None) -> None:
    """The document from the cached ``runs``; ``loads``: the load average before and after the runs (none
    with ``--report-only``)."""
    import framework as fw
    from framework.tracking import joint_steps

    robot = fw.load_robot("youbot_dual_mobile")
    lines = [
        "Setup (paper 000 section 4): `youbot_dual_mobile` (13 DOF), f = 1.2 (e_t1 + e_t2) + 0.1 e_q0 + "
        "0.4 (e_q1 + e_q2) with L2 motion to the previous waypoint's solution, q_prev of the paper before the "
        f"first point, K = 200 points per path, {ITERATIONS} iterations per point, population {POPULATION}, "
        f"seed {SEED}, one run per solver (the paper: one run, statistics over the 200 points). Infeasible members "
        "are re-sampled in the box (eq. 12). The paper's algorithms rank candidates by f (the problem's "
        "`priorities` off: the paper's weighted sum); the hybrid takes the task first (`priorities` on, the "
        "framework's default).",
        "",
        "Our choices, where the paper is silent or we differ:",
        "",
        f"- **t_r = {T_R} m** for end-effector 2 (t*_e2 = t*_e1 + t_r): the paper does not give the tracking "
        "t_r; this is the offset of the two end-effectors at the paper's q_prev (a 30 cm object held between "
        "them). Target 1's t_r = (0.2, -0.3, -0.2) is reachable along all four paths, but at the first point of "
        "the sinusoidal and rose paths the minimum of f does not reach end-effector 2 (reaching costs more "
        "motion than 1.2 e_t2 saves: the minimizer keeps e_t2 = 0.029 m and 0.040 m; every solver then shows "
        "that error, an artefact of the weights, not of the solvers).",
        "- **Warm start**: each solve after the first starts from the previous waypoint's solution: `cmaes_fast` "
        "continues its search distribution (mean at the Jacobian prediction from the previous solution, the "
        "previous point's adapted covariance mixed with the task covariance at the prediction, sigma0 = 1e-4; "
        "`framework.tracking.continued`), pycma takes the "
        "previous solution as its mean with sigma0 = 0.02, DE/SDE/CS take it and 14 members drawn from "
        "N(q_prev, 0.02²) in the first population (`track(..., warm_spread=0.02)`); the paper uses the previous "
        "solution only as q_prev in the cost. The first point is solved from the paper's q_prev (as mean / first "
        "member, default spread; `cmaes_fast` from the prediction with the task covariance, sigma0 = 0.1).",
        "- **CMA-ES**: `cmaes_fast` (numpy (μ/μ_w, λ)-CMA-ES, λ = 30, Hansen's tutorial defaults) and `cmaes` "
        "(pycma, active update off); same algorithm, `cmaes_fast` is ~10x faster per point.",
        "- **hybrid** (ours): the first point by a 30-generation `cmaes_fast` phase + the compiled local engine; "
        "every later point by the engine alone from the previous solution (Levenberg-Marquardt onto the waypoint, "
        "then Newton steps minimizing the motion terms without leaving it: the task first, the paper's reported "
        "behaviour).",
        "",
        "Position error = e_t1 + e_t2 [m] per point; motion error = e_q0 + e_q1 + e_q2 [rad, m] per point (its "
        "max is the first point: the move from q_prev onto the path); max step = largest single-joint move between "
        "consecutive points [rad or m] (after the first point). *Mean of points 2-200* leaves out the first point, "
        "which starts from the paper's q_prev, far from the path, and dominates the CMA-ES mean. Time: wall clock "
        "on the shared machine (other jobs ran alongside: load 5 on 2 cores) / CPU time of the process.",
        "",
    ]
    for k, path in enumerate(PATHS):
        lines += [
            f"## Table {8 + k}: {path} trajectory",
            "",
            "| | " + " | ".join(LABELS[s] for s in solvers if (path, s) in runs) + " |",
            "|---|" + "---:|" * sum((path, s) in runs for s in solvers),
        ]
        stats = {}
        for s in solvers:
            if (path, s) in runs:
                e = runs[path, s]["position"]
                stats[s] = (e.mean(), e.std(), e.min(), e.max())
        for i, row in enumerate(("mean", "STD", "min", "max")):
            lines.append(f"| {row} | " + " | ".join(fmt(stats[s][i]) for s in stats) + " |")
        lines.append(
            "| median | " + " | ".join(fmt(np.median(runs[path, s]["position"])) for s in stats) + " |"
        )
        lines.append(
            "| mean of points 2-200 | "
            + " | ".join(fmt(runs[path, s]["position"][1:].mean()) for s in stats)
            + " |"
        )
        paper_row = []
        for s in stats:
            key = "cmaes" if s.startswith("cmaes") else s
            paper_row.append(fmt(PAPER[path][key][0]) if key in PAPER[path] else "–")
        lines.append("| paper mean | " + " | ".join(paper_row) + " |")
        for label, fn in (
            ("motion error, mean", lambda r: r["motion"].mean()),
            ("motion error, max", lambda r: r["motion"].max()),
        ):
            lines.append(f"| {label} | " + " | ".join(fmt(fn(runs[path, s])) for s in stats) + " |")
        steps = {s: joint_steps(robot, runs[path, s]["Q"], Q_PREV) for s in stats}
        lines.append(
            "| max step (base / arm1 / arm2) | "
            + " | ".join(
                " / ".join(f"{steps[s].max_step[g]:.3f}" for g in ("base", "arm1", "arm2")) for s in stats
            )
            + " |"
        )
        lines.append(
            "| points ≤ 1e-4 m | "
            + " | ".join(f"{int((runs[path, s]['position'] <= 1e-4).sum())}/200" for s in stats)
            + " |"
        )
        lines.append(
            "| time, wall / CPU [s] | "
            + " | ".join(
                f"{float(runs[path, s]['wall_time']):.1f} / {float(runs[path, s]['cpu_time']):.1f}"
                for s in stats
            )
            + " |"
        )
        lines.append("")
    lines += [
        "Paper values (Tables 8-11, mean / STD / min / max of e_t1 + e_t2 [m]):",
        "",
        "| path | DE | SDE | CS | CMA-ES |",
        "|---|---|---|---|---|",
    ]
    for path in PATHS:
        lines.append(
            f"| {path} | "
            + " | ".join(" / ".join(f"{v:.2g}" for v in PAPER[path][s]) for s in ("de", "sde", "cs", "cmaes"))
            + " |"
        )
    lines += ["", *target_lines(runs)]
    lines += [
        "",
        "## Figures",
        "",
        "- Fig. 7 (position error per point, log scale): `figures/paper000_fig7_position_error.png`",
        "- Fig. 8 (desired vs. tracked paths of both end-effectors): `figures/paper000_fig8_paths.png`",
        "- Fig. 9 (motion error per point): `figures/paper000_fig9_motion_error.png`",
        "- Fig. 10 (joint motion, trapezoidal path, CMA-ES vs. CS): `figures/paper000_fig10_joint_motion.png`",
        "",
        "![Fig. 7](figures/paper000_fig7_position_error.png)",
        "",
        "![Fig. 8](figures/paper000_fig8_paths.png)",
        "",
        "![Fig. 9](figures/paper000_fig9_motion_error.png)",
        "",
        "![Fig. 10](figures/paper000_fig10_joint_motion.png)",
        "",
    ]
    report.write(REPORT, "Paper 000, Tables 8-11: coordinated trajectory tracking (mobile dual-arm youBot)",
                 "\n".join(lines), loads=loads)
    print(f"wrote {REPORT}")


def write_figures(runs: dict, solvers: list[str]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import framework as fw
    from framework.tracking.paths import paper000

    FIGURES.mkdir(parents=True, exist_ok=True)
    robot = fw.load_robot("youbot_dual_mobile")

    for key, title, fname, floor in (
        ("position", "position error e_t1 + e_t2 [m]", "fig7_position_error", 1e-17),
        ("motion", "motion error e_q0 + e_q1 + e_q2", "fig9_motion_error", 1e-6),
    ):
        fig, axes = plt.subplots(1, 4, figsize=(16, 4), sharey=True)
        for ax, path in zip(axes, PATHS):
            present = [s for s in solvers if (path, s) in runs]
            ax.boxplot([np.maximum(runs[path, s][key], floor) for s in present], showfliers=True)
            ax.set_xticks(
                range(1, len(present) + 1),
                [LABELS[s].split(" ")[0] if s != "cmaes" else "pycma" for s in present],
                rotation=30,
            )
            ax.set_yscale("log")
            ax.set_title(path)
        axes[0].set_ylabel(title)
        fig.tight_layout()
        fig.savefig(FIGURES / f"paper000_{fname}.png", dpi=110)
        plt.close(fig)

    fig, axes = plt.subplots(1, 4, figsize=(18, 4.5))
    for ax, path in zip(axes, PATHS):
        desired = paper000(path)
        for offset, style in ((np.zeros(3), "k-"), (np.asarray(T_R), "k--")):
            P = desired.positions + offset
            ax.plot(P[:, 1], P[:, 2], style, lw=3, alpha=0.3)
        for s, color in (("cmaes_fast", "tab:blue"), ("sde", "tab:orange"), ("hybrid", "tab:green")):
            if (path, s) not in runs:
                continue
            P = robot.frame_poses(runs[path, s]["Q"], ("arm1_ee", "arm2_ee")).positions
            ax.plot(P[:, 0, 1], P[:, 0, 2], ".", ms=2, color=color, label=f"{LABELS[s]}")
            ax.plot(P[:, 1, 1], P[:, 1, 2], ".", ms=2, color=color)
        ax.set_title(f"{path} (solid: e1 desired, dashed: e2 desired)", fontsize=9)
        ax.set_xlabel("y [m]")
        ax.set_aspect("equal", adjustable="datalim")
    axes[0].set_ylabel("z [m]")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(FIGURES / "paper000_fig8_paths.png", dpi=110)
    plt.close(fig)

    fig, axes = plt.subplots(2, 3, figsize=(15, 7), sharex=True)
    groups = {"base": robot.group("base"), "arm1": robot.group("arm1"), "arm2": robot.group("arm2")}
    for row, s in enumerate(("cmaes_fast", "cs")):
        if ("trapezoidal", s) not in runs:
            continue
        Q = runs["trapezoidal", s]["Q"]
        for col, (g, idx) in enumerate(groups.items()):
            ax = axes[row, col]
            for i in idx:
                ax.plot(Q[:, i], lw=1, label=robot.coordinate_names[i])
            ax.set_title(f"{LABELS[s]}: {g}")
            ax.legend(fontsize=6)
    for ax in axes[1]:
        ax.set_xlabel("point k")
    fig.tight_layout()
    fig.savefig(FIGURES / "paper000_fig10_joint_motion.png", dpi=110)
    plt.close(fig)
    print(f"wrote figures to {FIGURES}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-j", "--jobs", type=int, default=2, help="processes (default 2)")
    parser.add_argument(
        "--solvers", default=",".join(SOLVERS), help=f"comma-separated (default {','.join(SOLVERS)})"
    )
    parser.add_argument(
        "--cache",
        type=Path,
        default=Path("/tmp/metaik_paper000_tracking"),
        help="directory of the per-run .npz files",
    )
    parser.add_argument("--force", action="store_true", help="re-run runs already in the cache")
    parser.add_argument("--report-only", action="store_true", help="only write the tables and figures")
    args = parser.parse_args(argv)
    solvers = [s for s in args.solvers.split(",") if s]
    start, before = time.perf_counter(), report.load()
    if not args.report_only:
        run_grid(solvers, args.jobs, args.cache, args.force)
    runs = load(args.cache, solvers)
    write_report(runs, solvers, None if args.report_only else (before, report.load()))
    write_figures(runs, solvers)
    print(f"done in {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
