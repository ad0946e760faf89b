"""Two-hand pose IK on PR2 (example-robot-data): both grippers at given poses, motion minimized, defaults.

PR2's torso lift and both 7-DOF arms are solved (15 coordinates; forearm and wrist rolls are continuous
joints), every other joint is locked. Targets: FK of uniform random configurations of those joints, kept when
both grippers are in front of the robot (x > 0.2 m) and 0.2-0.4 m apart — reachable target pairs by
construction. Each is solved through the public API with every default (the hybrid, task first, tolerance
1e-6 m / 1e-6 rad), problem construction included::

    solve(Problem(robot, Pose("l_gripper_tool_frame", A) + Pose("r_gripper_tool_frame", B)
                  + 0.1 * Motion("all", q_rest)), seed=k)

with ``q_rest`` the middle of the joint box. Success is checked afterwards by Pinocchio FK of the full model.

    python benchmarks/two_hands.py [--pairs 1000]

Writes docs/results/two_hands.md.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import report  # noqa: E402

import framework as fw  # noqa: E402
from tests.conftest import example_robot_data_dir  # noqa: E402

OUT = report.ROOT / "docs" / "results" / "two_hands.md"
HANDS = ("l_gripper_tool_frame", "r_gripper_tool_frame")
ARM = ("shoulder_pan", "shoulder_lift", "upper_arm_roll", "elbow_flex", "forearm_roll", "wrist_flex", "wrist_roll")
TOLERANCE = 1e-6


def pr2() -> fw.Robot:
    joints = ["torso_lift_joint"] + [f"{side}_{name}_joint" for side in "lr" for name in ARM]
    return fw.load_robot(example_robot_data_dir() / "pr2_description" / "urdf" / "pr2.urdf", joints=joints)


def target_pairs(robot: fw.Robot, count: int, rng: np.random.Generator) -> list[tuple[pin.SE3, pin.SE3]]:
    pairs = []
    while len(pairs) < count:
        x = robot.random_configurations(rng, 1)[0]
        a, b = (robot.frame_placement(x, hand) for hand in HANDS)
        apart = np.linalg.norm(a.translation - b.translation)
        if a.translation[0] > 0.2 and b.translation[0] > 0.2 and 0.2 <= apart <= 0.4:
            pairs.append((a, b))
    return pairs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=1000)
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    robot = pr2()
    rest = robot.middle.copy()
    pairs = target_pairs(robot, args.pairs, np.random.default_rng(2026))
    fw.solve(fw.Problem(robot, fw.Pose(HANDS[0], pairs[0][0]) + fw.Pose(HANDS[1], pairs[0][1])))  # warm up
    before = report.load()
    ok, times, worst, motion = [], [], [], []
    for k, (a, b) in enumerate(pairs):
        t = time.perf_counter()
        result = fw.solve(fw.Problem(robot, fw.Pose(HANDS[0], a) + fw.Pose(HANDS[1], b)
                                     + 0.1 * fw.Motion("all", rest)), seed=k)
        times.append(time.perf_counter() - t)
        errors = []
        for hand, target in zip(HANDS, (a, b)):
            M = robot.frame_placement(result.configuration, hand)
            errors += [np.linalg.norm(M.translation - target.translation),
                       np.linalg.norm(pin.log3(target.rotation.T @ M.rotation))]
        ok.append(max(errors) <= TOLERANCE)
        worst.append(max(errors))
        motion.append(result.terms["motion[all]"])
    after = report.load()
    ms = 1e3 * np.array(times)
    body = "\n".join([
        __doc__.split("\n\n")[1].strip(), "", __doc__.split("\n\n")[2].strip(), "",
        f"{args.pairs} target pairs (seed 2026).", "",
        "| pairs | success % | median ms | mean ms | p95 ms | max ms | worst error of a success | median motion [rad] |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|",
        f"| {args.pairs} | {100 * np.mean(ok):.2f} | {np.median(ms):.3f} | {ms.mean():.3f} | "
        f"{np.percentile(ms, 95):.3f} | {ms.max():.2f} | "
        f"{max((w for w, s in zip(worst, ok) if s), default=float('nan')):.1e} | {np.median(motion):.3f} |",
        "", "Success: both grippers within 1e-6 m and 1e-6 rad of their targets by Pinocchio FK.",
    ])
    print(body)
    report.write(args.out, "Two-hand pose IK on PR2 (15 solved joints), defaults", body, loads=(before, after))


if __name__ == "__main__":
    main()
