"""Joints: how a joint moves and how many search coordinates it has (:class:`JointKind`, the vocabulary of the
robot model and of the compiled kinematics), and the solved and mimic joints read from a Pinocchio model
(:class:`Joint`, :func:`build_joints`)."""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..errors import UnsupportedJointError


class JointKind(str, enum.Enum):
    """How a joint moves, and how many search coordinates it has."""

    REVOLUTE = "revolute"  # 1 angle [rad], bounded
    CONTINUOUS = "continuous"  # 1 angle [rad], unbounded (Pinocchio stores cos, sin)
    PRISMATIC = "prismatic"  # 1 displacement [m]
    PLANAR = "planar"  # x [m], y [m], θ [rad] in the parent's xy-plane (Pinocchio stores x, y, cos, sin)

    @property
    def width(self) -> int:
        """Number of search coordinates of one joint of this kind."""
        return 3 if self is JointKind.PLANAR else 1


_KIND_BY_PINOCCHIO = {
    "JointModelRX": JointKind.REVOLUTE,
    "JointModelRY": JointKind.REVOLUTE,
    "JointModelRZ": JointKind.REVOLUTE,
    "JointModelRevoluteUnaligned": JointKind.REVOLUTE,
    "JointModelRUBX": JointKind.CONTINUOUS,
    "JointModelRUBY": JointKind.CONTINUOUS,
    "JointModelRUBZ": JointKind.CONTINUOUS,
    "JointModelRevoluteUnboundedUnaligned": JointKind.CONTINUOUS,
    "JointModelPX": JointKind.PRISMATIC,
    "JointModelPY": JointKind.PRISMATIC,
    "JointModelPZ": JointKind.PRISMATIC,
    "JointModelPrismaticUnaligned": JointKind.PRISMATIC,
    "JointModelPlanar": JointKind.PLANAR,
}


_AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}


def joint_kind_and_axis(joint: pin.JointModel) -> tuple[JointKind, np.ndarray]:
    """Kind and unit axis (in the joint frame; ``z`` for planar) of a Pinocchio joint model."""
    short = joint.shortname()
    if short not in _KIND_BY_PINOCCHIO:
        raise UnsupportedJointError(
            f"joint type {short} cannot be searched over; lock it (load_robot(..., locked={{name: value}}))"
        )
    kind = _KIND_BY_PINOCCHIO[short]
    if kind is JointKind.PLANAR:
        return kind, np.array([0.0, 0.0, 1.0])
    if short.endswith("Unaligned"):  # the axis is the joint's motion subspace (some bindings expose no `axis`)
        data = joint.createData()
        joint.calc(data, np.array([1.0, 0.0]) if kind is JointKind.CONTINUOUS else np.zeros(1))
        S = np.asarray(data.S, dtype=float).ravel()
        axis = S[:3] if kind is JointKind.PRISMATIC else S[3:]
        norm = np.linalg.norm(axis)
        if not norm > 0:
            raise UnsupportedJointError(f"joint type {short} has a zero axis")
        return kind, axis / norm
    return kind, np.array(_AXES[short[-1]])


@dataclass(frozen=True)
class Joint:
    """One solved joint: its name, kind, slice of the search vector and Pinocchio indices."""

    name: str
    kind: JointKind
    index: int  # first search coordinate
    pin_id: int  # joint index in the Pinocchio model
    idx_q: int  # first entry in Pinocchio's q
    idx_v: int  # first entry in Pinocchio's v
    axis: np.ndarray = field(repr=False)  # (3,) unit axis in the joint frame
    #: a mimic joint follows ``leader``: its value is ``multiplier * x[index] + offset`` (``index``: the leader's
    #: coordinate); it is never a search coordinate of its own
    leader: str | None = None
    multiplier: float = 1.0
    offset: float = 0.0

    @property
    def width(self) -> int:
        return self.kind.width

    @property
    def coordinates(self) -> range:
        """Indices of this joint's coordinates in the search vector."""
        return range(self.index, self.index + self.width)


def coordinate_names(joint: Joint) -> list[str]:
    if joint.kind is JointKind.PLANAR:
        return [f"{joint.name}.x", f"{joint.name}.y", f"{joint.name}.theta"]
    return [joint.name]


def build_joints(
    model: pin.Model, mimic: Mapping[str, tuple[str, float, float]] | None = None
) -> tuple[tuple[Joint, ...], tuple[Joint, ...]]:
    """The solved joints of a Pinocchio model in model order with their search-vector offsets, and the mimic
    joints (``mimic``: name -> (leader, multiplier, offset)), which take their leader's coordinate."""
    mimic = mimic or {}
    joints, followers, index = [], [], 0
    for jid in range(1, model.njoints):
        jm, name = model.joints[jid], model.names[jid]
        try:
            kind, axis = joint_kind_and_axis(jm)
        except UnsupportedJointError as err:
            raise UnsupportedJointError(f"joint {name!r}: {err}") from None
        if name in mimic:
            if kind is JointKind.PLANAR:
                raise UnsupportedJointError(f"joint {name!r}: a planar joint cannot mimic another")
            followers.append((name, kind, jid, jm, axis))
            continue
        joints.append(Joint(name, kind, index, jid, jm.idx_q, jm.idx_v, axis))
        index += kind.width
    by_name = {j.name: j for j in joints}
    mimics = []
    for name, kind, jid, jm, axis in followers:
        leader, multiplier, offset = mimic[name]
        if leader not in by_name or by_name[leader].width != 1:
            raise UnsupportedJointError(f"joint {name!r} mimics {leader!r}, which is not a solved one-coordinate joint")
        mimics.append(Joint(name, kind, by_name[leader].index, jid, jm.idx_q, jm.idx_v, axis, leader,
                            float(multiplier), float(offset)))
    return tuple(joints), tuple(mimics)
