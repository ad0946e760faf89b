"""References for the random-tree checks (``test_random_trees.py`` asserts on them, ``benchmarks/reliability.py``
reports them): Pinocchio's FK of the same URDF, central differences, the hybrid on reachable poses."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

import framework as fw
from tests.fuzz.trees import Tree, random_tree


def pinocchio_q(model: pin.Model, robot: fw.Robot, x: np.ndarray, mimic: dict | None = None) -> np.ndarray:
    """The Pinocchio configuration of search vector ``x``, built here from the joint types (cos/sin for
    continuous joints) and the tree's own mimic table, not with the framework's own conversion."""
    q = pin.neutral(model)
    values = {joint.name: x[joint.index] for joint in robot.joints}
    values.update({name: m * values[leader] + o for name, (leader, m, o) in (mimic or {}).items()})
    for name, value in values.items():
        jm = model.joints[model.getJointId(name)]
        if jm.nq == 2:
            q[jm.idx_q:jm.idx_q + 2] = np.cos(value), np.sin(value)
        else:
            q[jm.idx_q] = value
    return q


def fk_difference(tree: Tree, robot: fw.Robot, X: np.ndarray, frames: Sequence[str]) -> float:
    """Largest difference between the population FK of ``frames`` and Pinocchio's FK of the same URDF (positions
    [m] and rotation entries) over the configurations ``X`` ``(b, n)``."""
    model = pin.buildModelFromXML(tree.urdf)
    data = model.createData()
    poses = robot.frame_poses(X, frames)
    worst = 0.0
    for b, x in enumerate(X):
        pin.framesForwardKinematics(model, data, pinocchio_q(model, robot, x, tree.mimic))
        for k, frame in enumerate(frames):
            oMf = data.oMf[model.getFrameId(frame)]
            worst = max(worst, np.abs(poses.positions[b, k] - oMf.translation).max(),
                        np.abs(poses.rotations[b, k] - oMf.rotation).max())
    return float(worst)


def jacobian_difference(robot: fw.Robot, X: np.ndarray, frames: Sequence[str], h: float = 1e-6) -> float:
    """Largest difference between the frame Jacobians and central differences of step ``h``: positions, and the
    world angular velocity ``log(R(x+h) R(x-h)ᵀ) / 2h``, over the configurations ``X``."""
    _, J = robot.frame_jacobians(X, frames)
    worst = 0.0
    for b, x in enumerate(X):
        for i in range(robot.n):
            step = np.zeros(robot.n)
            step[i] = h
            P = robot.frame_poses(np.array([x + step, x - step]), frames)
            for k in range(len(frames)):
                dp = (P.positions[0, k] - P.positions[1, k]) / (2 * h)
                w = pin.log3(P.rotations[0, k] @ P.rotations[1, k].T) / (2 * h)
                worst = max(worst, np.abs(J[b, k, :3, i] - dp).max(), np.abs(J[b, k, 3:, i] - w).max())
    return float(worst)


def reach_reachable_pose(seed: int) -> tuple[bool, float, float]:
    """Solve the hybrid for the FK pose of a random configuration of a random tree's deepest leaf (position +
    orientation); returns (success, position error [m], angle error [rad]) checked with Pinocchio's FK."""
    tree = random_tree(seed, joints=(2, 8))
    robot = fw.robot_from_urdf(tree.urdf)
    rng = np.random.default_rng(seed)
    model = pin.buildModelFromXML(tree.urdf)
    data = model.createData()
    moving = [f for f in tree.leaves if model.frames[model.getFrameId(f)].parentJoint > 0]
    depth = {f: 0 for f in moving}
    for f in moving:
        j = model.frames[model.getFrameId(f)].parentJoint
        while j > 0:
            depth[f] += 1
            j = model.parents[j]
    frame = max(moving, key=lambda f: (depth[f], f))
    x_true = robot.random_configurations(rng, 1)[0]
    target = robot.frame_placement(x_true, frame)
    result = fw.solve(fw.Problem(robot, fw.Pose(frame, target)), "hybrid", seed=seed, tolerance=1e-9)
    pin.framesForwardKinematics(model, data, pinocchio_q(model, robot, result.configuration, tree.mimic))
    oMf = data.oMf[model.getFrameId(frame)]
    position = float(np.linalg.norm(oMf.translation - target.translation))
    angle = float(np.linalg.norm(pin.log3(target.rotation.T @ oMf.rotation)))
    return result.success, position, angle
