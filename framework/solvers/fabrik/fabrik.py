"""FABRIK for a fixed-base yaw-planar chain (Aristidou & Lasenby 2011), with joint limits.

One solve: read the chain's root placement at the start configuration; turn the yaw so the plane holds the target
(in front of the yaw axis if the yaw's limits and the arm's reach allow, else behind it, else as near as the yaw's
limits allow); then alternate forward and backward reaching in that plane until the end-effector is within the
tolerance, the iteration cap is hit, or the error stops decreasing. Joint angles come from the final points
(:meth:`PlanarChain.angles`); the reported error is Pinocchio's, at those angles.

Example::

    robot = framework.load_robot("youbot_arm")
    solver = Fabrik(PlanarChain.from_robot(robot))
    result = solver.solve(target=[0.3, 0.1, 0.4], x0=np.zeros(robot.n))
"""

from __future__ import annotations

import math
import time

import numpy as np

from ...errors import TaskError
from .chain import PlanarChain
from .kinematics import PointKinematics
from .passes import Links, backward, forward
from .progress import Progress, random_shape
from .reach import ReachTable
from .result import ReachResult


class Fabrik:
    """FABRIK solver for one chain (fixed base: joints before the chain keep their start values).

    Args:
        chain: the chain, from :meth:`PlanarChain.from_robot`.
        reach: the chain's reach table (default: sampled here, :meth:`ReachTable.from_chain`).
        window, restarts, seed: stall detection and restarts (:class:`~framework.solvers.fabrik.progress.Progress`); new
            arm shapes are drawn from ``numpy.random.default_rng(seed)``, so a solve is deterministic.
    """

    def __init__(self, chain: PlanarChain, *, window: int = 10, restarts: int = 10, seed: int = 0,
                 reach: ReachTable | None = None) -> None:
        self.chain = chain
        self.robot = chain.robot
        self.links = Links.of(chain)
        self.reach = ReachTable.from_chain(chain) if reach is None else reach
        self.window = window
        self.restarts = restarts
        self.seed = seed
        self._fk = PointKinematics(chain.robot, chain.frame)

    def solve(
        self, target: np.ndarray, x0: np.ndarray, *, tolerance: float = 1e-6, max_iterations: int = 1000,
        seed: int | None = None,
    ) -> ReachResult:
        """Reach ``target`` ``(3,)`` [m, world] from the start configuration ``x0`` ``(n,)``.

        Args:
            target: end-effector position in the world frame [m].
            x0: start configuration; joints outside the chain keep their values.
            tolerance: success threshold on the position error [m].
            max_iterations: cap on forward + backward iterations.
            seed: the restarts' chain shapes are drawn from ``default_rng(seed)`` (default: the solver's ``seed``).
        """
        start = time.perf_counter()
        target = check_target(target)
        x0 = self.robot.check_population(x0, "start configuration")[0]
        chain = self.chain
        local = self._fk.joint_placement(x0, chain.root).actInv(target)
        phi = self._choose_yaw(local, x0)
        q_yaw = chain.yaw_angle(phi) if chain.yaw is not None else None
        phi = chain.yaw_turn(q_yaw) if q_yaw is not None else 0.0
        tx, ty, off = chain.plane_target(local, phi)

        points = chain.points(x0[list(chain.planar)])
        xs, ys = points[:, 0].tolist(), points[:, 1].tolist()
        sx, sy = chain.shoulder
        progress = Progress(tolerance, max_iterations, self.window, self.restarts)
        progress.history.append(math.hypot(xs[-1] - tx, ys[-1] - ty, off))
        distance = math.hypot(tx - sx, ty - sy)
        if distance > chain.reach + tolerance:
            # FABRIK's reachability test: stretch the chain towards the target and stop.
            for i in range(1, len(xs)):
                xs[i], ys[i] = tx, ty
            backward(xs, ys, sx, sy, self.links)
            progress.history.append(math.hypot(xs[-1] - tx, ys[-1] - ty, off))
            decision = (
                f"unreachable: the target is {distance:.4g} m from the first planar joint, beyond the "
                f"chain's reach {chain.reach:.4g} m"
            )
        else:
            best, rng = (progress.history[0], xs.copy(), ys.copy()), None
            while (decision := progress.decide()) in ("continue", "restart", "resume"):
                if decision == "restart":
                    rng = rng or np.random.default_rng(self.seed if seed is None else seed)
                    xs, ys = random_shape(chain, rng)
                elif decision == "resume":
                    xs, ys = best[1].copy(), best[2].copy()
                forward(xs, ys, tx, ty, self.links)
                backward(xs, ys, sx, sy, self.links)
                progress.history.append(math.hypot(xs[-1] - tx, ys[-1] - ty, off))
                if progress.history[-1] < best[0]:
                    best = (progress.history[-1], xs.copy(), ys.copy())
            _, xs, ys = best

        q = chain.angles(np.column_stack([xs, ys]))
        x = chain.configuration(x0, q, q_yaw)
        error = float(np.linalg.norm(self._fk.position(x) - target))
        if decision == "converged" and error > tolerance:
            decision = "stalled"
        return ReachResult(
            configuration=x,
            position_error=error,
            iterations=progress.iterations,
            wall_time=time.perf_counter() - start,
            success=error <= tolerance,
            reason=decision,
            solver="fabrik",
            error_history=np.array(progress.history),
        )

    def _choose_yaw(self, local: np.ndarray, x0: np.ndarray) -> float:
        """The yaw turn for a target in the root frame: prefer a plane where the yaw is within limits and the
        target within the arm's reach, then the smaller turn from the start configuration."""
        chain = self.chain
        if chain.yaw is None:
            return 0.0
        current = chain.yaw_turn(float(x0[chain.yaw]))

        def score(phi: float) -> tuple[bool, bool, bool, float]:
            q = chain.yaw_reference + chain.yaw_sign * phi
            in_limits = abs(math.remainder(chain.yaw_angle(phi) - q, 2 * math.pi)) < 1e-12
            tx, ty, _ = chain.plane_target(local, phi)
            sx, sy = chain.shoulder
            return (
                not in_limits,
                math.hypot(tx - sx, ty - sy) > chain.reach,
                not self.reach.contains(tx, ty),
                abs(math.remainder(phi - current, 2 * math.pi)),
            )

        return min(chain.yaw_headings(local), key=score)


def check_target(target: np.ndarray) -> np.ndarray:
    """``target`` as a float ``(3,)`` position [m]; raises :class:`TaskError` unless it is 3 finite numbers."""
    target = np.asarray(target, dtype=float)
    if target.shape != (3,) or not np.isfinite(target).all():
        raise TaskError(f"a position target must be 3 finite numbers [m]; got {target!r}")
    return target
