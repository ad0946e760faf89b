"""Warm starts along a path: the Jacobian predictor, the first waypoint's task-shaped covariance, a continued
search distribution."""


from __future__ import annotations

import numpy as np

from ..engine import LocalSettings, residuals, solve_local
from ..costs.problem import Problem
from .task import TASK_SPACE_RATIO


# ---------------------------------------------------------------------------------------------- predictor
def task_covariance(problem: Problem, x: np.ndarray, *, ratio: float = TASK_SPACE_RATIO) -> np.ndarray | None:
    """``(n, n)`` covariance for a search from ``x`` on the task: identity on the null space of the stacked task
    Jacobian, ``ratio`` on its row space (moves that leave the task are ``1/√ratio`` times narrower).

    ``None`` when ``x`` is not on the task (task error above 1e-9) or there is no task term.
    """
    if not problem.program.task_rows or problem.evaluate(x).task_error[0] > 1e-9:
        return None
    _, J = residuals(problem.program, x)
    row = np.linalg.pinv(J, rcond=1e-10) @ J  # projector onto the row space
    row = 0.5 * (row + row.T)
    return np.eye(problem.robot.n) - (1.0 - ratio) * row


#: The predictor: a few Levenberg-Marquardt steps of the local engine, no restart, no regularization.
PREDICTOR = LocalSettings(tolerance=1e-12, max_iterations=5, restarts=False, regularize=False, polish=0)


def predictor(problem: Problem, x: np.ndarray) -> np.ndarray:
    """``x`` moved onto the task by a few Levenberg-Marquardt steps of the local engine (the tracking predictor);
    ``x`` itself when the problem has no task term."""
    if not problem.program.task_rows:
        return np.array(x, dtype=float)
    return solve_local(problem.program, x, 0, PREDICTOR).x.copy()


