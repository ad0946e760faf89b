"""Multi-start Levenberg-Marquardt on a whole population at once, for problems made of task terms only.

Every member of a population of starting configurations takes damped Gauss-Newton steps in lock-step, with
its own damping, from one call of the population Jacobian kernel per iteration; members that stall restart
from a random configuration. It stops as soon as one member reaches the tolerance. This is the vectorized
form of what TRAC-IK does with threads: many cheap local solves, the first success wins.

Residuals (shapes per member): position ``p − t`` (3,); relative position ``p_b − p_a − offset`` (3,);
orientation ``vec(E − I)`` with ``E = R_targetᵀ R`` (9,; norm ``2√2 sin(φ/2)``, zero only at φ = 0 — the
3-vector ``½ vee(E − Eᵀ) = sin φ · axis`` also vanishes at φ = π and traps many starts there).
Success is judged on the problem's own task error.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .costs import JointLimitPenalty, Orientation, Position, RelativePosition
from .errors import SolverError
from .problem import Problem

_HAT = np.array([[[0, 0, 0], [0, 0, -1], [0, 1, 0]], [[0, 0, 1], [0, 0, 0], [-1, 0, 0]], [[0, -1, 0], [1, 0, 0], [0, 0, 0]]], float)


@dataclass(frozen=True)
class MultistartResult:
    """Best member: configuration ``x`` ``(n,)``, its cost and task error; iterations, evaluations, restarts."""

    x: np.ndarray
    cost: float
    task_error: float
    iterations: int
    evaluations: int
    restarts: int


def _residuals(problem: Problem, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Stacked task residuals ``(pop, m)`` and their Jacobians ``(pop, m, n)``."""
    robot = problem.robot
    frames = problem.objective.frames
    poses, J = robot.frame_jacobians(X, frames)
    index = {f: k for k, f in enumerate(frames)}
    rs, js = [], []
    for weight, term in problem.objective:
        if isinstance(term, Position):
            k = index[term.frame]
            rs.append(poses.positions[:, k] - term.target)
            js.append(J[:, k, :3])
        elif isinstance(term, RelativePosition):
            a, b = index[term.frame_a], index[term.frame_b]
            rs.append(poses.positions[:, b] - poses.positions[:, a] - term.offset)
            js.append(J[:, b, :3] - J[:, a, :3])
        elif isinstance(term, Orientation):
            k = index[term.frame]
            E = term.target.T @ poses.rotations[:, k]  # (pop, 3, 3)
            rs.append((E - np.eye(3)).reshape(-1, 9))
            # dE = [v]x E with v = R_targetᵀ ω: column i of d vec(E) / dv is vec([e_i]x E)
            M = np.einsum("iab,pbc->piac", _HAT, E).reshape(-1, 3, 9).transpose(0, 2, 1)
            js.append(M @ (term.target.T @ J[:, k, 3:]))
        # JointLimitPenalty: zero inside the box, which the steps never leave.
    return np.concatenate(rs, axis=1), np.concatenate(js, axis=1)


def check_task_only(problem: Problem) -> None:
    for _, term in problem.objective:
        if not isinstance(term, (Position, RelativePosition, Orientation, JointLimitPenalty)):
            raise SolverError(
                f"multistart_lm solves problems of position/orientation/relative-position terms only; "
                f"{term.name!r} is a {type(term).__name__} (use the hybrid)"
            )


def multistart_lm(
    problem: Problem,
    rng: np.random.Generator,
    *,
    starts: int = 16,
    initial: np.ndarray | None = None,
    tolerance: float = 1e-6,
    max_iterations: int = 200,
    time_budget: float | None = None,
    stall: int = 8,
) -> MultistartResult:
    """Run population LM until a member's task error is within ``tolerance`` (or the budget runs out).

    Args:
        problem: task terms only (position, orientation, relative position; joint-limit penalty ignored).
        rng: restarts and the random part of the first population.
        starts: members stepped together.
        initial: ``(k, n)`` configurations seeding the first members (e.g. the middle of the limits).
        tolerance: success threshold on the problem's task error.
        max_iterations: iteration cap; ``time_budget``: seconds cap.
        stall: a member that gained less than 1 % in this many iterations restarts.
    """
    check_task_only(problem)
    start = time.perf_counter()
    robot = problem.robot
    lower, upper = robot.lower, robot.upper
    X = robot.random_configurations(rng, starts)
    if initial is not None:
        k = min(starts, len(initial))
        X[:k] = initial[:k]
    r, J = _residuals(problem, X)
    norm = np.linalg.norm(r, axis=1)
    damping = np.full(starts, 1e-3)
    checkpoint, since = norm.copy(), np.zeros(starts, int)
    eye = np.eye(robot.n)
    evaluations, restarts, iteration = starts, 0, 0
    best_x, best_error = X[np.argmin(norm)].copy(), np.inf
    for iteration in range(1, max_iterations + 1):
        JT = np.swapaxes(J, 1, 2)
        A = JT @ J + damping[:, None, None] * eye
        step = -np.linalg.solve(A, (JT @ r[:, :, None]))[:, :, 0]
        X_new = np.clip(X + step, lower, upper)
        r_new, J_new = _residuals(problem, X_new)
        evaluations += starts
        norm_new = np.linalg.norm(r_new, axis=1)
        better = norm_new < norm
        X[better], r[better], J[better], norm[better] = X_new[better], r_new[better], J_new[better], norm_new[better]
        damping = np.where(better, np.maximum(damping / 10, 1e-12), damping * 10)

        candidates = np.flatnonzero(norm < max(10 * tolerance, 1e-9))
        if candidates.size:
            errors = problem.evaluate(X[candidates]).task_error
            i = int(np.argmin(errors))
            if errors[i] < best_error:
                best_x, best_error = X[candidates[i]].copy(), float(errors[i])
            if best_error <= tolerance:
                break
        progressed = norm < 0.99 * checkpoint
        checkpoint = np.where(progressed, norm, checkpoint)
        since = np.where(progressed, 0, since + 1)
        stuck = (since >= stall) | (damping > 1e8)
        if stuck.any():
            count = int(stuck.sum())
            X[stuck] = robot.random_configurations(rng, count)
            r_s, J_s = _residuals(problem, X[stuck])
            r[stuck], J[stuck], norm[stuck] = r_s, J_s, np.linalg.norm(r_s, axis=1)
            damping[stuck], since[stuck], checkpoint[stuck] = 1e-3, 0, norm[stuck]
            evaluations += count
            restarts += count
        if time_budget is not None and time.perf_counter() - start > time_budget:
            break
    if not np.isfinite(best_error):
        best_x = X[np.argmin(norm)].copy()
    evaluation = problem.evaluate(best_x)
    return MultistartResult(
        best_x, float(evaluation.cost[0]), float(evaluation.task_error[0]), iteration, evaluations, restarts
    )
