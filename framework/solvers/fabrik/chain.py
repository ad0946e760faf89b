"""Serial chains FABRIK can solve, with their geometry read from the Pinocchio model.

Supported chains ("yaw-planar"). The revolute joints that move the end-effector *position* are either

* all parallel: a planar arm, whose end-effector moves in one fixed plane; or
* a first joint, the *yaw*, followed by parallel joints whose axes are perpendicular to the yaw axis: the KUKA
  youBot (joint 1 | joints 2-4), the Puma 560's position sub-chain (joint 1 | joints 2-3). The yaw turns the
  plane of the others about its axis; that plane may sit at a constant offset from the yaw axis (the Puma's
  shoulder offset).

Joints whose axis passes through the end-effector point at every configuration (the youBot's wrist roll, a
spherical wrist centred on the end-effector frame) do not move the position; they must follow the position
joints, and keep their value. Prismatic joints, two non-parallel joints after the yaw, or a yaw that is not
perpendicular to the joints after it raise :class:`UnsupportedChainError`. The structure is detected from joint
axes and origins at several configurations, never from the robot's name.

Plane coordinates. Every point of the chain is written ``(x, y)`` [m] in the plane of the planar joints:
``x`` along ``e_x``, ``y`` along ``e_y`` (the yaw axis, for yaw chains), from ``origin`` (on the yaw axis);
every position joint and the end-effector lie at the signed offset ``lateral`` [m] along the normal
``n = e_x × e_y``, so a rotation about ``+n`` is counter-clockwise in ``(x, y)``. The chain's *points* are the
intersections of the planar joints' axes with that plane, then the end-effector: ``(K + 1, 2)`` for ``K``
planar joints. Link lengths and reference turns are read from Pinocchio at one configuration and are constant.
Vectors are expressed in the frame of the chain's *root* joint (the joint before the chain; the world for a
fixed arm, the platform for a mobile manipulator) and ``e_x``, ``n`` are given at the yaw's reference angle:
turning the yaw by ``φ`` [rad] about ``e_y`` turns them by ``φ``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ...model.joints import Joint, JointKind
from ...model.robot import Robot
from .angles import clamp_angle, joint_angle, wrap
from .errors import UnsupportedChainError

#: Distances [m] and sines below this count as zero when classifying joints.
GEOMETRY_TOLERANCE = 1e-9
_REVOLUTE = (JointKind.REVOLUTE, JointKind.CONTINUOUS)


@dataclass(frozen=True, eq=False)
class PlanarChain:
    """A yaw-planar chain of a robot, from its root joint to an end-effector frame (see the module docstring).

    Attributes:
        robot: the robot the chain belongs to.
        frame: end-effector frame.
        root: Pinocchio id of the joint whose frame expresses the geometry (0: the world).
        yaw: search index of the yaw joint, or None for a planar arm.
        planar: search indices of the ``K`` planar joints, root to tip.
        passive: search indices of the trailing joints that do not move the end-effector position.
        origin: ``(3,)`` plane origin in the root frame [m] (on the yaw axis).
        e_x, e_y, normal: ``(3,)`` unit plane axes in the root frame, at the yaw's reference angle.
        lateral: offset of the chain's plane along ``normal`` [m].
        start: ``(2,)`` plane coordinates of the first planar joint [m] (fixed in the yaw frame).
        lengths: ``(K,)`` link lengths between consecutive points [m].
        turns: ``(K,)`` turn of each link from the previous one (from ``e_x`` for the first) at ``reference``.
        signs: ``(K,)`` +1 where the joint axis is ``normal``, -1 where it is ``-normal``.
        reference: ``(K,)`` planar joint angles at which ``turns`` were read [rad].
        lower, upper: ``(K,)`` limits of the planar joints [rad].
        yaw_reference, yaw_lower, yaw_upper: yaw angle at which ``e_x`` was read, and its limits [rad].
        yaw_sign: +1 if the yaw joint's axis is ``e_y``, -1 if it is ``-e_y``.
    """

    robot: Robot = field(repr=False)
    frame: str
    root: int
    yaw: int | None
    planar: tuple[int, ...]
    passive: tuple[int, ...]
    origin: np.ndarray = field(repr=False)
    e_x: np.ndarray = field(repr=False)
    e_y: np.ndarray = field(repr=False)
    normal: np.ndarray = field(repr=False)
    lateral: float
    start: np.ndarray = field(repr=False)
    lengths: np.ndarray = field(repr=False)
    turns: np.ndarray = field(repr=False)
    signs: np.ndarray = field(repr=False)
    reference: np.ndarray = field(repr=False)
    lower: np.ndarray = field(repr=False)
    upper: np.ndarray = field(repr=False)
    yaw_reference: float = 0.0
    yaw_lower: float = -math.pi
    yaw_upper: float = math.pi
    yaw_sign: float = 1.0

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_robot(
        cls,
        robot: Robot,
        frame: str | None = None,
        *,
        joints: str | Sequence[str] | None = None,
        configuration: np.ndarray | None = None,
        up: np.ndarray | None = None,
    ) -> PlanarChain:
        """Detect the chain's structure and read its geometry from the Pinocchio model.

        Args:
            robot: the robot.
            frame: end-effector frame (default: the robot's first end-effector).
            joints: the chain's joints: a group name (``"arm"``) or joint names; default every solved joint
                between the world and ``frame``. Joints before the chain (a mobile base) set its root.
            configuration: ``(n,)`` joint coordinates at which link lengths and reference turns are read
                (default: zero, clipped into the search bounds).
            up: ``(3,)`` preferred direction of ``e_y`` for a yaw chain, in the root frame (default: the yaw
                joint's axis).

        Raises:
            UnsupportedChainError: the chain is outside the supported class; the message names the joints.
        """
        frame = robot.end_effectors[0] if frame is None else frame
        frame_id = robot.frame_id(frame)
        chain = _chain_joints(robot, frame_id, joints)
        x_ref = (
            np.clip(np.zeros(robot.n), robot.lower, robot.upper) if configuration is None else configuration
        )
        x_ref = robot.check_population(x_ref)[0]
        root = int(robot.model.parents[chain[0].pin_id])
        samples = _samples(robot, chain, x_ref)
        axes, origins, tips = _chain_geometry(robot, chain, frame_id, root, samples)

        passive = _passive(axes, origins, tips)
        if all(passive):
            raise UnsupportedChainError(
                f"no joint of {[j.name for j in chain]} moves the position of {frame!r}"
            )
        last = max(i for i, p in enumerate(passive) if not p)
        if any(passive[: last + 1]):
            inner = [chain[i].name for i in range(last + 1) if passive[i]]
            raise UnsupportedChainError(
                f"joints {inner} do not move {frame!r} but sit between joints that do; FABRIK here needs the "
                "position joints first"
            )
        active = list(range(last + 1))
        yaw = _split_yaw(chain, active, axes)
        planar = active[1:] if yaw is not None else active

        a, o, tip = axes[0], origins[0], tips[0]  # geometry at the reference configuration
        origin, e_x, e_y, yaw_sign = _plane_axes(a, o, tip, yaw, planar, up)
        normal = np.cross(e_x, e_y)
        lateral = float(normal @ (tip - origin))

        # The planar joints' axes met with the plane that holds the end-effector, then the end-effector.
        joints_at = [o[i] + normal * (lateral - normal @ (o[i] - origin)) for i in planar]
        points3 = np.array([*joints_at, tip]) - origin
        points = np.stack([points3 @ e_x, points3 @ e_y], axis=1)
        steps = np.diff(points, axis=0)
        lengths = np.linalg.norm(steps, axis=1)
        if np.any(lengths < GEOMETRY_TOLERANCE):
            k = int(np.argmin(lengths))
            raise UnsupportedChainError(
                f"joint {chain[planar[k]].name!r} and the next point of the chain coincide (zero-length link)"
            )
        directions = np.arctan2(steps[:, 1], steps[:, 0])
        turns = np.array([wrap(d) for d in np.diff(np.concatenate([[0.0], directions]))])
        signs = np.array([1.0 if a[i] @ normal > 0 else -1.0 for i in planar])
        index = [chain[i].index for i in planar]
        yaw_index = chain[yaw].index if yaw is not None else None
        return cls(
            robot=robot,
            frame=frame,
            root=root,
            yaw=yaw_index,
            planar=tuple(index),
            passive=tuple(chain[i].index for i in range(last + 1, len(chain))),
            origin=origin,
            e_x=e_x,
            e_y=e_y,
            normal=normal,
            lateral=lateral,
            start=points[0].copy(),
            lengths=lengths,
            turns=turns,
            signs=signs,
            reference=x_ref[index].copy(),
            lower=robot.lower[index].copy(),
            upper=robot.upper[index].copy(),
            yaw_reference=float(x_ref[yaw_index]) if yaw_index is not None else 0.0,
            yaw_lower=float(robot.lower[yaw_index]) if yaw_index is not None else -math.pi,
            yaw_upper=float(robot.upper[yaw_index]) if yaw_index is not None else math.pi,
            yaw_sign=yaw_sign,
        )

    # ------------------------------------------------------------------ sizes
    @property
    def size(self) -> int:
        """Number ``K`` of planar joints."""
        return len(self.planar)

    @property
    def shoulder(self) -> tuple[float, float]:
        """Plane coordinates ``(x, y)`` [m] of the first planar joint (fixed in the yaw frame)."""
        return float(self.start[0]), float(self.start[1])

    @property
    def reach(self) -> float:
        """Sum of the link lengths [m]."""
        return float(self.lengths.sum())

    # ------------------------------------------------------------------ planar kinematics
    def points(self, q: np.ndarray) -> np.ndarray:
        """Plane coordinates of the chain's points for planar joint angles ``q`` ``(..., K)`` -> ``(..., K+1, 2)``."""
        q = np.asarray(q, dtype=float)
        alpha = np.cumsum(self.turns + self.signs * (q - self.reference), axis=-1)
        steps = self.lengths[..., None] * np.stack([np.cos(alpha), np.sin(alpha)], axis=-1)
        first = self.start
        return np.concatenate(
            [np.broadcast_to(first, steps[..., :1, :].shape), first + np.cumsum(steps, -2)], -2
        )

    def angles(self, points: np.ndarray) -> np.ndarray:
        """Planar joint angles ``(K,)`` [rad] that place the links along ``points`` ``(K+1, 2)``, clipped to limits.

        Each link's direction is taken relative to the previous one (to ``e_x`` for the first); the signed turn
        gives the joint angle about the joint's own axis.
        """
        points = np.asarray(points, dtype=float)
        q = np.empty(self.size)
        previous = 0.0
        for i in range(self.size):
            dx, dy = points[i + 1] - points[i]
            direction = math.atan2(dy, dx)
            q[i] = joint_angle(
                direction - previous,
                self.turns[i],
                self.signs[i],
                self.reference[i],
                self.lower[i],
                self.upper[i],
            )[0]
            previous = direction
        return q

    # ------------------------------------------------------------------ the yaw
    def axes(self, phi: float) -> tuple[np.ndarray, np.ndarray]:
        """``e_x`` and ``normal`` ``(3,)`` after turning the yaw by ``phi`` [rad] from its reference."""
        if self.yaw is None:
            return self.e_x, self.normal
        c, s = math.cos(phi), math.sin(phi)
        e2 = np.cross(self.e_y, self.e_x)  # = -normal
        return c * self.e_x + s * e2, s * self.e_x - c * e2

    def yaw_headings(self, target: np.ndarray) -> list[float]:
        """Yaw turns ``φ`` [rad] that bring ``target`` ``(3,)`` (root frame) into the chain's plane.

        Two for a yaw chain (the plane in front of the yaw axis, then behind it), one (0) for a planar arm.
        When the target is closer to the yaw axis than ``|lateral|``, both put it as close as possible.
        """
        if self.yaw is None:
            return [0.0]
        w = np.asarray(target, dtype=float) - self.origin
        e2 = np.cross(self.e_y, self.e_x)
        a, b = float(w @ self.e_x), float(w @ e2)
        x = math.sqrt(max(a * a + b * b - self.lateral**2, 0.0))
        beta = math.atan2(b, a)
        return [beta + math.atan2(self.lateral, x), beta + math.atan2(self.lateral, -x)]

    def yaw_angle(self, phi: float) -> float:
        """Yaw joint angle [rad] of the turn ``phi``, clipped to its limits."""
        return clamp_angle(self.yaw_reference + self.yaw_sign * phi, self.yaw_lower, self.yaw_upper)

    def yaw_turn(self, q_yaw: float) -> float:
        """Turn ``φ`` [rad] of the plane for yaw joint angle ``q_yaw``."""
        return self.yaw_sign * (q_yaw - self.yaw_reference)

    def plane_target(self, target: np.ndarray, phi: float) -> tuple[float, float, float]:
        """``(x, y, off)``: plane coordinates [m] of ``target`` (root frame) for yaw turn ``phi``, and its
        distance from the plane [m]."""
        w = np.asarray(target, dtype=float) - self.origin
        e_x, n = self.axes(phi)
        return float(w @ e_x), float(w @ self.e_y), float(w @ n) - self.lateral

    def to_root(self, points: np.ndarray, phi: float) -> np.ndarray:
        """Root-frame positions ``(m, 3)`` [m] of plane points ``(m, 2)`` for yaw turn ``phi``."""
        e_x, n = self.axes(phi)
        points = np.asarray(points, dtype=float)
        return self.origin + self.lateral * n + points[:, :1] * e_x + points[:, 1:2] * self.e_y

    def configuration(self, x0: np.ndarray, q_planar: np.ndarray, q_yaw: float | None = None) -> np.ndarray:
        """``x0`` ``(n,)`` with the planar joints (and the yaw) replaced; other joints keep their values."""
        x = np.array(x0, dtype=float)
        x[list(self.planar)] = q_planar
        if self.yaw is not None and q_yaw is not None:
            x[self.yaw] = q_yaw
        return x


# ---------------------------------------------------------------------------------------------- helpers


def path_joints(robot: Robot, frame: str) -> list[Joint]:
    """The solved joints between the world and ``frame``, root first."""
    model = robot.model
    by_id = {j.pin_id: j for j in robot.joints}
    path, jid = [], model.frames[robot.frame_id(frame)].parentJoint
    while jid > 0:
        path.append(jid)
        jid = model.parents[jid]
    return [by_id[j] for j in reversed(path) if j in by_id]


def _chain_joints(robot: Robot, frame_id: int, joints: str | Sequence[str] | None) -> list[Joint]:
    """The solved joints between the world and the frame, restricted to ``joints``; checks they are revolute."""
    model = robot.model
    on_path = path_joints(robot, model.frames[frame_id].name)
    if joints is None:
        chosen = on_path
    else:
        names = (
            [j.name for j in robot.joints if j.index in set(robot.group(joints).tolist())]
            if isinstance(joints, str)
            else [robot.joint(name).name for name in joints]
        )
        off = [n for n in names if n not in {j.name for j in on_path}]
        if off:
            raise UnsupportedChainError(
                f"joints {off} are not between the world and frame {model.frames[frame_id].name!r}"
            )
        chosen = [j for j in on_path if j.name in names]
    if not chosen:
        raise UnsupportedChainError(f"no solved joint moves frame {model.frames[frame_id].name!r}")
    first = on_path.index(chosen[0])
    gaps = [j.name for j in on_path[first:] if j not in chosen]
    if gaps:
        raise UnsupportedChainError(
            f"joints {gaps} lie inside the chain but are not part of it; include them or lock them when loading"
        )
    for j in chosen:
        if j.kind not in _REVOLUTE:
            raise UnsupportedChainError(
                f"joint {j.name!r} is {j.kind.value}; FABRIK here solves revolute chains (hold other joints "
                "outside the chain, e.g. joints='arm')"
            )
    return chosen


def _samples(robot: Robot, chain: list[Joint], x_ref: np.ndarray, count: int = 6) -> np.ndarray:
    """``x_ref`` and ``count - 1`` configurations with the chain's joints drawn in their bounds (fixed seed)."""
    rng = np.random.default_rng(0)
    X = np.repeat(x_ref[None], count, axis=0)
    idx = [j.index for j in chain]
    X[1:, idx] = robot.lower[idx] + (robot.upper[idx] - robot.lower[idx]) * rng.random((count - 1, len(idx)))
    return X


def _chain_geometry(
    robot: Robot, chain: list[Joint], frame_id: int, root: int, X: np.ndarray
) -> tuple[list[np.ndarray], list[np.ndarray], list[np.ndarray]]:
    """Per sample: joint axes ``(m, 3)``, joint origins ``(m, 3)`` and the end-effector ``(3,)``, root frame."""
    model, data = robot.model, robot.model.createData()
    axes, origins, tips = [], [], []
    for x in X:
        pin.framesForwardKinematics(model, data, robot.to_pinocchio(x))
        inv = data.oMi[root].inverse()
        placements = [inv * data.oMi[j.pin_id] for j in chain]
        axes.append(np.array([m.rotation @ j.axis for m, j in zip(placements, chain)]))
        origins.append(np.array([m.translation for m in placements]))
        tips.append((inv * data.oMf[frame_id]).translation.copy())
    return axes, origins, tips


def _passive(axes: list[np.ndarray], origins: list[np.ndarray], tips: list[np.ndarray]) -> list[bool]:
    """Per chain joint: does the end-effector point lie on its axis at every sample?"""
    flags = np.ones(len(axes[0]), dtype=bool)
    for a, o, tip in zip(axes, origins, tips):
        flags &= np.linalg.norm(np.cross(tip - o, a), axis=1) < GEOMETRY_TOLERANCE
    return flags.tolist()


def _plane_axes(
    a: np.ndarray, o: np.ndarray, tip: np.ndarray, yaw: int | None, planar: list[int], up: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Plane origin, ``e_x``, ``e_y`` and the yaw's sign, from joint axes ``a`` and origins ``o`` ``(m, 3)``.

    Yaw chain: the origin is on the yaw axis, ``e_y`` is the yaw axis (flipped towards ``up``), ``e_x = e_y × n``
    for the planar axis ``n``. Planar arm: the origin is the first joint, ``e_x`` points at the next point.
    Either way ``e_x × e_y`` is the first planar joint's axis (up to sign), so turns about it are counter-clockwise.
    """
    normal = a[planar[0]]
    if yaw is None:
        radial = (o[planar[1]] if len(planar) > 1 else tip) - o[planar[0]]
        radial = radial - normal * (normal @ radial)
        if np.linalg.norm(radial) < GEOMETRY_TOLERANCE:
            radial = np.cross(normal, np.eye(3)[np.argmin(np.abs(normal))])
        e_x = radial / np.linalg.norm(radial)
        return o[planar[0]], e_x, np.cross(normal, e_x), 1.0
    e_y, sign = a[yaw], 1.0
    if up is not None and float(np.dot(e_y, up)) < 0.0:
        e_y, sign = -e_y, -1.0
    return o[yaw], np.cross(e_y, normal), e_y, sign


def _split_yaw(chain: list[Joint], active: list[int], axes: list[np.ndarray]) -> int | None:
    """Index (in ``chain``) of the yaw joint, or None for a planar chain; raises outside the supported class."""

    def parallel(i: int, j: int) -> bool:
        return all(np.linalg.norm(np.cross(a[i], a[j])) < GEOMETRY_TOLERANCE for a in axes)

    first = active[0]
    if all(parallel(first, j) for j in active[1:]):
        return None
    rest = active[1:]
    for j in rest[1:]:
        if not parallel(rest[0], j):
            raise UnsupportedChainError(
                f"joints {chain[rest[0]].name!r} and {chain[j].name!r} both move the end-effector position but "
                "their axes are not parallel: FABRIK here supports a yaw joint followed by parallel joints"
            )
    if not all(abs(a[first] @ a[rest[0]]) < GEOMETRY_TOLERANCE for a in axes):
        raise UnsupportedChainError(
            f"the yaw joint {chain[first].name!r} is neither parallel nor perpendicular to "
            f"{chain[rest[0]].name!r}: its plane would not turn about the yaw axis"
        )
    return first
