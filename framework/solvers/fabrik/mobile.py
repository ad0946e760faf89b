"""A yaw-planar arm on an omnidirectional base ``(x, y, θ)``: the geometry M-FABRIK works with.

World quantities, with the base at ``(b_x, b_y, θ)`` and the arm's yaw turned by ``φ`` from its reference:

* yaw axis (vertical) at ``c = b + R(θ)·mount`` [m], plane origin at height ``height`` [m];
* arm plane heading ``ψ = θ + heading0 + φ`` [rad]: ``e_x = (cos ψ, sin ψ, 0)``, normal ``(sin ψ, -cos ψ, 0)``;
* a plane point ``(x, y)`` sits at ``c + x·e_x + lateral·normal`` horizontally and at ``height + y``.

All of it is read from the Pinocchio model at the base's zero pose (never typed in).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ...model.robot import Robot
from .chain import GEOMETRY_TOLERANCE, PlanarChain, path_joints
from .errors import UnsupportedBaseError, UnsupportedChainError
from .reach import ReachTable
from .regions import BaseReach


class BaseOrientation(str, enum.Enum):
    """How M-FABRIK turns the base after placing it (paper 003's *SetBaseOrientation*).

    * ``FACE_TARGET``: the platform's x axis points at the target.
    * ``FOLLOW_JOINT1``: the base turns with the arm's yaw joint, which stays at its reference angle (0): the
      robot heads where the arm reaches (the paper's path experiment).
    * ``FIXED``: the base keeps the start configuration's heading; the yaw joint turns the arm.
    """

    FACE_TARGET = "face_target"
    FOLLOW_JOINT1 = "follow_joint1"
    FIXED = "fixed"


@dataclass(frozen=True, eq=False)
class MobileArm:
    """The arm's chain and the base's geometry, from the model.

    Attributes:
        robot: the mobile manipulator.
        chain: the arm's yaw-planar chain (a yaw joint with a vertical axis, then >= 2 planar joints).
        base: search indices of the base's ``x`` [m], ``y`` [m] and ``θ`` [rad].
        reach: the planar sub-chain's reach table.
        mount: ``(x, y)`` of the yaw axis in the platform frame [m].
        height: height of the plane origin above the floor plane [m].
        heading0: heading of the plane's ``e_x`` in the platform frame at the yaw's reference [rad].
    """

    robot: Robot = field(repr=False)
    chain: PlanarChain = field(repr=False)
    base: tuple[int, int, int]
    reach: ReachTable = field(repr=False)
    mount: tuple[float, float]
    height: float
    heading0: float

    @classmethod
    def of(cls, robot: Robot, frame: str) -> MobileArm:
        """:meth:`from_robot` built once per robot and frame (its reach table takes ~0.1 s)."""
        return robot.derived(cls.from_robot, frame)

    @classmethod
    def from_robot(cls, robot: Robot, frame: str | None = None, *, base: str = "base") -> MobileArm:
        """Read the arm between the base group and ``frame`` (default: the first end-effector).

        Raises:
            UnsupportedBaseError: ``base`` is not ``(x, y, θ)`` of a planar base in the world's xy-plane.
            UnsupportedChainError: the arm is not a yaw-planar chain with a vertical yaw and >= 2 planar joints.
        """
        frame = robot.end_effectors[0] if frame is None else frame
        base_index = tuple(int(i) for i in robot.group(base))
        if len(base_index) != 3:
            raise UnsupportedBaseError(
                f"group {base!r} has {len(base_index)} coordinates; a planar base has 3 (x, y, θ)"
            )
        arm_joints = [j for j in path_joints(robot, frame) if j.index not in base_index]
        if not arm_joints:
            raise UnsupportedChainError(f"no joint between the base group {base!r} and frame {frame!r}")
        arm = [j.name for j in arm_joints]
        root = int(robot.model.parents[arm_joints[0].pin_id])
        x_ref = np.clip(np.zeros(robot.n), robot.lower, robot.upper)
        x_ref[list(base_index)] = 0.0
        data = robot.model.createData()
        pin.forwardKinematics(robot.model, data, robot.to_pinocchio(x_ref))
        platform = data.oMi[root].copy()
        _check_base(robot, base_index, root, x_ref, platform)
        up = platform.rotation.T @ np.array([0.0, 0.0, 1.0])
        chain = PlanarChain.from_robot(robot, frame, joints=arm, configuration=x_ref, up=up)
        if chain.yaw is None or np.linalg.norm(np.cross(platform.rotation @ chain.e_y, [0, 0, 1])) > 1e-9:
            raise UnsupportedChainError(
                f"M-FABRIK needs an arm whose first position joint turns about the vertical (a yaw); the arm to "
                f"{frame!r} has {'none' if chain.yaw is None else 'a tilted one'}"
            )
        if chain.size < 2:
            raise UnsupportedChainError(
                f"M-FABRIK needs >= 2 planar joints after the yaw; the arm has {chain.size}"
            )
        origin = platform.act(chain.origin)
        e_x = platform.rotation @ chain.e_x
        return cls(
            robot=robot,
            chain=chain,
            base=base_index,  # type: ignore[arg-type]
            reach=ReachTable.from_chain(chain),
            mount=(float(origin[0]), float(origin[1])),
            height=float(origin[2]),
            heading0=math.atan2(e_x[1], e_x[0]),
        )

    # ------------------------------------------------------------------ the admissible annulus
    def base_reach(
        self, target: np.ndarray, rule: BaseOrientation, theta: float, *, slack: float = 0.0
    ) -> BaseReach | None:
        """Base positions ``(x, y)`` from which the arm can reach ``target`` ``(3,)`` [m] when the base turns by
        ``rule`` (``theta`` [rad]: the heading kept by ``FIXED``); None if there are none.

        The radial reach at the target's height comes from :attr:`reach`, its outer end pulled in by ``slack``
        [m] (at most to the middle of the interval) so the arm is never asked to stretch fully, where FABRIK
        converges slowly; with the base heading tied to the arm's plane (``FOLLOW_JOINT1``, ``FACE_TARGET``) the
        mount offset adds to it; with ``FIXED`` the annulus is centred at ``target - R(θ)·mount`` and cut to the
        directions the yaw's limits allow.
        """
        interval = self.reach.interval(float(target[2]) - self.height, front=True)
        if interval is None:
            return None
        lo, hi = interval
        hi = max(hi - slack, 0.5 * (lo + hi))
        lateral = self.chain.lateral
        mx, my = self.mount
        tx, ty = float(target[0]), float(target[1])
        if rule is BaseOrientation.FOLLOW_JOINT1:
            c, s = math.cos(self.heading0), math.sin(self.heading0)
            px, py = c * mx + s * my, -s * mx + c * my  # the mount in the plane's frame

            def radius(x: float) -> float:
                return math.hypot(px + x, py - lateral)

            inner = radius(min(max(-px, lo), hi))
            return BaseReach((tx, ty), inner, max(radius(lo), radius(hi)))
        if rule is BaseOrientation.FACE_TARGET:
            lo = max(lo, math.sqrt(max(my * my - lateral * lateral, 0.0)))
            if lo > hi:
                return None

            def distance(x: float) -> float:
                return mx + math.sqrt(max(x * x + lateral * lateral - my * my, 0.0))

            return BaseReach((tx, ty), max(distance(lo), 0.0), distance(hi))
        ct, st = math.cos(theta), math.sin(theta)
        centre = (tx - (ct * mx - st * my), ty - (st * mx + ct * my))
        chain = self.chain
        turns = sorted(chain.yaw_sign * (q - chain.yaw_reference) for q in (chain.yaw_lower, chain.yaw_upper))
        wedge = None
        if turns[1] - turns[0] < 2 * math.pi - 1e-9:
            slack = abs(math.atan2(lateral, max(lo, GEOMETRY_TOLERANCE))) if lateral else 0.0
            heading = theta + self.heading0 + math.pi
            wedge = (heading + turns[0] + slack, heading + turns[1] - slack)
        return BaseReach(centre, math.hypot(lo, lateral), math.hypot(hi, lateral), wedge)

    # ------------------------------------------------------------------ poses
    def axis(self, bx: float, by: float, theta: float) -> tuple[float, float]:
        """Horizontal position ``c`` [m] of the yaw axis for the base at ``(bx, by, θ)``."""
        c, s = math.cos(theta), math.sin(theta)
        mx, my = self.mount
        return bx + c * mx - s * my, by + s * mx + c * my

    def heading_to(self, cx: float, cy: float, target: np.ndarray) -> float:
        """Plane heading ``ψ`` [rad] through the yaw axis at ``(cx, cy)`` that holds ``target`` in front."""
        hx, hy = float(target[0]) - cx, float(target[1]) - cy
        lateral = self.chain.lateral
        x = math.sqrt(max(hx * hx + hy * hy - lateral * lateral, 0.0))
        return math.atan2(hy, hx) + math.atan2(lateral, x)


def _check_base(robot: Robot, base: tuple[int, ...], root: int, x_ref: np.ndarray, platform: pin.SE3) -> None:
    """The arm's root must move as ``Trans(x, y, 0) · Rz(θ)`` times its zero-pose placement."""
    data = robot.model.createData()
    for pose in ((0.3, -0.2, 0.7), (-0.5, 0.4, -2.0)):
        x = x_ref.copy()
        x[list(base)] = pose
        pin.forwardKinematics(robot.model, data, robot.to_pinocchio(x))
        expected = (
            pin.SE3(pin.utils.rpyToMatrix(0.0, 0.0, pose[2]), np.array([pose[0], pose[1], 0.0])) * platform
        )
        if not data.oMi[root].isApprox(expected, 1e-9):
            names = [robot.coordinate_names[i] for i in base]
            raise UnsupportedBaseError(
                f"coordinates {names} do not move the arm's root as a planar base (x, y, θ about the vertical)"
            )
