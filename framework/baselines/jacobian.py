"""Jacobian pseudo-inverse IK: the conventional methods the papers compare against.

Closed-loop inverse kinematics on the position of one frame: at every iteration ``Δx = K J⁺ e`` with
``e = t − p(x)`` [m] and ``J`` the ``3 × n`` position Jacobian in joint coordinates (the residual and Jacobian
of a :class:`~framework.costs.Position` term from the compiled kernels, so a planar mobile base is handled like
any joint). ``J⁺`` is

- ``"pinv"``: the Moore-Penrose pseudo-inverse by SVD, singular values below ``rcond · σ_max`` dropped
  (paper 001's "conventional method" inverts this way; near a singularity ``1/σ`` explodes: the jump);
- ``"dls"``: damped least squares ``Jᵀ (J Jᵀ + λ² I)⁻¹`` (bounded steps, larger error near singularities).

Steps are clipped to the search box (the robot cannot leave its limits; the methods do not know them).
"""

from __future__ import annotations

import numpy as np

from ..costs import Position, Program
from ..engine import residuals
from ..errors import TaskError
from ..robot import Robot

METHODS = ("pinv", "dls")


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


def inverse(J: np.ndarray, method: str, *, rcond: float = 1e-6, damping: float = 0.05) -> np.ndarray:
    """``J⁺`` by ``"pinv"`` (:func:`svd_pinv`) or ``"dls"`` (:func:`dls_inverse`)."""
    if method == "pinv":
        return svd_pinv(J, rcond)
    if method == "dls":
        return dls_inverse(J, damping)
    raise TaskError(f"unknown Jacobian method {method!r}; use one of {METHODS}")


def position_and_jacobian(robot: Robot, x: np.ndarray, frame: str) -> tuple[np.ndarray, np.ndarray]:
    """World position ``(3,)`` [m] of ``frame`` and its position Jacobian ``(3, n)`` in joint coordinates."""
    key = ("position of", frame)
    # the residual p(x) − 0 of a position term is the position itself
    program = robot.memo(key, lambda: Program(robot, 1.0 * Position(frame, np.zeros(3))))
    return residuals(program, x)


def jacobian_ik(
    robot: Robot,
    frame: str,
    target: np.ndarray,
    x0: np.ndarray,
    *,
    method: str = "pinv",
    gain: float = 1.0,
    max_iterations: int = 100,
    tolerance: float = 1e-6,
    rcond: float = 1e-6,
    damping: float = 0.05,
) -> tuple[np.ndarray, float, int]:
    """Iterate ``x ← clip(x + gain J⁺ (t − p(x)))`` from ``x0`` until ``‖t − p‖ < tolerance`` [m].

    Returns ``(x (n,), final error [m], Jacobian evaluations)``.
    """
    x = np.array(x0, dtype=float)
    target = np.asarray(target, dtype=float)
    evaluations = 0
    for _ in range(max_iterations):
        p, J = position_and_jacobian(robot, x, frame)
        evaluations += 1
        e = target - p
        if np.linalg.norm(e) < tolerance:
            return x, float(np.linalg.norm(e)), evaluations
        x = np.clip(x + gain * inverse(J, method, rcond=rcond, damping=damping) @ e, robot.lower, robot.upper)
    p, _ = position_and_jacobian(robot, x, frame)
    return x, float(np.linalg.norm(target - p)), evaluations + 1
