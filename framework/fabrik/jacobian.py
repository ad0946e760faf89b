"""The Jacobian baselines of paper 003: pseudo-inverse and damped least squares, on the whole mobile manipulator.

The base is modelled as joints (``youbot_mobile``: prismatic ``base_x``, ``base_y``, revolute ``base_theta``), so
the robot is one serial chain and the Jacobian of the end-effector position is Pinocchio's
(``computeFrameJacobian(..., LOCAL_WORLD_ALIGNED)``, rows 0:3) times :meth:`Robot.coordinate_jacobian` (the
identity unless the robot has planar or continuous joints). One loop, two update rules (Buss 2004, "Introduction
to inverse kinematics with Jacobian transpose, pseudoinverse and damped least squares methods", whose
implementation Aristidou & Lasenby compared FABRIK with):

* pseudo-inverse: ``Δx = J⁺ e`` (singular values below ``rcond·σ_max`` dropped);
* damped least squares: ``Δx = Jᵀ (J Jᵀ + λ² I)⁻¹ e``.

As in Buss's code, the error fed to the update is clamped to ``max_error`` [m] and the step is scaled so no
coordinate moves more than ``max_step`` (rad, or m for prismatic joints). After each step, coordinates are
clipped to the search bounds, except those whose bounds span a full turn (``base_theta``), which are wrapped.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..baselines.jacobian import dls_inverse, svd_pinv
from ..robot import JointKind, Robot
from .fabrik import check_target
from .kinematics import PointKinematics
from .result import ReachResult

#: ``update(J, e, settings) -> Δx``: one step from the position Jacobian ``(3, n)`` and the error ``(3,)`` [m].
Update = Callable[[np.ndarray, np.ndarray, "JacobianSettings"], np.ndarray]


@dataclass(frozen=True)
class JacobianSettings:
    """Step settings (defaults: Buss's, with lengths in metres for a ~0.5 m arm).

    Attributes:
        damping: λ [m] of damped least squares.
        rcond: relative cut-off of small singular values for the pseudo-inverse.
        max_step: largest change of one coordinate per iteration (rad or m).
        max_error: the error vector is clamped to this length [m] before the update.
    """

    damping: float = 0.1
    rcond: float = 0.01
    max_step: float = math.radians(5.0)
    max_error: float = 0.1


def pseudo_inverse_step(J: np.ndarray, e: np.ndarray, settings: JacobianSettings) -> np.ndarray:
    """``J⁺ e`` with singular values below ``rcond·σ_max`` dropped."""
    return svd_pinv(J, settings.rcond) @ e


def damped_least_squares_step(J: np.ndarray, e: np.ndarray, settings: JacobianSettings) -> np.ndarray:
    """``Jᵀ (J Jᵀ + λ² I)⁻¹ e``."""
    return dls_inverse(J, settings.damping) @ e


class JacobianIK:
    """Iterative Jacobian IK of one frame's position over all of a robot's coordinates.

    Args:
        robot: the robot (for paper 003, ``youbot_mobile``: base joints included).
        update: the update rule, :func:`pseudo_inverse_step` or :func:`damped_least_squares_step`.
        frame: end-effector frame (default: the first end-effector).
        settings: step settings.
        name: solver name in results.
    """

    def __init__(
        self,
        robot: Robot,
        update: Update,
        *,
        frame: str | None = None,
        settings: JacobianSettings | None = None,
        name: str = "jacobian",
    ) -> None:
        self.robot = robot
        self.update = update
        self.settings = settings or JacobianSettings()
        self.name = name
        self.frame = robot.end_effectors[0] if frame is None else frame
        self._fk = PointKinematics(robot, self.frame)
        self._identity = all(j.kind in (JointKind.REVOLUTE, JointKind.PRISMATIC) for j in robot.joints)
        self._wrap = (robot.upper - robot.lower) >= 2 * math.pi - 1e-9
        self._base = robot.group("base") if "base" in robot.groups and len(robot.group("base")) == 3 else None

    def solve(
        self, target: np.ndarray, x0: np.ndarray, *, tolerance: float = 1e-6, max_iterations: int = 1000
    ) -> ReachResult:
        """Drive the frame to ``target`` ``(3,)`` [m] from ``x0`` ``(n,)``."""
        start = time.perf_counter()
        target = check_target(target)
        x = self.robot.check_population(x0, "start configuration")[0].copy()
        model, data, fid = self._fk.model, self._fk.data, self._fk.frame_id
        lower, upper, s = self.robot.lower, self.robot.upper, self.settings
        history: list[float] = []
        path = [x[self._base].copy()] if self._base is not None else []
        reason = "max_iterations"
        while True:
            J = pin.computeFrameJacobian(model, data, self._fk.q(x), fid, pin.LOCAL_WORLD_ALIGNED)[:3]
            e = target - data.oMf[fid].translation
            history.append(float(np.linalg.norm(e)))
            if history[-1] <= tolerance:
                reason = "converged"
                break
            if len(history) > max_iterations:
                break
            if not self._identity:
                J = J @ self.robot.coordinate_jacobian(x)
            if history[-1] > s.max_error:
                e *= s.max_error / history[-1]
            dx = self.update(J, e, s)
            biggest = float(np.abs(dx).max())
            if biggest > s.max_step:
                dx *= s.max_step / biggest
            x += dx
            x = np.where(self._wrap, lower + np.mod(x - lower, 2 * math.pi), np.clip(x, lower, upper))
            if self._base is not None:
                path.append(x[self._base].copy())
        error = float(np.linalg.norm(self._fk.position(x) - target))
        return ReachResult(
            configuration=x,
            position_error=error,
            iterations=len(history) - 1,
            wall_time=time.perf_counter() - start,
            success=error <= tolerance,
            reason=reason,
            solver=self.name,
            base_path=np.array(path) if path else np.zeros((0, 3)),
            error_history=np.array(history),
        )


def pseudo_inverse_ik(robot: Robot, **kwargs) -> JacobianIK:
    """The pseudo-inverse baseline (keyword arguments as :class:`JacobianIK`)."""
    return JacobianIK(robot, pseudo_inverse_step, name="pinv", **kwargs)


def damped_least_squares_ik(robot: Robot, **kwargs) -> JacobianIK:
    """The damped least-squares baseline (keyword arguments as :class:`JacobianIK`)."""
    return JacobianIK(robot, damped_least_squares_step, name="dls", **kwargs)
