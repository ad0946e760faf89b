"""Hybrid speed on paper 000's four coordinated-IK targets, as ratios measured in one process.

For each target, the median wall time of 20 hybrid solves (refinement from q_prev, the default), of 20 solves of
the same hybrid started with 30 CMA-ES generations from a uniform start (its former default), and of 5 runs of
`cmaes_fast` with the paper's 1000 iterations. Prints a table.

    python benchmarks/hybrid_speed.py
"""

from __future__ import annotations

import os
import platform
from pathlib import Path

import numpy as np

from framework.solve import solve
from framework.taskfile import load_task

TASK = Path(__file__).resolve().parents[1] / "tasks" / "youbot_dual_coordinated_ik.toml"


def main() -> None:
    task = load_task(TASK)
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}")
    print("| target | hybrid [ms] | 30-generation start [ms] | ratio | cmaes_fast, 1000 it [ms] | ratio |")
    print("|---|---:|---:|---:|---:|---:|")
    for case in task.cases:
        p = case.problem
        solve(p, "hybrid", seed=0), solve(p, "cmaes_fast", seed=0, max_iterations=10)  # compile and warm up
        hybrid = [solve(p, "hybrid", seed=s, tolerance=1e-12).wall_time for s in range(20)]
        former = [solve(p, "hybrid", seed=s, tolerance=1e-12, options={"global_iterations": 30, "warm_start": False})
                  .wall_time for s in range(20)]
        cmaes = [solve(p, "cmaes_fast", seed=s, max_iterations=1000).wall_time for s in range(5)]
        h, f, c = (1e3 * float(np.median(t)) for t in (hybrid, former, cmaes))
        print(f"| {case.name} | {h:.1f} | {f:.1f} | {f / h:.1f}x | {c:.0f} | {c / h:.0f}x |")


if __name__ == "__main__":
    main()
