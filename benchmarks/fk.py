"""Population forward kinematics vs. a Python loop over Pinocchio, in microseconds per *population*.

Run: python benchmarks/fk.py   (prints a Markdown table and writes docs/results/fk.md; ratios are against the
loop run in the same process). The loop is what a cost would do without batching: per configuration
pinocchio.forwardKinematics, then updateFramePlacement of only the frames needed (cheaper than updating all
frames), then read them. Best of 7 timings of each.
"""

from __future__ import annotations

import sys
import timeit
from pathlib import Path

import numpy as np
import pinocchio as pin

sys.path.insert(0, str(Path(__file__).resolve().parent))

import report  # noqa: E402

import framework as fw  # noqa: E402


def pinocchio_loop(robot: fw.Robot, data: pin.Data, Q: np.ndarray, fids: list[int]) -> np.ndarray:
    out = np.empty((len(Q), len(fids), 3))
    for b, q in enumerate(Q):
        pin.forwardKinematics(robot.model, data, q)
        for k, fid in enumerate(fids):
            out[b, k] = pin.updateFramePlacement(robot.model, data, fid).translation
    return out


def best_time_us(fn, repeat: int = 7) -> float:
    number = max(1, int(0.05 / max(timeit.timeit(fn, number=1), 1e-7)))
    return min(timeit.repeat(fn, number=number, repeat=repeat)) / number * 1e6


def main() -> None:
    rng = np.random.default_rng(0)
    before = report.load()
    lines = [__doc__.split("\n\n")[1].strip(), "", "| robot | n | pop | Pinocchio loop [µs] | population FK [µs] | speed-up |",
             "|---|---:|---:|---:|---:|---:|"]
    for name in ("youbot_dual_mobile", "baxter_arm"):
        robot = fw.load_robot(name)
        fids = [robot.frame_id(f) for f in robot.end_effectors]
        data = robot.model.createData()
        for pop in (1, 30, 1000):
            X = robot.random_configurations(rng, pop)
            Q = robot.to_pinocchio(X)
            robot.frame_poses(X)  # compile / load the kernel outside the timing
            assert np.allclose(robot.frame_poses(X).positions, pinocchio_loop(robot, data, Q, fids), atol=1e-12)
            t_loop = best_time_us(lambda: pinocchio_loop(robot, data, Q, fids))
            t_pop = best_time_us(lambda: robot.frame_poses(X))
            lines.append(f"| {name} | {robot.n} | {pop} | {t_loop:.1f} | {t_pop:.1f} | {t_loop / t_pop:.1f}x |")
            print(lines[-1], flush=True)
    report.write(report.ROOT / "docs" / "results" / "fk.md", "Population forward kinematics vs. a Pinocchio loop",
                 "\n".join(lines), loads=(before, report.load()))


if __name__ == "__main__":
    main()
