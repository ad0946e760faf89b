"""Jacobian pseudo-inverse IK: the conventional methods the papers compare against.

Closed-loop inverse kinematics on the position of one frame: at every iteration ``Δx = K J⁺ e`` with
``e = t − p(x)`` [m] and ``J`` the ``3 × n`` position Jacobian in joint coordinates (the residual and Jacobian
of a :class:`~framework.costs.Position` term from the compiled kernels, so a planar mobile base is handled like
any joint). ``J⁺`` is

- ``"pinv"``: the Moore-Penrose pseudo-inverse by SVD, singular values below ``rcond · σ_max`` dropped
  (paper 001's "conventional method" inverts this way; near a singularity ``1/σ`` explodes: the jump);
- ``"dls"``: damped least squares ``Jᵀ (J Jᵀ + λ² I)⁻¹`` (bounded steps, larger error near singularities).

Steps are clipped to the search box (the robot cannot leave its limits; the methods do not know them). One loop,
:func:`jacobian_ik`, runs on the task terms of any problem's :class:`~framework.costs.Program`; the solvers
``"pinv"`` and ``"dls"`` (:mod:`~framework.solvers.baselines.solver`) put it behind :func:`framework.solve`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from ...costs import Position, Program
from ...engine import residual_arrays, residuals
from ...model.joints import JointKind
from ...model.robot import Robot

class JacobianRun(NamedTuple):
    """What :func:`jacobian_ik` returns.

    Attributes:
        x: the last configuration ``(n,)``; stop: ``"tolerance"``, ``"max_iterations"``, ``"time_budget"`` or
            ``"callback"``; steps: Jacobian steps taken; evaluations: residual and Jacobian evaluations
            (``steps + 1``: the last one found the task within tolerance or ended the run); history: ``‖e‖`` at
            each evaluation ``(evaluations,)``.
    """

    x: np.ndarray
    stop: str
    steps: int
    evaluations: int
    history: np.ndarray


def svd_pinv(J: np.ndarray, rcond: float = 1e-6) -> np.ndarray:
    """Moore-Penrose pseudo-inverse ``(n, m)`` of ``J`` ``(m, n)`` by SVD; ``σ < rcond · σ_max`` are dropped."""
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    keep = s > rcond * (s[0] if s.size else 0.0)
    inverse = np.zeros_like(s)
    inverse[keep] = 1.0 / s[keep]
    return (Vt.T * inverse) @ U.T


def dls_inverse(J: np.ndarray, damping: float = 0.05) -> np.ndarray:
    """Damped least-squares inverse ``Jᵀ (J Jᵀ + λ² I)⁻¹`` ``(n, m)``; ``λ`` = ``damping`` [m/rad]."""
    m = J.shape[0]
    return J.T @ np.linalg.solve(J @ J.T + damping**2 * np.eye(m), np.eye(m))


def position_and_jacobian(robot: Robot, x: np.ndarray, frame: str) -> tuple[np.ndarray, np.ndarray]:
    """World position ``(3,)`` [m] of ``frame`` and its position Jacobian ``(3, n)`` in joint coordinates."""
    return residuals(robot.derived(_position_program, frame), x)


def _position_program(robot: Robot, frame: str) -> Program:
    """The program of a position term at the origin: its residual p(x) − 0 is the frame's position itself."""
    return Program(robot, 1.0 * Position(frame, np.zeros(3)))


def full_turns(program: Program) -> np.ndarray:
    """``(n,)`` True for the angles the baselines wrap: those the engine wraps (continuous joints, a planar
    base's heading) and revolute joints whose limits span a full turn (``youbot_mobile``'s ``base_theta``, ±π:
    paper 003's baselines turn the base through ±π)."""
    robot = program.robot
    full = robot.upper - robot.lower >= 2 * np.pi - 1e-9
    revolute = np.zeros(robot.n, dtype=bool)
    for joint in robot.joints:
        if joint.kind is JointKind.REVOLUTE:
            revolute[joint.index] = True
    return program.layout.box_wrap | (revolute & full)


def jacobian_ik(
    program: Program,
    x0: np.ndarray,
    inverse_of: Callable[[np.ndarray], np.ndarray],
    *,
    gain: float = 1.0,
    max_step: float | None = None,
    max_error: float | None = None,
    tolerance: float = 1e-6,
    angle_tolerance: float | None = None,
    max_iterations: int = 100,
    deadline: float | None = None,
    callback: Callable[[int, float, np.ndarray], bool | None] | None = None,
) -> JacobianRun:
    """Closed-loop IK on the task terms of ``program``: ``x ← box(x + gain J⁺ e)`` from ``x0`` ``(n,)``.

    ``e = −r`` is the stacked task residual (``t − p(x)`` for a position [m]), ``J`` its Jacobian ``(m, n)`` in
    joint coordinates (the compiled kernels: planar bases and continuous joints included), ``J⁺ =
    inverse_of(J)``. Optionally, as in Buss's code, ``e`` is clamped to the length ``max_error`` and the step
    scaled so that no coordinate moves more than ``max_step`` [rad or m]. ``box`` wraps the angles whose range
    is a full turn (:func:`full_turns`) and clips the others to the limits (the methods do not know them). Stops
    when every task block is within ``tolerance`` [m] / ``angle_tolerance`` [rad], after ``max_iterations``
    steps, at ``deadline`` (``time.monotonic()``) or when ``callback(step, ‖e‖, x)`` returns True.
    """
    lower, upper, wrap = program.robot.lower, program.robot.upper, full_turns(program)
    wraps = bool(wrap.any())
    angle_tolerance = tolerance if angle_tolerance is None else angle_tolerance
    ends = np.cumsum(program.task_block_rows).tolist()
    blocks = list(zip([0, *ends[:-1]], ends))
    out = residual_arrays(program)
    x = np.array(x0, dtype=float)
    history: list[float] = []
    steps, stop = 0, "max_iterations"
    while True:
        r, J = residuals(program, x, out=out)
        history.append(math.sqrt(float(r @ r)))
        errors = [history[-1]] if len(blocks) == 1 else [math.sqrt(float(r[a:b] @ r[a:b])) for a, b in blocks]
        if program.within(errors, tolerance, angle_tolerance):
            stop = "tolerance"
            break
        if steps >= max_iterations:
            break
        if deadline is not None and time.monotonic() >= deadline:
            stop = "time_budget"
            break
        e = -r
        if max_error is not None and history[-1] > max_error:
            e *= max_error / history[-1]
        dx = gain * (inverse_of(J) @ e)
        biggest = float(np.abs(dx).max())
        if max_step is not None and biggest > max_step:
            dx *= max_step / biggest
        x = x + dx
        if wraps:
            x = np.where(wrap, lower + np.mod(x - lower, 2 * np.pi), np.clip(x, lower, upper))
        else:
            np.clip(x, lower, upper, out=x)
        steps += 1
        if callback is not None and callback(steps, history[-1], x.copy()):
            stop = "callback"
            break
    return JacobianRun(x, stop, steps, len(history), np.array(history))
