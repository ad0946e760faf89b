"""Joint groups named by role: what the structure of a robot says its chains are — a mobile base, a torso the
chains share, arms, legs, a head — and which side each is on, read from the kinematic tree and the names its
files give (``l_``/``left``, ``FL``/``front_left``, ``head``, ``foot``, ...).

A base is recognised by its joints, of any kind: leading every chain, a planar joint, a floating base's six
joints, or prismatic joints along horizontal axes followed by at most one turn about the vertical (an
omnidirectional base built as x, y, θ).
"""

from __future__ import annotations

import re
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from .joints import JointKind

#: Words that make a chain a head or a leg (else it is an arm), matched on its joints' and end frame's names.
HEAD = re.compile(r"head|neck|gaze|pan_tilt|ptu", re.IGNORECASE)
LEG = re.compile(r"leg|foot|feet|toe|sole|ankle|knee|thigh|calf|shin|paw|hip", re.IGNORECASE)
#: Words that make a joint on no end-effector's chain part of a gripper (its fingers, jaws).
GRIPPER = re.compile(r"finger|gripper|jaw|claw|thumb|hand", re.IGNORECASE)
#: Side tokens: a name part (between separators) that says left / right / front / rear.
_SIDES = (
    (re.compile(r"(^|[^a-z])(fl|lf)([^a-z]|$)"), "front_left"), (re.compile(r"(^|[^a-z])(fr|rf)([^a-z]|$)"), "front_right"),
    (re.compile(r"(^|[^a-z])(rl|hl|lh|bl)([^a-z]|$)"), "rear_left"),
    (re.compile(r"(^|[^a-z])(rr|hr|rh|br)([^a-z]|$)"), "rear_right"),
    (re.compile(r"(^|[^a-z])(left|l)([^a-z]|$)"), "left"), (re.compile(r"(^|[^a-z])(right|r)([^a-z]|$)"), "right"),
)
_FRONT_REAR = re.compile(r"front|rear|back|hind")


def mobile_base(robot, chains: Sequence[Sequence[str]], floating: Sequence[str]) -> list[str]:
    """The joints of a mobile base: the leading joints every chain shares that are planar, a floating base's, or
    drives along the floor (horizontal prismatic joints) with the turns about the vertical before them and one
    after; ``[]`` when there is none (a lone rail or lone turns belong to the arm)."""
    if not chains:
        return []
    shared = []
    for joints in zip(*chains):
        if len(set(joints)) != 1:
            break
        shared.append(joints[0])
    axes = _world_axes(robot, shared)
    base: list[str] = []
    for name in shared:
        kind = robot.joint(name).kind
        if kind is JointKind.PLANAR or name in floating:
            base.append(name)
        elif kind is JointKind.PRISMATIC and abs(axes[name][2]) < 0.1:  # a drive along the floor
            base.append(name)
        elif kind in (JointKind.REVOLUTE, JointKind.CONTINUOUS) and abs(abs(axes[name][2]) - 1) < 0.1:
            base.append(name)  # a turn about the vertical (kept below only if a drive is beside it)
        else:
            break
    kinds = [robot.joint(j).kind for j in base]
    if any(k in (JointKind.PLANAR,) for k in kinds) or any(j in floating for j in base):
        return [j for j in base if robot.joint(j).kind is JointKind.PLANAR or j in floating]
    drives = [i for i, k in enumerate(kinds) if k is JointKind.PRISMATIC]
    if not drives or (len(drives) == 1 and drives[-1] == len(base) - 1 and len(base) == 1):
        return []  # turns alone are an arm's first joint; one rail alone is a linear axis of the arm
    return base[: min(drives[-1] + 2, len(base))]  # the drives, the turns before them and one turn after


def _world_axes(robot, joints: Sequence[str]) -> dict[str, np.ndarray]:
    """Each joint's axis in the world at the robot's middle configuration."""
    model = robot.model
    data = model.createData()
    pin.forwardKinematics(model, data, robot.to_pinocchio(robot.middle))
    out = {}
    for name in joints:
        joint = robot.joint(name)
        out[name] = data.oMi[joint.pin_id].rotation @ np.asarray(joint.axis, dtype=float)
    return out


def segment_names(robot, chains: Sequence[Sequence[str]], segments: Sequence[frozenset[int]]) -> list[str]:
    """A name for each segment (the set of chains its joints are on): ``"torso"`` for joints several chains share,
    else the chain's role and side (``"left_arm"``, ``"head"``, ``"front_right_leg"``); roles without a side told
    apart are numbered (``"arm1"``, ``"arm2"``), and a single arm is ``"arm"``."""
    labels = []
    for keys in segments:
        if len(keys) > 1:
            labels.append(("torso", ""))
            continue
        k = next(iter(keys))
        words = [*chains[k], robot.end_effectors[k]]
        text = " ".join(words)
        role = "head" if HEAD.search(text) else "leg" if LEG.search(text) or _quadruped_side(words) else "arm"
        labels.append((role, _side(words)))
    names = []
    for role, side in labels:
        same = [(r, s) for r, s in labels if r == role]
        sides = [s for _, s in same]
        if len(same) == 1:
            names.append(role)
        elif side and sides.count(side) == 1:
            names.append(f"{side}_{role}")
        else:
            names.append(f"{role}{sum(1 for n in names if n.startswith(role)) + 1}")
    return names


def _side(words: Sequence[str]) -> str:
    """The side the names say: in the first word that says one, its earliest side token; or ``""``."""
    for word in words:
        lowered = word.lower()
        found = [(m.start(), side) for pattern, side in _SIDES for m in [pattern.search(lowered)] if m]
        if not found:
            continue
        side = min(found)[1]
        front_rear = _FRONT_REAR.search(lowered)
        if side in ("left", "right") and front_rear:
            return f"{'front' if front_rear.group(0) == 'front' else 'rear'}_{side}"
        return side
    return ""


def _quadruped_side(words: Sequence[str]) -> bool:
    return any(pattern.search(w.lower()) for w in words for pattern, side in _SIDES[:4])


def gripper_groups(robot, grouped: set[str]) -> dict[str, list[str]]:
    """The solved joints of no group that move fingers or jaws (:data:`GRIPPER`), as ``"gripper"`` or, when the
    names tell the sides apart, ``"left_gripper"`` / ``"right_gripper"``."""
    found: dict[str, list[str]] = {}
    for name in robot.joint_names:
        if name not in grouped and GRIPPER.search(name):
            found.setdefault(_side([name]), []).append(name)
    if len(found) == 1:
        return {"gripper": next(iter(found.values()))}
    return {f"{side}_gripper" if side else "gripper": joints for side, joints in found.items()}
