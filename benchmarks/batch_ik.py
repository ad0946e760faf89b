"""Batch IK throughput: `solve_batch` beside the single-solve loop and TRAC-IK one by one, on the same poses.

Protocol (TRAC-IK's, as in benchmarks/pose_ik.py): TRAC-IK's driver (``../shared/peers/tracik``, built from
source) samples B uniform random configurations within the URDF's limits and their FK poses, and solves them one
by one (its "Speed" mode, 5 ms budget). metaik solves the same poses: ``solve_batch`` (the hybrid, every item as
``solve`` would solve it with seed ``i``, the compiled batch loop on 1 thread and on every core) and the loop
``for pose: solve(Problem(robot, Pose(tip, pose)))``. Strict success: position ≤ 1e-5 m and rotation angle ≤
1e-5 rad by Pinocchio FK of the returned configuration (the batch gives each item the same 5 ms budget).

Throughput = poses / wall time of the whole call (``solve_batch`` includes packing the targets and the items it
hands to ``solve``; the random restarts are drawn inside the compiled loop). TRAC-IK's figure is B / the sum of
its per-solve wall times (its process start and file output excluded). Each metaik figure is the median of three runs, the
three variants alternated; B = 1 and 100 are repeated to 2,000 poses per run.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import report  # noqa: E402
from pose_ik import (BUDGET, TOLERANCE, Chain, chains, find_tracik, row_pose, run_tracik, strict_errors,  # noqa: E402
                     tracik_strict)

import framework as fw  # noqa: E402

OUT = report.ROOT / "docs" / "results" / "batch_ik.md"
SIZES = (1, 100, 10_000)
RUNS = 3


def poses_of(chain: Chain, robot: fw.Robot, rows: list[dict]) -> np.ndarray:
    """``(B, 4, 4)`` the driver's poses in the model's world frame."""
    base = robot.frame_placement(robot.middle, chain.base)
    return np.array([(base * row_pose(row)).homogeneous for row in rows]).reshape(len(rows), 4, 4)


def strict(robot: fw.Robot, tip: str, X: np.ndarray, T: np.ndarray) -> np.ndarray:
    """``(B,)`` whether each configuration reaches its pose within 1e-5 m and 1e-5 rad (Pinocchio FK)."""
    return np.array([max(strict_errors(robot, x, tip, pin.SE3(target))) <= TOLERANCE for x, target in zip(X, T)],
                    dtype=bool)


def batch_run(problem: fw.Problem, T: np.ndarray, workers: int) -> tuple[float, np.ndarray]:
    result = fw.solve_batch(problem, T, tolerance=TOLERANCE, time_budget=BUDGET, workers=workers, progress=False)
    return result.wall_time, result.configurations


def loop_run(robot: fw.Robot, tip: str, T: np.ndarray) -> tuple[float, np.ndarray]:
    X = np.empty((len(T), robot.n))
    start = time.perf_counter()
    for k, target in enumerate(T):
        X[k] = fw.solve(fw.Problem(robot, fw.Pose(tip, target)), tolerance=TOLERANCE, time_budget=BUDGET,
                        seed=k).configuration
    return time.perf_counter() - start, X


def measure(chain: Chain, robot: fw.Robot, T: np.ndarray, rows: list[dict], workers: int) -> list[dict]:
    problem = fw.Problem(robot, fw.Pose(chain.tip, T[0]))
    fw.solve_batch(problem, T[:20], tolerance=TOLERANCE, progress=False)  # load the compiled code
    lines = []
    for B in SIZES:
        repeat = max(1, 2000 // B)
        subset = T[:B]
        variants = {
            f"solve_batch, {workers} threads": lambda: batch_run(problem, subset, workers),
            "solve_batch, 1 thread": lambda: batch_run(problem, subset, 1),
            "solve loop": lambda: loop_run(robot, chain.tip, subset),
        }
        times: dict[str, list[float]] = {name: [] for name in variants}
        solutions: dict[str, np.ndarray] = {}
        for _ in range(RUNS):
            for name, run in variants.items():
                total = 0.0
                for _ in range(repeat):
                    seconds, X = run()
                    total += seconds
                times[name].append(total / repeat)
                solutions[name] = X
        for name in variants:
            lines.append({"chain": chain.name, "B": B, "method": name, "rate": B / float(np.median(times[name])),
                          "success": 100 * strict(robot, chain.tip, solutions[name], subset).mean()})
        ms = np.array([float(r["ms"]) for r in rows[:B]])
        order = np.array([robot.joint(name).index for name in chain.meta["joints"]])
        ok = np.array([tracik_strict(robot, chain, r, order, pin.SE3(t)) for r, t in zip(rows[:B], subset)])
        lines.append({"chain": chain.name, "B": B, "method": "TRAC-IK one by one (C++)",
                      "rate": B / (ms.sum() / 1e3), "success": 100 * ok.mean()})
        for line in lines[-4:]:
            print(f"{line['chain']:6s} B={B:<6d} {line['method']:28s} {line['rate']:10.0f} IK/s  "
                  f"{line['success']:.2f} %", flush=True)
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tracik", help="path of TRAC-IK's tracik_bench driver")
    parser.add_argument("--workers", type=int, default=2, help="threads of the batch loop (default 2: the cores)")
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    binary = find_tracik(args.tracik)
    before = report.load()
    lines = []
    with tempfile.TemporaryDirectory() as folder:
        for chain in [c for c in chains() if c.name in ("UR5", "Panda")]:
            rows = run_tracik(binary, chain, max(SIZES), 0, max(SIZES), Path(folder))
            robot = fw.load_robot(chain.urdf, joints=chain.meta["joints"])
            lines += measure(chain, robot, poses_of(chain, robot, rows), rows, args.workers)
    after = report.load()
    report.write(args.out, "Batch IK throughput against the single-solve loop and TRAC-IK", body(lines),
                 loads=(before, after))
    print(args.out.read_text())


def body(lines: list[dict]) -> str:
    text = [__doc__.split("\n\n", 1)[1].strip(), "",
            f"Budget {1e3 * BUDGET:g} ms per pose; target of the batch issue: ≥ 30,000 IK/s at B = 10,000 on this "
            "machine's 2 cores at ≥ 99.9 % strict success.", "",
            "| chain | B | method | IK per second | strict success % | vs TRAC-IK |", "|---|---:|---|---:|---:|---:|"]
    for line in lines:
        tracik = next(x for x in lines if x["chain"] == line["chain"] and x["B"] == line["B"]
                      and x["method"].startswith("TRAC-IK"))
        text.append(f"| {line['chain']} | {line['B']:,} | {line['method']} | {line['rate']:,.0f} | "
                    f"{line['success']:.2f} | {line['rate'] / tracik['rate']:.1f}x |")
    return "\n".join(text)


if __name__ == "__main__":
    main()
