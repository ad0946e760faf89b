"""M-FABRIK (Santos et al. 2020, paper 003, Algorithm 1): FABRIK for an arm on an omnidirectional base.

One iteration, in the arm's plane (:mod:`framework.solvers.fabrik.mobile`):

1. *Forward reaching*: the plane is turned about the yaw axis to hold the target; the end-effector is put on the
   target and the joints are pulled after it, which drags the first joint, and with it the base, off its place.
2. *ProjectPoint*: the base follows the first joint along the floor plane Φ; the orientation rule gives the base
   heading for that yaw axis. The base carries the first joint at a fixed height, so by default (``keep_link``)
   the forward pass already puts the first joint back at that height, where the first link still reaches it
   (the point of Φ nearest the forward-reached base among those that keep the link's length); with
   ``keep_link=False`` the first joint is projected orthogonally, as in the paper, and the height error is left
   to the backward pass.
3. *MoveToAdmArea*: a base position outside the admissible area moves to its nearest point.
4. *SetBaseOrientation*: the heading rule and the yaw joint are settled for the placed base.
5. *Backward reaching* from the first joint's fixed place on the placed base.

Before the loop (*CreateAdmissibleArea*) the admissible area is built; if it is empty the solve returns at once with
``success=False`` and an ``"unreachable: ..."`` reason. An attempt that stops converging (joint limits can trap
FABRIK) restarts from a new arm shape (:mod:`framework.solvers.fabrik.progress`); the loop is capped, never endless.

Deviation from Algorithm 1: the heading is set before the backward pass (line 18 of the paper sets it after),
because the youBot's arm is mounted off the base's centre: turning the base after the pass would move the shoulder
and undo the pass.

Example::

    robot = framework.load_robot("youbot_mobile")
    solver = MFabrik.from_robot(robot, environment=Environment([Circle((0.5, 0.0), 0.2)], bounds=((-2, 2),) * 2))
    result = solver.solve(target=[0.8, 0.3, 0.4], x0=np.zeros(robot.n), tolerance=1e-3)
"""

from __future__ import annotations

import math
import time

import numpy as np

from ...model.robot import Robot
from .angles import clamp_angle
from .environment import Environment
from .fabrik import check_target
from .kinematics import PointKinematics
from .mobile import BaseOrientation, MobileArm
from .passes import Links, backward, forward
from .progress import Progress, random_shape
from .regions import Region
from .result import ReachResult

#: Cap on the fixed-point iterations that settle the base heading (they contract by ~|mount| / reach).
_FIXED_POINT_ITERATIONS = 50


class MFabrik:
    """M-FABRIK solver for one mobile manipulator and one environment.

    Args:
        arm: the arm and base geometry, from :meth:`MobileArm.from_robot`.
        environment: obstacles, margin and navigable box (default: no obstacles, the base's search bounds).
        orientation: how the base turns (:class:`BaseOrientation` or its value).
        keep_link: place the first joint on its fixed height during forward reaching (True; see the module
            docstring) or leave it where the line puts it, as the paper's orthogonal ProjectPoint (False).
        reach_margin: keep the base this fraction of the arm's length (the sum of its planar links) inside its
            outer reach (the outer edge of the admissible annulus is pulled in by as much, at most to the middle
            of the annulus). A stretched arm is near its singularity, where FABRIK converges slowly and the
            manipulability is low (one of paper 003's criteria for an admissible area); 0 gives the raw reach.
        window, restarts, seed: stall detection and restarts (:class:`~framework.solvers.fabrik.progress.Progress`); new
            arm shapes are drawn from ``numpy.random.default_rng(seed)``, so a solve is deterministic.
    """

    def __init__(
        self,
        arm: MobileArm,
        environment: Environment | None = None,
        *,
        orientation: BaseOrientation | str = BaseOrientation.FOLLOW_JOINT1,
        keep_link: bool = True,
        reach_margin: float = 0.2,
        window: int = 4,
        restarts: int = 10,
        seed: int = 0,
    ) -> None:
        self.arm = arm
        self.robot = arm.robot
        ix, iy, _ = arm.base
        lower, upper = arm.robot.lower, arm.robot.upper
        self.environment = environment or Environment(bounds=((lower[ix], upper[ix]), (lower[iy], upper[iy])))
        self.orientation = BaseOrientation(orientation)
        self.keep_link = keep_link
        self.reach_margin = reach_margin
        self.window = window
        self.restarts = restarts
        self.seed = seed
        self.links = Links.of(arm.chain)
        self._fk = PointKinematics(arm.robot, arm.chain.frame)

    @classmethod
    def from_robot(cls, robot: Robot, frame: str | None = None, **kwargs) -> MFabrik:
        """Build the solver for ``robot`` (base group ``"base"``); keyword arguments as the constructor."""
        return cls(MobileArm.from_robot(robot, frame), **kwargs)

    # ------------------------------------------------------------------ the admissible area
    def admissible_area(self, target: np.ndarray, x0: np.ndarray) -> Region | None:
        """Where the base may stand to reach ``target`` ``(3,)`` [m] starting from ``x0`` ``(n,)``; None if the
        target's height is out of the arm's reach."""
        ix, iy, ith = self.arm.base
        reach = self.arm.base_reach(
            np.asarray(target, dtype=float),
            self.orientation,
            float(x0[ith]),
            slack=self.reach_margin * self.arm.chain.reach,
        )
        return None if reach is None else self.environment.admissible(reach, (float(x0[ix]), float(x0[iy])))

    # ------------------------------------------------------------------ Algorithm 1
    def solve(
        self, target: np.ndarray, x0: np.ndarray, *, tolerance: float = 1e-6, max_iterations: int = 1000,
        seed: int | None = None,
    ) -> ReachResult:
        """Reach ``target`` ``(3,)`` [m, world] from ``x0`` ``(n,)``, moving base and arm.

        Args:
            target: end-effector position [m].
            x0: start configuration (base and arm); its heading is the one ``FIXED`` keeps.
            tolerance: success threshold on the position error [m].
            max_iterations: cap on iterations.
            seed: the restarts' arm shapes are drawn from ``default_rng(seed)`` (default: the planner's ``seed``).
        """
        start = time.perf_counter()
        target = check_target(target)
        x0 = self.robot.check_population(x0, "start configuration")[0]
        arm, chain = self.arm, self.arm.chain
        ix, iy, ith = arm.base
        bx, by, th = float(x0[ix]), float(x0[iy]), float(x0[ith])
        fixed = th
        region = self.admissible_area(target, x0)
        if region is None or region.is_empty:
            why = (
                f"the target's height {target[2]:.4g} m is out of the arm's reach"
                if region is None
                else "no admissible base position (out of the navigable area or inside the rejection area)"
            )
            return self._result(x0, target, 0, start, f"unreachable: {why}", [(bx, by, th)], [math.nan])

        tx, ty, tz = (float(v) for v in target)
        points = chain.points(x0[list(chain.planar)])
        xs, ys = points[:, 0].tolist(), points[:, 1].tolist()
        sx, sy = chain.shoulder
        lateral, height = chain.lateral, arm.height
        q_yaw = float(x0[chain.yaw])
        psi = th + arm.heading0 + chain.yaw_turn(q_yaw)
        cx, cy = arm.axis(bx, by, th)
        path = [(bx, by, th)]
        progress = Progress(tolerance, max_iterations, self.window, self.restarts)
        progress.history.append(self._error(cx, cy, psi, xs[-1], ys[-1], target))
        best = (progress.history[0], xs.copy(), ys.copy(), bx, by, th, q_yaw)
        rng = None
        while (decision := progress.decide()) in ("continue", "restart", "resume"):
            if decision == "restart":  # a new arm shape, from the base where it stands
                rng = rng or np.random.default_rng(self.seed if seed is None else seed)
                xs, ys = random_shape(chain, rng)
            elif decision == "resume":  # back to the best state met
                _, xs, ys, bx, by, th, q_yaw = best
                xs, ys = xs.copy(), ys.copy()
                cx, cy = arm.axis(bx, by, th)
            # Forward reaching, in the plane through the yaw axis that holds the target.
            psi = arm.heading_to(cx, cy, target)
            ex, ey = math.cos(psi), math.sin(psi)
            forward(
                xs,
                ys,
                ex * (tx - cx) + ey * (ty - cy),
                tz - height,
                self.links,
                sy if self.keep_link else None,
            )
            # ProjectPoint: the yaw axis follows the first joint along the floor; heading by the rule.
            shift = xs[0] - sx
            cx, cy = cx + shift * ex, cy + shift * ey
            xs = [x - shift for x in xs]
            th = self._heading_for_axis(cx, cy, psi, th, fixed, target)
            ax, ay = arm.axis(0.0, 0.0, th)
            # MoveToAdmArea, then SetBaseOrientation for the placed base.
            bx, by = region.nearest(cx - ax, cy - ay)
            th, ncx, ncy, npsi, q_yaw = self._place(bx, by, th, fixed, target)
            # The old points, seen from the new plane (orthogonal projection), guide the backward pass.
            if (ncx, ncy, npsi) != (cx, cy, psi):
                nex, ney = math.cos(npsi), math.sin(npsi)
                ox = cx + lateral * ey - ncx
                oy = cy - lateral * ex - ncy
                xs = [nex * (ox + x * ex) + ney * (oy + x * ey) for x in xs]
                cx, cy, psi = ncx, ncy, npsi
            backward(xs, ys, sx, sy, self.links)
            path.append((bx, by, th))
            progress.history.append(self._error(cx, cy, psi, xs[-1], ys[-1], target))
            if progress.history[-1] < best[0]:
                best = (progress.history[-1], xs.copy(), ys.copy(), bx, by, th, q_yaw)

        _, xs, ys, bx, by, th, q_yaw = best
        x = x0.copy()
        x[[ix, iy, ith]] = bx, by, th
        x = chain.configuration(x, chain.angles(np.column_stack([xs, ys])), q_yaw)
        return self._result(
            x, target, progress.iterations, start, decision, path, progress.history, tolerance
        )

    # ------------------------------------------------------------------ a configuration at a given base position
    def pose_at(
        self, base: tuple[float, float], target: np.ndarray, x_previous: np.ndarray, *, iterations: int = 10
    ) -> np.ndarray:
        """Configuration ``(n,)`` with the base at ``base`` ``(x, y)`` [m], turned by the rule, and the arm reaching
        for ``target`` from its shape in ``x_previous`` by FABRIK on that fixed base (Algorithm 2's intermediate
        configurations; the target need not be reachable from there)."""
        target = check_target(target)
        x_previous = self.robot.check_population(x_previous, "previous configuration")[0]
        arm, chain = self.arm, self.arm.chain
        ix, iy, ith = arm.base
        bx, by = float(base[0]), float(base[1])
        fixed = float(x_previous[ith])
        th, cx, cy, psi, q_yaw = self._place(bx, by, fixed, fixed, target)
        points = chain.points(x_previous[list(chain.planar)])
        xs, ys = points[:, 0].tolist(), points[:, 1].tolist()
        tx = math.cos(psi) * (float(target[0]) - cx) + math.sin(psi) * (float(target[1]) - cy)
        sx, sy = chain.shoulder
        for _ in range(iterations):
            forward(xs, ys, tx, float(target[2]) - arm.height, self.links)
            backward(xs, ys, sx, sy, self.links)
        x = x_previous.copy()
        x[[ix, iy, ith]] = bx, by, th
        return chain.configuration(x, chain.angles(np.column_stack([xs, ys])), q_yaw)

    # ------------------------------------------------------------------ the base's heading
    def _heading_for_axis(
        self, cx: float, cy: float, psi: float, theta: float, fixed: float, target: np.ndarray
    ) -> float:
        """Base heading [rad] for a yaw axis at ``(cx, cy)`` and plane heading ``psi``, by the rule (``theta``:
        the current heading, ``fixed``: the heading ``FIXED`` keeps)."""
        arm = self.arm
        if self.orientation is BaseOrientation.FOLLOW_JOINT1:
            return psi - arm.heading0
        if self.orientation is BaseOrientation.FACE_TARGET:
            for _ in range(_FIXED_POINT_ITERATIONS):  # the base centre depends on the heading (mount offset)
                ax, ay = arm.axis(0.0, 0.0, theta)
                theta, last = math.atan2(float(target[1]) - (cy - ay), float(target[0]) - (cx - ax)), theta
                if abs(math.remainder(theta - last, 2 * math.pi)) < 1e-14:
                    break
            return theta
        return fixed

    def _place(
        self, bx: float, by: float, theta: float, fixed: float, target: np.ndarray
    ) -> tuple[float, float, float, float, float]:
        """Heading, yaw axis, plane heading and yaw joint angle for the base at ``(bx, by)``."""
        arm, chain = self.arm, self.arm.chain
        if self.orientation is BaseOrientation.FOLLOW_JOINT1:
            for _ in range(_FIXED_POINT_ITERATIONS):  # the yaw axis depends on the heading (mount offset)
                theta, last = arm.heading_to(*arm.axis(bx, by, theta), target) - arm.heading0, theta
                if abs(math.remainder(theta - last, 2 * math.pi)) < 1e-14:
                    break
        elif self.orientation is BaseOrientation.FACE_TARGET:
            theta = math.atan2(float(target[1]) - by, float(target[0]) - bx)
        else:
            theta = fixed
        ith = arm.base[2]
        theta = clamp_angle(theta, float(self.robot.lower[ith]), float(self.robot.upper[ith]))
        cx, cy = arm.axis(bx, by, theta)
        q_yaw = chain.yaw_angle(arm.heading_to(cx, cy, target) - theta - arm.heading0)
        return theta, cx, cy, theta + arm.heading0 + chain.yaw_turn(q_yaw), q_yaw

    # ------------------------------------------------------------------ errors and results
    def _error(self, cx: float, cy: float, psi: float, x: float, y: float, target: np.ndarray) -> float:
        """Distance [m] from the end-effector at plane point ``(x, y)`` to ``target``."""
        lateral = self.arm.chain.lateral
        c, s = math.cos(psi), math.sin(psi)
        return math.sqrt(
            (cx + x * c + lateral * s - target[0]) ** 2
            + (cy + x * s - lateral * c - target[1]) ** 2
            + (self.arm.height + y - target[2]) ** 2
        )

    def _result(
        self,
        x: np.ndarray,
        target: np.ndarray,
        iterations: int,
        start: float,
        reason: str,
        path: list[tuple[float, float, float]],
        history: list[float],
        tolerance: float = 0.0,
    ) -> ReachResult:
        error = float(np.linalg.norm(self._fk.position(x) - target))
        success = error <= tolerance and not reason.startswith("unreachable")
        if reason == "converged" and not success:
            reason = "stalled"
        if reason.startswith("unreachable"):
            history = [error]
        return ReachResult(
            configuration=x,
            position_error=error,
            iterations=iterations,
            wall_time=time.perf_counter() - start,
            success=success,
            reason=reason,
            solver="m-fabrik",
            base_path=np.array(path),
            error_history=np.array(history),
        )
