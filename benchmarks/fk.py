"""Population forward kinematics vs. a Python loop over Pinocchio, in microseconds per *population*.

Run: python benchmarks/fk.py   (prints a Markdown table; ratios are against the loop run in the same process)
The loop is what a cost would do without batching: per configuration pinocchio.forwardKinematics +
updateFramePlacements, then read the end-effector frames.
"""

from __future__ import annotations

import os
import platform
import timeit

import numpy as np
import pinocchio as pin

import framework as fw


def pinocchio_loop(robot: fw.Robot, Q: np.ndarray, fids: list[int]) -> np.ndarray:
    data = robot.model.createData()
    out = np.empty((len(Q), len(fids), 3))
    for b, q in enumerate(Q):
        pin.forwardKinematics(robot.model, data, q)
        pin.updateFramePlacements(robot.model, data)
        for k, fid in enumerate(fids):
            out[b, k] = data.oMf[fid].translation
    return out


def best_time_us(fn, repeat: int = 7) -> float:
    number = max(1, int(0.05 / max(timeit.timeit(fn, number=1), 1e-7)))
    return min(timeit.repeat(fn, number=number, repeat=repeat)) / number * 1e6


def main() -> None:
    rng = np.random.default_rng(0)
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}, pinocchio {pin.__version__}\n")
    print("| robot | n | pop | Pinocchio loop [µs] | population FK [µs] | speed-up |")
    print("|---|---|---|---|---|---|")
    for name in ("youbot_dual_mobile", "baxter_arm"):
        robot = fw.load_robot(name)
        fids = [robot.frame_id(f) for f in robot.end_effectors]
        for pop in (1, 30, 1000):
            X = robot.random_configurations(rng, pop)
            Q = robot.to_pinocchio(X)
            robot.frame_poses(X)  # compile / load the kernel outside the timing
            assert np.allclose(robot.frame_poses(X).positions, pinocchio_loop(robot, Q, fids), atol=1e-12)
            t_loop = best_time_us(lambda: pinocchio_loop(robot, Q, fids))
            t_pop = best_time_us(lambda: robot.frame_poses(X))
            print(f"| {name} | {robot.n} | {pop} | {t_loop:.1f} | {t_pop:.1f} | {t_loop / t_pop:.1f}x |")


if __name__ == "__main__":
    main()
