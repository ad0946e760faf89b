"""How far a frame reaches: the farthest it gets from a point fixed in the world (the first joint of its chain),
for saying that a target lies beyond it (:attr:`~framework.solvers.solve.IKResult.reason`)."""

from __future__ import annotations

import numpy as np

from .robot import Robot


def reach_hint(robot: Robot, frame: str, target: np.ndarray) -> str | None:
    """A few words when ``target`` [m, world] lies beyond ``frame``'s reach: farther from a fixed point of the
    robot (the first joint of the frame's chain) than the frame ever gets from it (its farthest point, found once
    per robot and frame: the farthest of 4,000 random configurations, pushed out by gradient ascent; a target within
    2 % of that distance is not called unreachable); ``None`` otherwise."""
    center, radius = robot.derived(_reach_sphere, frame)
    distance = float(np.linalg.norm(np.asarray(target, dtype=float) - center))
    if distance <= 1.02 * radius + 1e-3:
        return None
    return (f"the target is {distance:.3g} m from {frame}'s first joint, and {frame} gets at most {radius:.3g} m "
            f"from it: {distance - radius:.3g} m beyond its reach")


def _reach_sphere(robot: Robot, frame: str, samples: int = 4000) -> tuple[np.ndarray, float]:
    """``(center (3,), radius)``: the origin of the first joint moving ``frame`` (fixed in the world) and the
    largest distance [m] of ``frame`` from it found over ``samples`` seeded random configurations, the 16 farthest
    then pushed outwards by projected gradient ascent."""
    import pinocchio as pin

    model = robot.model
    jid = model.frames[robot.frame_id(frame)].parentJoint
    first = jid
    while jid > 0:
        if model.joints[jid].nq > 0:
            first = jid
        jid = model.parents[jid]
    data = model.createData()
    pin.forwardKinematics(model, data, robot.to_pinocchio(robot.middle))
    center = np.array(data.oMi[first].translation)
    X = robot.random_configurations(np.random.default_rng(0), samples)
    far = np.linalg.norm(robot.frame_poses(X, frame).positions[:, 0] - center, axis=1)
    radius = float(far.max())
    X = X[np.argsort(far)[-16:]]
    step = 0.1
    for _ in range(80):
        poses, J = robot.frame_jacobians(X, frame)
        v = poses.positions[:, 0] - center
        radius = max(radius, float(np.linalg.norm(v, axis=1).max()))
        g = np.einsum("bij,bi->bj", J[:, 0, :3, :], v)
        X = np.clip(X + step * g / (np.linalg.norm(g, axis=1, keepdims=True) + 1e-12), robot.lower, robot.upper)
        step *= 0.95
    return center, radius
